// Synthetic BODY_25 detections: exact projection without noise, noise and dropout
// statistics, the occlusion rule against a rendered depth image, unmapped and
// out-of-frame keypoints, determinism and the OpenPose JSON files; the openpose error
// model (error in proportion to the person's size, left/right swaps, dropouts under
// occlusion, confidence that falls with the error) and its config keys.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

#include "capture/render/renderer.h"
#include "capture/studio/studio_rig.h"
#include "capture/studio/synthetic_keypoints.h"
#include "capture/studio/synthetic_studio.h"
#include "tests/capture/box_mesh.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::box_mesh;
using weft::capture::testing::expect_error;
using weft::capture::testing::repo_file;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// A stick figure standing on the floor (metres, facing +z): keypoint k at a height
// spread over the body, left/right spread in x; two keypoints unmapped (NaN).
Vertices stick_figure() {
  Vertices p(kBody25Count, 3);
  for (int k = 0; k < kBody25Count; ++k)
    p.row(k) << 0.3 * std::sin(1.7 * k), 0.05 + 1.55 * k / 24.0, 0.05 * std::cos(k);
  p.row(17).setConstant(kNaN);  // REar
  p.row(18).setConstant(kNaN);  // LEar
  return p;
}

Camera front_camera(double metres_per_unit = 1.0) {
  StudioRigConfig cfg;
  cfg.metres_per_unit = metres_per_unit;
  return studio_rig(cfg)[0];  // azimuth 0: in front (+z)
}

KeypointNoiseConfig exact() {
  KeypointNoiseConfig c;
  c.noise_px = 0;
  c.dropout = 0;
  c.occluded_dropout = 0;
  c.confidence_jitter = 0;
  return c;
}

// The openpose model with nothing random but the position error (and its confidence).
KeypointNoiseConfig detector(double multiple) {
  KeypointNoiseConfig c = KeypointNoiseConfig::openpose();
  c.scale_error_multiple = multiple;
  c.dropout = 0;
  c.occluded_dropout = 0;
  c.swap_probability = 0;
  c.swap_probability_side = 0;
  c.confidence_jitter = 0;
  return c;
}

// The same camera with focal lengths, principal point and image size doubled: every
// keypoint lands at exactly twice its pixel coordinates, the person twice as big.
Camera zoomed(const Camera& cam) {
  Camera z = cam;
  z.K.topRows<2>() *= 2.0;
  z.width *= 2;
  z.height *= 2;
  return z;
}

// Spearman's rank correlation (no ties expected in continuous data).
double rank_correlation(const std::vector<double>& a, const std::vector<double>& b) {
  auto ranks = [](const std::vector<double>& v) {
    std::vector<int> order(v.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(), [&](int i, int j) { return v[i] < v[j]; });
    std::vector<double> r(v.size());
    for (size_t i = 0; i < order.size(); ++i) r[order[i]] = double(i);
    return r;
  };
  const std::vector<double> ra = ranks(a), rb = ranks(b);
  const double mean = (a.size() - 1) / 2.0;
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sab += (ra[i] - mean) * (rb[i] - mean);
    saa += (ra[i] - mean) * (ra[i] - mean);
    sbb += (rb[i] - mean) * (rb[i] - mean);
  }
  return sab / std::sqrt(saa * sbb);
}

std::string synth_config(const std::string& keypoints) {
  return "name: t\n"
         "character: " + repo_file("configs/characters/makehuman_skirt_coarse.yaml") + "\n" +
         "motion:\n"
         "  procedural: " + repo_file("configs/motions/walk_in_place.yaml") + "\n" +
         "  mapping: " + repo_file("configs/retarget/humanoid_to_makehuman.yaml") + "\n" + keypoints;
}

RenderMesh draw(const TriangleMesh& mesh) {
  RenderMesh m;
  m.mesh = &mesh;
  return m;
}

}  // namespace

