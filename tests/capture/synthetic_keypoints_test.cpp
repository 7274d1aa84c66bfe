// Synthetic BODY_25 detections: exact projection without noise, noise and dropout
// statistics, the occlusion rule against a rendered depth image, unmapped and
// out-of-frame keypoints, determinism and the OpenPose JSON files.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "capture/render/renderer.h"
#include "capture/studio/studio_rig.h"
#include "capture/studio/synthetic_keypoints.h"
#include "tests/capture/box_mesh.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::box_mesh;
using weft::capture::testing::expect_error;

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