TEST(SyntheticKeypoints, WithoutNoiseTheyAreTheCameraProjection) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  KeypointNoiseConfig cfg = exact();
  const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), cfg, 42);
  const Body25 clean = project_keypoints(cam, world);
  for (int i = 0; i < kBody25Count; ++i) {
    if (i == 17 || i == 18) continue;
    const Eigen::Vector2d uv = cam.project(world.row(i).transpose());
    EXPECT_NEAR(k(i, 0), uv.x(), 1e-9) << i;
    EXPECT_NEAR(k(i, 1), uv.y(), 1e-9) << i;
    EXPECT_DOUBLE_EQ(k(i, 2), cfg.visible_confidence) << i;
    EXPECT_NEAR(clean(i, 0), uv.x(), 1e-9) << i;
    EXPECT_NEAR(clean(i, 1), uv.y(), 1e-9) << i;
    EXPECT_EQ(clean(i, 2), 1.0) << i;
  }
  // Unmapped keypoints are undetected in both.
  for (int i : {17, 18}) {
    EXPECT_EQ(k.row(i), Eigen::RowVector3d::Zero()) << i;
    EXPECT_EQ(clean.row(i), Eigen::RowVector3d::Zero()) << i;
  }
}

TEST(SyntheticKeypoints, NoiseHasTheConfiguredStandardDeviation) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  const Body25 clean = project_keypoints(cam, world);
  KeypointNoiseConfig cfg = exact();
  cfg.noise_px = 2.0;
  double sum[2] = {0, 0}, sum2[2] = {0, 0};
  int n = 0;
  for (uint64_t seed = 0; seed < 2000; ++seed) {
    const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), cfg, mix_seed(99, seed, 0));
    for (int i = 0; i < kBody25Count; ++i) {
      if (clean(i, 2) == 0) continue;
      ASSERT_GT(k(i, 2), 0);
      for (int a = 0; a < 2; ++a) {
        const double e = k(i, a) - clean(i, a);
        sum[a] += e;
        sum2[a] += e * e;
      }
      ++n;
    }
  }
  for (int a = 0; a < 2; ++a) {
    const double mean = sum[a] / n, std = std::sqrt(sum2[a] / n - mean * mean);
    EXPECT_NEAR(std, cfg.noise_px, 0.1 * cfg.noise_px) << "axis " << a;
    EXPECT_LT(std::abs(mean), 4 * cfg.noise_px / std::sqrt(double(n))) << "axis " << a;  // unbiased
  }
  // The x and y noise are not the same draw.
  const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), cfg, 5);
  EXPECT_NE(k(0, 0) - clean(0, 0), k(0, 1) - clean(0, 1));
}

TEST(SyntheticKeypoints, DropoutFractionMatchesTheConfiguredProbability) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  for (double p : {0.05, 0.3}) {
    KeypointNoiseConfig cfg = exact();
    cfg.dropout = p;
    int dropped = 0, trials = 0;
    for (uint64_t seed = 0; seed < 400; ++seed) {
      const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), cfg, mix_seed(7, seed, 1));
      for (int i = 0; i < kBody25Count; ++i) {
        if (i == 17 || i == 18) continue;
        ++trials;
        if (k(i, 2) == 0) {
          ++dropped;
          EXPECT_EQ(k.row(i), Eigen::RowVector3d::Zero());
        }
      }
    }
    const double fraction = double(dropped) / trials;
    const double sigma = std::sqrt(p * (1 - p) / trials);  // binomial
    EXPECT_NEAR(fraction, p, 4 * sigma) << "dropout " << p << ", " << trials << " trials";
  }
}

// A torso-sized box (x ±0.2, y 0.8…1.4, z ±0.1 m) rendered into the camera in front and
// the one behind; a joint inside it, one behind it, one beside it.
TEST(SyntheticKeypoints, JointBehindTheTorsoIsOccludedJointFacingTheCameraIsVisible) {
  for (double unit_m : {1.0, 0.001}) {  // metres, then millimetres (ddc)
    const double u = 1.0 / unit_m;
    StudioRigConfig rig;
    rig.metres_per_unit = unit_m;
    const std::vector<Camera> cams = studio_rig(rig);
    const Camera& front = cams[0];  // azimuth 0, at +z
    const Camera& back = cams[4];   // azimuth 180, at −z
    const TriangleMesh torso = box_mesh(Eigen::Vector3d(-0.2, 0.8, -0.1) * u, Eigen::Vector3d(0.2, 1.4, 0.1) * u);
    Vertices world = Vertices::Constant(kBody25Count, 3, kNaN);
    const int inside = 1, behind = 8, beside = 4;
    world.row(inside) << 0, 1.1 * u, 0.0;         // a joint 0.1 m under the front surface
    world.row(behind) << 0.05 * u, 1.0 * u, -0.25 * u;  // 0.35 m behind the front surface
    world.row(beside) << 0.5 * u, 1.0 * u, -0.25 * u;   // nothing in front of it
    KeypointNoiseConfig cfg;
    cfg.metres_per_unit = unit_m;
    cfg.noise_px = 0;
    cfg.dropout = 0;
    cfg.occluded_dropout = 0;

    const cv::Mat front_depth = render(front, {draw(torso)}).depth;
    const auto seen = keypoint_visibility(front, world, front_depth, cfg);
    EXPECT_EQ(seen[inside], KeypointVisibility::visible) << unit_m;
    EXPECT_EQ(seen[behind], KeypointVisibility::occluded) << unit_m;
    EXPECT_EQ(seen[beside], KeypointVisibility::visible) << unit_m;
    EXPECT_EQ(seen[0], KeypointVisibility::unmapped);
    const Body25 k = synthesize_keypoints(front, world, front_depth, cfg, 11);
    EXPECT_NEAR(k(inside, 2), cfg.visible_confidence, cfg.confidence_jitter + 1e-12);
    EXPECT_NEAR(k(behind, 2), cfg.occluded_confidence, cfg.confidence_jitter + 1e-12);
    EXPECT_NEAR(k(beside, 2), cfg.visible_confidence, cfg.confidence_jitter + 1e-12);
    // Occluded keypoints keep their position: lower confidence, not dropped.
    const Body25 clean = project_keypoints(front, world);
    EXPECT_NEAR(k(behind, 0), clean(behind, 0), 1e-9);
    EXPECT_NEAR(k(behind, 1), clean(behind, 1), 1e-9);

    // From behind, the joint behind the torso faces the camera; the one inside it is 0.1 m
    // under the back surface, within the tolerance.
    const cv::Mat back_depth = render(back, {draw(torso)}).depth;
    const auto from_back = keypoint_visibility(back, world, back_depth, cfg);
    EXPECT_EQ(from_back[inside], KeypointVisibility::visible) << unit_m;
    EXPECT_EQ(from_back[behind], KeypointVisibility::visible) << unit_m;

    // A tighter tolerance hides the joint inside the box as well.
    cfg.depth_tolerance_m = 0.05;
    EXPECT_EQ(keypoint_visibility(front, world, front_depth, cfg)[inside], KeypointVisibility::occluded) << unit_m;

    // Separate dropout rates: visible keypoints always dropped, occluded ones never.
    cfg.depth_tolerance_m = KeypointNoiseConfig{}.depth_tolerance_m;
    cfg.dropout = 1;
    const Body25 only_occluded = synthesize_keypoints(front, world, front_depth, cfg, 3);
    EXPECT_EQ(only_occluded(inside, 2), 0);
    EXPECT_EQ(only_occluded(beside, 2), 0);
    EXPECT_GT(only_occluded(behind, 2), 0);
  }
}

TEST(SyntheticKeypoints, OutsideTheImageOrBehindTheCameraIsUndetected) {
  const Camera cam = front_camera();
  Vertices world = stick_figure();
  world.row(0) << 5, 1, 0;   // far to the side: outside the image
  world.row(1) << 0, 1, 4;   // behind the camera (it stands at z = 3)
  world.row(2) = (cam.center() + cam.R.row(0).transpose()).transpose();  // in the camera's plane (depth 0)
  const Body25 clean = project_keypoints(cam, world);
  const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), KeypointNoiseConfig{}, 1);
  const auto seen = keypoint_visibility(cam, world, cv::Mat(), KeypointNoiseConfig{});
  for (int i : {0, 1, 2}) {
    EXPECT_EQ(clean.row(i), Eigen::RowVector3d::Zero()) << i;
    EXPECT_EQ(k.row(i), Eigen::RowVector3d::Zero()) << i;
    EXPECT_EQ(seen[i], KeypointVisibility::outside) << i;
  }
  // A keypoint on the image border whose noise pushes it out is not reported either.
  Vertices edge = Vertices::Constant(kBody25Count, 3, kNaN);
  KeypointNoiseConfig cfg = exact();
  cfg.noise_px = 3;
  int reported_outside = 0, reported = 0;
  for (uint64_t seed = 0; seed < 200; ++seed) {
    // Back-project the left border pixel column at mid height to depth 3 m.
    const Eigen::Vector3d ray = cam.K.inverse() * Eigen::Vector3d(0.0, cam.height / 2.0, 1.0);
    edge.row(3) = (cam.R.transpose() * (3.0 * ray - cam.t)).transpose();
    const Body25 b = synthesize_keypoints(cam, edge, cv::Mat(), cfg, seed);
    if (b(3, 2) > 0) ++reported;
    if (b(3, 2) > 0 && b(3, 0) < -0.5) ++reported_outside;
  }
  EXPECT_EQ(reported_outside, 0);
  EXPECT_GT(reported, 50);  // the ones that stay in the image are reported
}

TEST(SyntheticKeypoints, DeterministicPerSeed) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  const KeypointNoiseConfig cfg;
  const Body25 a = synthesize_keypoints(cam, world, cv::Mat(), cfg, mix_seed(1, 2, 3));
  const Body25 b = synthesize_keypoints(cam, world, cv::Mat(), cfg, mix_seed(1, 2, 3));
  const Body25 c = synthesize_keypoints(cam, world, cv::Mat(), cfg, mix_seed(1, 3, 2));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_NE(mix_seed(1, 2, 3), mix_seed(1, 3, 2));
  EXPECT_NE(mix_seed(0, 0, 0), mix_seed(0, 0, 1));
  // One keypoint leaving the frame does not change another keypoint's noise.
  Vertices moved = world;
  moved.row(0) << 50, 1, 0;
  const Body25 d = synthesize_keypoints(cam, moved, cv::Mat(), cfg, mix_seed(1, 2, 3));
  EXPECT_EQ(d.row(5), a.row(5));
}

TEST(SyntheticKeypoints, RoundTripThroughOpenPoseJson) {
  ScratchDir dir("keypoints");
  const Camera cam = front_camera();
  OpenPoseFrame frame;
  frame.people.push_back(synthesize_keypoints(cam, stick_figure(), cv::Mat(), KeypointNoiseConfig{}, 17));
  write_openpose_json(dir.file("cam00_000000_keypoints.json"), frame);
  const OpenPoseFrame back = read_openpose_json(dir.file("cam00_000000_keypoints.json"));
  ASSERT_EQ(back.people.size(), 1u);
  EXPECT_LT((back.people[0] - frame.people[0]).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(back.people[0].row(17), Eigen::RowVector3d::Zero());
}

TEST(SyntheticKeypoints, InvalidInputsAreNamed) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  KeypointNoiseConfig cfg;
  cfg.dropout = 1.5;
  expect_error([&] { synthesize_keypoints(cam, world, cv::Mat(), cfg, 1); }, {"dropout"});
  cfg = {};
  cfg.visible_confidence = 0;
  expect_error([&] { synthesize_keypoints(cam, world, cv::Mat(), cfg, 1); }, {"visible_confidence"});
  expect_error([&] { synthesize_keypoints(cam, world, cv::Mat(10, 10, CV_32FC1, 0.f), {}, 1); },
               {"cam00", "depth image of 512x512"});
  expect_error([&] { project_keypoints(cam, Vertices::Zero(3, 3)); }, {"25×3"});
}

// ---- The openpose error model ----

TEST(SyntheticKeypoints, DetectorErrorSpreadScalesWithThePersonsSizeInTheImage) {
  // One camera, one image size; the same figure at half its size (about the point the
  // camera looks at) is about half as big in the image.
  const Camera cam = front_camera();
  const Vertices big = stick_figure();
  const Eigen::RowVector3d target(0, 0.9, 0);
  const Vertices small = ((big.rowwise() - target) * 0.5).rowwise() + target;
  const double s_big = person_scale_px(cam, big, cv::Mat()), s_small = person_scale_px(cam, small, cv::Mat());
  ASSERT_GT(s_small, 50);
  EXPECT_NEAR(s_big / s_small, 2.0, 0.1);
  const KeypointNoiseConfig cfg = detector(1.5);
  const Body25 clean_big = project_keypoints(cam, big), clean_small = project_keypoints(cam, small);
  for (int k : {0, 4, 9, 14}) {  // Nose, RWrist, RHip, LAnkle: σ .026, .062, .107, .089
    double sum2[2] = {0, 0};
    int n = 0;
    for (uint64_t seed = 0; seed < 3000; ++seed) {
      const uint64_t s = mix_seed(5, seed, 2);
      const Body25 a = synthesize_keypoints(cam, big, cv::Mat(), cfg, s);
      const Body25 b = synthesize_keypoints(cam, small, cv::Mat(), cfg, s);
      if (a(k, 2) == 0 || b(k, 2) == 0) continue;
      for (int axis = 0; axis < 2; ++axis) {
        sum2[0] += std::pow(a(k, axis) - clean_big(k, axis), 2);
        sum2[1] += std::pow(b(k, axis) - clean_small(k, axis), 2);
      }
      n += 2;
    }
    ASSERT_GT(n, 5000);
    const double std_big = std::sqrt(sum2[0] / n), std_small = std::sqrt(sum2[1] / n);
    const double expected = 1.5 * kBody25CocoSigma[k] * s_big / std::sqrt(2.0);  // per axis
    EXPECT_NEAR(std_big, expected, 0.05 * expected) << kBody25Names[k];
    EXPECT_NEAR(std_big / std_small, s_big / s_small, 0.02 * s_big / s_small) << kBody25Names[k];
  }
  // A hip's error is larger than the nose's: COCO's spread, not one σ for all.
  EXPECT_GT(kBody25CocoSigma[9], 4 * kBody25CocoSigma[0]);
  // No noise at all with a multiple of 0.
  const Body25 exact_kp = synthesize_keypoints(cam, big, cv::Mat(), detector(0), 3);
  for (int k = 0; k < kBody25Count; ++k)
    if (clean_big(k, 2) > 0) EXPECT_EQ(exact_kp.row(k).head<2>(), clean_big.row(k).head<2>()) << k;

  // With a depth image the scale is COCO's √(segment area): the person's pixels.
  const TriangleMesh torso = box_mesh(Eigen::Vector3d(-0.2, 0.6, -0.1), Eigen::Vector3d(0.2, 1.2, 0.1));
  const TriangleMesh half = box_mesh(Eigen::Vector3d(-0.1, 0.75, -0.05), Eigen::Vector3d(0.1, 1.05, 0.05));
  const cv::Mat depth_big = render(cam, {draw(torso)}).depth, depth_half = render(cam, {draw(half)}).depth;
  const double m_big = person_scale_px(cam, big, depth_big), m_half = person_scale_px(cam, big, depth_half);
  EXPECT_EQ(m_big, std::sqrt(double(cv::countNonZero(depth_big))));
  EXPECT_GT(m_half, 30);
  EXPECT_NEAR(m_big / m_half, 2.0, 0.1);
}

TEST(SyntheticKeypoints, DetectorSwapsLeftAndRightAtTheConfiguredRate) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  const Body25 clean = project_keypoints(cam, world);
  KeypointNoiseConfig cfg = detector(0);  // exact positions: a swap is visible as such
  cfg.swap_probability = cfg.swap_probability_side = 0.2;
  int swapped = 0, trials = 0;
  for (uint64_t seed = 0; seed < 1000; ++seed) {
    const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), cfg, mix_seed(8, seed, 0));
    for (const auto& [right, left] : kBody25LeftRightPairs) {
      if (right == 17) continue;  // the ears are unmapped in the stick figure
      ++trials;
      const bool same = k.row(right).head<2>() == clean.row(right).head<2>() &&
                        k.row(left).head<2>() == clean.row(left).head<2>();
      const bool exchanged = k.row(right).head<2>() == clean.row(left).head<2>() &&
                             k.row(left).head<2>() == clean.row(right).head<2>();
      ASSERT_TRUE(same || exchanged) << kBody25Names[right] << ", seed " << seed;
      if (exchanged) {
        ++swapped;
        EXPECT_DOUBLE_EQ(k(right, 2), cfg.visible_confidence * cfg.swap_confidence_scale);
      } else {
        EXPECT_DOUBLE_EQ(k(right, 2), cfg.visible_confidence);
      }
    }
  }
  const double p = 0.2, fraction = double(swapped) / trials;
  EXPECT_NEAR(fraction, p, 4 * std::sqrt(p * (1 - p) / trials)) << trials << " pairs";

  // Seen edge on (the pair along the camera's axis) a pair swaps at swap_probability_side,
  // face on at swap_probability.
  Vertices posed = world;
  const Eigen::RowVector3d ray = (posed.row(2) - cam.center().transpose()).normalized();
  posed.row(5) = posed.row(2) + 0.35 * ray;                       // shoulders: one behind the other
  posed.row(12) = posed.row(9) + Eigen::RowVector3d(0.25, 0, 0);  // hips: side by side
  cfg.swap_probability = 0.02;
  cfg.swap_probability_side = 0.3;
  const Body25 posed_clean = project_keypoints(cam, posed);
  int shoulders = 0, hips = 0;
  const int n = 2000;
  for (uint64_t seed = 0; seed < n; ++seed) {
    const Body25 k = synthesize_keypoints(cam, posed, cv::Mat(), cfg, mix_seed(9, seed, 0));
    if (k(2, 2) < cfg.visible_confidence) ++shoulders;  // both project to one pixel: the confidence tells
    if (k.row(9).head<2>() == posed_clean.row(12).head<2>()) ++hips;
  }
  EXPECT_NEAR(double(shoulders) / n, 0.3, 4 * std::sqrt(0.3 * 0.7 / n));
  EXPECT_NEAR(double(hips) / n, 0.02, 4 * std::sqrt(0.02 * 0.98 / n));
}

TEST(SyntheticKeypoints, DetectorConfidenceFallsWithTheError) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  const Body25 clean = project_keypoints(cam, world);
  const double s = person_scale_px(cam, world, cv::Mat());
  KeypointNoiseConfig cfg = detector(1.5);
  cfg.confidence_jitter = 0.05;  // the confidence is not a function of the error alone
  std::vector<double> error_sigmas, confidence;
  for (uint64_t seed = 0; seed < 300; ++seed) {
    const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), cfg, mix_seed(4, seed, 4));
    for (int i = 0; i < kBody25Count; ++i) {
      if (k(i, 2) == 0) continue;
      const double sigma = 1.5 * kBody25CocoSigma[i] * s / std::sqrt(2.0);
      error_sigmas.push_back((k.row(i).head<2>() - clean.row(i).head<2>()).norm() / sigma);
      confidence.push_back(k(i, 2));
    }
  }
  ASSERT_GT(error_sigmas.size(), 5000u);
  EXPECT_LT(rank_correlation(error_sigmas, confidence), -0.7);
  // Small errors report about the base confidence, errors of 3σ and more a low one.
  double small = 0, large = 0;
  int n_small = 0, n_large = 0;
  for (size_t i = 0; i < error_sigmas.size(); ++i) {
    if (error_sigmas[i] < 0.5) small += confidence[i], ++n_small;
    if (error_sigmas[i] > 3.0) large += confidence[i], ++n_large;
  }
  ASSERT_GT(n_large, 20);
  EXPECT_GT(small / n_small, 0.85);
  EXPECT_LT(large / n_large, 0.4);

  // The old model's confidence does not track its noise.
  KeypointNoiseConfig old = exact();
  old.noise_px = 3;
  old.confidence_jitter = 0.05;
  std::vector<double> old_error, old_confidence;
  for (uint64_t seed = 0; seed < 300; ++seed) {
    const Body25 k = synthesize_keypoints(cam, world, cv::Mat(), old, mix_seed(4, seed, 4));
    for (int i = 0; i < kBody25Count; ++i)
      if (k(i, 2) > 0) {
        old_error.push_back((k.row(i).head<2>() - clean.row(i).head<2>()).norm());
        old_confidence.push_back(k(i, 2));
      }
  }
  EXPECT_GT(rank_correlation(old_error, old_confidence), -0.1);
}

TEST(SyntheticKeypoints, DetectorDropsOccludedJointsAtTheirRate) {
  const Camera front = front_camera();
  const TriangleMesh torso = box_mesh(Eigen::Vector3d(-0.2, 0.8, -0.1), Eigen::Vector3d(0.2, 1.4, 0.1));
  const cv::Mat depth = render(front, {draw(torso)}).depth;
  Vertices world = Vertices::Constant(kBody25Count, 3, kNaN);
  const int inside = 1, behind = 8, beside = 0;  // Neck, MidHip, Nose: no left/right pair
  world.row(inside) << 0, 1.1, 0.0;
  world.row(behind) << 0.05, 1.0, -0.25;
  world.row(beside) << 0.5, 1.0, -0.25;
  KeypointNoiseConfig cfg = KeypointNoiseConfig::openpose();
  EXPECT_GT(cfg.occluded_dropout, cfg.dropout);  // the defaults drop hidden joints more often
  cfg.dropout = 0.05;
  cfg.occluded_dropout = 0.4;
  const auto seen = keypoint_visibility(front, world, depth, cfg);
  ASSERT_EQ(seen[behind], KeypointVisibility::occluded);
  ASSERT_EQ(seen[inside], KeypointVisibility::visible);
  ASSERT_EQ(seen[beside], KeypointVisibility::visible);
  const int n = 2000;
  int occluded_dropped = 0, visible_dropped = 0;
  double occluded_confidence = 0, visible_confidence = 0;
  for (uint64_t seed = 0; seed < n; ++seed) {
    const Body25 k = synthesize_keypoints(front, world, depth, cfg, mix_seed(6, seed, 0));
    if (k(behind, 2) == 0) ++occluded_dropped;
    else occluded_confidence += k(behind, 2);
    for (int i : {inside, beside}) {
      if (k(i, 2) == 0) ++visible_dropped;
      else visible_confidence += k(i, 2);
    }
  }
  EXPECT_NEAR(double(occluded_dropped) / n, 0.4, 4 * std::sqrt(0.4 * 0.6 / n));
  EXPECT_NEAR(double(visible_dropped) / (2 * n), 0.05, 4 * std::sqrt(0.05 * 0.95 / (2 * n)));
  // Those reported keep the lower confidence of a hidden joint.
  EXPECT_LT(occluded_confidence / (n - occluded_dropped), 0.5 * visible_confidence / (2 * n - visible_dropped));
}

TEST(SyntheticKeypoints, DetectorIsDeterministicAndLeavesTheGaussianModelAlone) {
  const Camera cam = front_camera();
  const Vertices world = stick_figure();
  const KeypointNoiseConfig cfg = KeypointNoiseConfig::openpose();
  EXPECT_EQ(synthesize_keypoints(cam, world, cv::Mat(), cfg, 77), synthesize_keypoints(cam, world, cv::Mat(), cfg, 77));
  EXPECT_NE(synthesize_keypoints(cam, world, cv::Mat(), cfg, 77), synthesize_keypoints(cam, world, cv::Mat(), cfg, 78));
  // The default model is still the gaussian one, with its old defaults.
  const KeypointNoiseConfig old;
  EXPECT_EQ(old.model, KeypointErrorModel::gaussian);
  EXPECT_EQ(old.noise_px, 2.0);
  EXPECT_EQ(old.occluded_dropout, 0.05);
}

TEST(SyntheticKeypoints, DetectorConfigKeysAreCheckedWithFileAndKey) {
  const SynthConfig c =
      parse_synth_config(synth_config("keypoints: {model: openpose, swap_probability: 0.05}\n"), "ok.yaml");
  EXPECT_EQ(c.keypoints.model, KeypointErrorModel::openpose);
  EXPECT_DOUBLE_EQ(c.keypoints.swap_probability, 0.05);
  EXPECT_DOUBLE_EQ(c.keypoints.scale_error_multiple, 1.5);  // the model's defaults for the rest
  EXPECT_DOUBLE_EQ(c.keypoints.occluded_dropout, 0.3);
  EXPECT_EQ(parse_synth_config(synth_config(""), "ok.yaml").keypoints.model, KeypointErrorModel::gaussian);

  const auto bad = [](const std::string& keypoints, std::initializer_list<std::string> parts) {
    expect_error([&] { parse_synth_config(synth_config(keypoints), "bad.yaml"); }, parts);
  };
  bad("keypoints: {model: openpose, scale_error_multiple: -1}\n", {"bad.yaml", "keypoints.scale_error_multiple"});
  bad("keypoints: {model: yolo}\n", {"bad.yaml", "keypoints.model", "gaussian or openpose", "yolo"});
  bad("keypoints: {model: [openpose]}\n", {"bad.yaml", "keypoints.model"});
  bad("keypoints: {model: openpose, swap_probability_side: 1.5}\n", {"bad.yaml", "keypoints.swap_probability_side"});
  bad("keypoints: {model: openpose, swap_confidence_scale: -0.5}\n", {"bad.yaml", "keypoints.swap_confidence_scale"});
  bad("keypoints: {model: openpose, confidence_falloff: 0}\n", {"bad.yaml", "keypoints.confidence_falloff"});
  bad("keypoints: {model: openpose, swap_rate: 0.1}\n", {"bad.yaml", "keypoints.swap_rate", "unknown key"});
  // A key of the other model is an error, not silently ignored.
  bad("keypoints: {model: openpose, noise_px: 2}\n", {"bad.yaml", "keypoints.noise_px", "gaussian only"});
  bad("keypoints: {swap_probability: 0.1}\n", {"bad.yaml", "keypoints.swap_probability", "openpose only"});
  bad("keypoints: {noise_px: 2, scale_error_multiple: 1}\n", {"bad.yaml", "keypoints.scale_error_multiple"});

  KeypointNoiseConfig direct = KeypointNoiseConfig::openpose();
  direct.scale_error_multiple = -1;
  expect_error([&] { validate_keypoint_noise(direct, "k"); }, {"scale_error_multiple"});
  direct = KeypointNoiseConfig::openpose();
  direct.confidence_falloff = 0;
  expect_error([&] { validate_keypoint_noise(direct, "k"); }, {"confidence_falloff"});
}

TEST(SyntheticKeypoints, TestSequencesUseTheDetectorModel) {
  for (const char* name : {"unseen_studio", "in_the_wild"})
    EXPECT_EQ(load_synth_config(repo_file(std::string("configs/synth/") + name + ".yaml")).keypoints.model,
              KeypointErrorModel::openpose)
        << name;
  REQUIRE_DEBIAN_FILE("/usr/share/backgrounds/mate/nature", "mate-backgrounds");
  EXPECT_EQ(load_synth_config(repo_file("configs/synth/in_the_wild_photos.yaml")).keypoints.model,
            KeypointErrorModel::openpose);
}
