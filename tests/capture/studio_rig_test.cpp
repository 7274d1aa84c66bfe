// The synthetic studio's cameras: the multi-view rig (placement, aim, framing of a
// 1.66 m subject, files, units) and the "in the wild" moving camera and exposure.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <set>

#include "capture/studio/studio_rig.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::expect_error;

namespace {

// Corners of a box around a 1.66 m A-pose subject standing on the floor (metres): the
// default character spans x ±0.53, z −0.10…0.34 (hands forward), y 0…1.66.
std::vector<Eigen::Vector3d> subject_box(double unit = 1.0) {
  std::vector<Eigen::Vector3d> corners;
  for (double x : {-0.55, 0.55})
    for (double y : {0.0, 1.66})
      for (double z : {-0.15, 0.35}) corners.emplace_back(Eigen::Vector3d(x, y, z) * unit);
  return corners;
}

// Every corner in front of the camera and at least `margin` (a fraction of the image
// size) inside the image.
void expect_in_frame(const Camera& c, const std::vector<Eigen::Vector3d>& points, double margin,
                     const std::string& where) {
  for (const Eigen::Vector3d& p : points) {
    ASSERT_GT(c.depth(p), 0) << where << " " << c.name;
    const Eigen::Vector2d uv = c.project(p);
    EXPECT_GE(uv.x(), margin * c.width) << where << " " << c.name << " corner " << p.transpose();
    EXPECT_LE(uv.x(), (1 - margin) * c.width) << where << " " << c.name << " corner " << p.transpose();
    EXPECT_GE(uv.y(), margin * c.height) << where << " " << c.name << " corner " << p.transpose();
    EXPECT_LE(uv.y(), (1 - margin) * c.height) << where << " " << c.name << " corner " << p.transpose();
  }
}

double azimuth_deg(const Eigen::Vector3d& centre, const Eigen::Vector3d& target) {
  return std::atan2(centre.x() - target.x(), centre.z() - target.z()) * 180 / M_PI;
}

double angle_between_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180 / M_PI;
}

}  // namespace

TEST(StudioRig, DefaultRigIsEightNamedCamerasEvenlyOnTheCircle) {
  const StudioRigConfig cfg;
  const std::vector<Camera> cams = studio_rig(cfg);
  ASSERT_EQ(cams.size(), 8u);
  for (size_t i = 0; i < cams.size(); ++i) {
    const Camera& c = cams[i];
    EXPECT_EQ(c.name, "cam0" + std::to_string(i));
    EXPECT_EQ(c.width, 512);
    EXPECT_EQ(c.height, 512);
    const Eigen::Vector3d centre = c.center();
    EXPECT_NEAR(std::hypot(centre.x() - cfg.target_m.x(), centre.z() - cfg.target_m.z()), cfg.radius_m, 1e-9);
    EXPECT_NEAR(centre.y(), cfg.height_m, 1e-9);
    // 45° apart, cam00 in front of the default character (+z).
    double expected = 45.0 * i;
    if (expected > 180) expected -= 360;
    EXPECT_NEAR(azimuth_deg(centre, cfg.target_m), expected, 1e-9) << c.name;
  }
  for (size_t i = 0; i < cams.size(); ++i)
    for (size_t j = i + 1; j < cams.size(); ++j)
      EXPECT_GT((cams[i].center() - cams[j].center()).norm(), 2.0) << i << " " << j;
}

TEST(StudioRig, EveryCameraIsAValidRotationLookingAtTheTargetWithUpUp) {
  for (int views : {1, 8, 18}) {
    StudioRigConfig cfg;
    cfg.views = views;
    cfg.width = 640;
    cfg.height = 480;
    cfg.first_azimuth_deg = 17;
    for (const Camera& c : studio_rig(cfg)) {
      EXPECT_NO_THROW(validate_camera(c, "rig"));
      EXPECT_NEAR((c.R * c.R.transpose() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
      EXPECT_NEAR(c.R.determinant(), 1, 1e-12);
      const Eigen::Vector2d principal(c.K(0, 2), c.K(1, 2));
      EXPECT_NEAR((principal - Eigen::Vector2d(319.5, 239.5)).norm(), 0, 1e-12);
      EXPECT_GT(c.depth(cfg.target_m), 0);
      EXPECT_LT((c.project(cfg.target_m) - principal).norm(), 1.0) << c.name;
      // The head is above the feet in the image, and the subject's left (+x) is on the
      // image's right for the camera in front.
      EXPECT_LT(c.project({0, 1.66, 0}).y(), c.project({0, 0, 0}).y()) << c.name;
    }
  }
  const Camera front = studio_rig({}).front();
  EXPECT_GT(front.project({0.3, 0.9, 0}).x(), front.project({-0.3, 0.9, 0}).x());
}

TEST(StudioRig, SubjectFitsEveryViewWithAMargin) {
  for (int views : {8, 18}) {
    StudioRigConfig cfg;
    cfg.views = views;
    for (const Camera& c : studio_rig(cfg)) expect_in_frame(c, subject_box(), 0.05, std::to_string(views) + " views");
  }
}

TEST(StudioRig, EighteenViewsAreTwoInterleavedRingsOfNine) {
  StudioRigConfig cfg;
  cfg.views = 18;
  EXPECT_EQ(studio_rig_rings(cfg), 2);
  const std::vector<Camera> cams = studio_rig(cfg);
  ASSERT_EQ(cams.size(), 18u);
  EXPECT_EQ(cams[17].name, "cam17");
  std::vector<double> azimuths;
  for (size_t i = 0; i < cams.size(); ++i) {
    const Eigen::Vector3d centre = cams[i].center();
    const double ring_height = i < 9 ? cfg.height_m - cfg.ring_spacing_m / 2 : cfg.height_m + cfg.ring_spacing_m / 2;
    EXPECT_NEAR(centre.y(), ring_height, 1e-9) << cams[i].name;
    EXPECT_NEAR(std::hypot(centre.x(), centre.z()), cfg.radius_m, 1e-9);
    double a = azimuth_deg(centre, cfg.target_m);
    azimuths.push_back(a < -1e-6 ? a + 360 : a);
  }
  std::sort(azimuths.begin(), azimuths.end());
  for (size_t i = 0; i < azimuths.size(); ++i) EXPECT_NEAR(azimuths[i], 20.0 * i, 1e-9);
  // Uneven counts spread over the rings too.
  cfg.views = 13;
  cfg.rings = 3;
  EXPECT_EQ(studio_rig(cfg).size(), 13u);
}

TEST(StudioRig, CamerasRoundTripThroughYaml) {
  ScratchDir dir("rig");
  StudioRigConfig cfg;
  cfg.views = 18;
  cfg.k1 = -0.05;
  const std::vector<Camera> cams = studio_rig(cfg);
  write_cameras_yaml(dir.file("cameras.yaml"), cams);
  const std::vector<Camera> back = read_cameras_yaml(dir.file("cameras.yaml"));
  ASSERT_EQ(back.size(), cams.size());
  for (size_t i = 0; i < cams.size(); ++i) {
    EXPECT_EQ(back[i].name, cams[i].name);
    EXPECT_EQ(back[i].width, cams[i].width);
    EXPECT_EQ(back[i].height, cams[i].height);
    EXPECT_LT((back[i].K - cams[i].K).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((back[i].R - cams[i].R).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((back[i].t - cams[i].t).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((back[i].dist - cams[i].dist).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_DOUBLE_EQ(back[i].dist(0), -0.05);
  }
}

TEST(StudioRig, MetresPerUnitPlacesCamerasInTheCharactersUnits) {
  StudioRigConfig metres;
  StudioRigConfig millimetres;
  millimetres.metres_per_unit = 0.001;
  const std::vector<Camera> m = studio_rig(metres), mm = studio_rig(millimetres);
  ASSERT_EQ(m.size(), mm.size());
  for (size_t i = 0; i < m.size(); ++i) {
    EXPECT_LT((mm[i].center() - 1000 * m[i].center()).norm(), 1e-9);
    EXPECT_LT((mm[i].R - m[i].R).norm(), 1e-12);
    EXPECT_LT((mm[i].K - m[i].K).norm(), 1e-12);
    // The same subject in millimetres looks the same.
    EXPECT_LT((mm[i].project(Eigen::Vector3d(120, 1500, -40)) - m[i].project(Eigen::Vector3d(0.12, 1.5, -0.04))).norm(),
              1e-9);
  }
  for (const Camera& c : mm) expect_in_frame(c, subject_box(1000), 0.05, "millimetres");
}

TEST(StudioRig, InvalidConfigsNameTheField) {
  StudioRigConfig cfg;
  cfg.views = 0;
  expect_error([&] { studio_rig(cfg); }, {"studio rig config", "views"});
  cfg = {};
  cfg.radius_m = -1;
  expect_error([&] { studio_rig(cfg); }, {"radius_m"});
  cfg = {};
  cfg.vertical_fov_deg = 180;
  expect_error([&] { studio_rig(cfg); }, {"vertical_fov_deg"});
  cfg = {};
  cfg.metres_per_unit = 0;
  expect_error([&] { studio_rig(cfg); }, {"metres_per_unit"});
  expect_error([&] { look_at_camera("top", {0, 3, 0}, {0, 0, 0}, 64, 64, 40); }, {"top", "straight up or down"});
}

// ------------------------------------------------------------------ in the wild

TEST(WildCamera, SameSeedSamePathOtherSeedOtherPath) {
  const WildCameraConfig cfg;
  const auto a = wild_camera_path(cfg, 60, 30, 7), b = wild_camera_path(cfg, 60, 30, 7),
             c = wild_camera_path(cfg, 60, 30, 8);
  ASSERT_EQ(a.size(), 60u);
  EXPECT_EQ(a[0].name, "wild0000");
  EXPECT_EQ(a[59].name, "wild0059");
  double differs = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].R, b[i].R);
    EXPECT_EQ(a[i].t, b[i].t);
    EXPECT_EQ(a[i].K, b[i].K);
    differs = std::max(differs, (a[i].center() - c[i].center()).norm());
  }
  EXPECT_GT(differs, 1e-3);  // metres: the shake differs
  EXPECT_EQ(wild_exposure(cfg, 60, 30, 7), wild_exposure(cfg, 60, 30, 7));
  EXPECT_NE(wild_exposure(cfg, 60, 30, 7), wild_exposure(cfg, 60, 30, 8));
}

TEST(WildCamera, FollowsTheArcWithBoundedShake) {
  WildCameraConfig cfg;
  const int frames = 90;
  const auto path = wild_camera_path(cfg, frames, 30, 3);
  WildCameraConfig still = cfg;
  still.shake_position_m = 0;
  still.shake_rotation_deg = 0;
  const auto steady = wild_camera_path(still, frames, 30, 3);
  // Without shake: on the arc, from the start azimuth and radius to the end ones.
  EXPECT_NEAR(azimuth_deg(steady.front().center(), cfg.target_m), cfg.start_azimuth_deg, 1e-9);
  EXPECT_NEAR(azimuth_deg(steady.back().center(), cfg.target_m), cfg.start_azimuth_deg + cfg.arc_deg, 1e-9);
  EXPECT_NEAR(std::hypot(steady.front().center().x(), steady.front().center().z()), cfg.radius_start_m, 1e-9);
  EXPECT_NEAR(std::hypot(steady.back().center().x(), steady.back().center().z()), cfg.radius_end_m, 1e-9);
  for (const Camera& c : steady) {
    EXPECT_NEAR(c.center().y(), cfg.height_m, 1e-9);
    EXPECT_LT((c.project(cfg.target_m) - Eigen::Vector2d(c.K(0, 2), c.K(1, 2))).norm(), 1e-6);
  }
  // With shake: off the arc, but never by more than the amplitudes.
  double largest_offset = 0, largest_turn = 0;
  for (int i = 0; i < frames; ++i) {
    const Eigen::Vector3d offset = path[i].center() - steady[i].center();
    EXPECT_LE(offset.cwiseAbs().maxCoeff(), cfg.shake_position_m + 1e-12);
    largest_offset = std::max(largest_offset, offset.norm());
    largest_turn = std::max(largest_turn, angle_between_deg(path[i].R, steady[i].R));
  }
  EXPECT_GT(largest_offset, 0.1 * cfg.shake_position_m);
  EXPECT_GT(largest_turn, 0.1 * cfg.shake_rotation_deg);
  EXPECT_LT(largest_turn, cfg.shake_rotation_deg * std::sqrt(3.0) + 1.0);  // shake plus the aim change from the offset
}

TEST(WildCamera, MovesSmoothlyFromFrameToFrame) {
  WildCameraConfig cfg;
  const int frames = 120;
  const double fps = 30;
  for (uint64_t seed : {1u, 2u, 3u}) {
    const auto path = wild_camera_path(cfg, frames, fps, seed);
    // Bounds from the motion's own speeds: the eased orbit peaks at 1.5× its mean rate;
    // the shake changes by at most 2π f A per second per axis.
    const double arc_rad = cfg.arc_deg * M_PI / 180;
    const double orbit_step = 1.5 * (arc_rad * std::max(cfg.radius_start_m, cfg.radius_end_m) +
                                     std::abs(cfg.radius_end_m - cfg.radius_start_m)) / (frames - 1);
    const double shake_step = 2 * M_PI * cfg.shake_frequency_hz * cfg.shake_position_m / fps * std::sqrt(3.0);
    double mean_step = 0;
    for (int i = 1; i < frames; ++i) {
      const double step = (path[i].center() - path[i - 1].center()).norm();
      mean_step += step / (frames - 1);
      EXPECT_LE(step, orbit_step + shake_step) << "frame " << i;
      EXPECT_LT(angle_between_deg(path[i].R, path[i - 1].R), 1.0) << "frame " << i;
    }
    EXPECT_GT(mean_step, 0.5 * arc_rad * cfg.radius_end_m / (frames - 1));  // it does move
  }
}

TEST(WildCamera, SubjectStaysInFrame) {
  WildCameraConfig cfg;
  for (uint64_t seed = 0; seed < 5; ++seed)
    for (const Camera& c : wild_camera_path(cfg, 150, 30, seed)) expect_in_frame(c, subject_box(), 0.02, "wild");
  cfg.metres_per_unit = 0.001;
  for (const Camera& c : wild_camera_path(cfg, 30, 30, 1)) expect_in_frame(c, subject_box(1000), 0.02, "wild mm");
}

// A subject walking 3 m along x and 1 m along z over 4 s (and bobbing 5 cm up and down):
// the camera keeps it in frame and aims at its smoothed ground position.
TEST(WildCamera, FollowsAWalkingSubject) {
  WildCameraConfig cfg;
  const int frames = 120;
  const double fps = 30;
  std::vector<Eigen::Vector3d> root(frames);
  for (int i = 0; i < frames; ++i) {
    const double s = double(i) / (frames - 1);
    root[i] = Eigen::Vector3d(3.0 * s, 0.95 + 0.05 * std::sin(12 * s), 1.0 * s);
  }
  const std::vector<Eigen::Vector3d> smooth = smooth_track(root, cfg.follow_smoothing_s * fps);
  WildCameraConfig still = cfg;
  still.shake_position_m = 0;
  still.shake_rotation_deg = 0;
  const auto steady = wild_camera_path(still, frames, fps, 4, root);
  for (int i = 0; i < frames; ++i) {
    Eigen::Vector3d aim = cfg.target_m + smooth[i] - smooth[0];
    aim.y() = cfg.target_m.y();  // the subject's height does not move the aim
    const Camera& c = steady[i];
    EXPECT_LT((c.project(aim) - Eigen::Vector2d(c.K(0, 2), c.K(1, 2))).norm(), 1e-6) << "frame " << i;
    EXPECT_NEAR(c.center().y(), cfg.height_m, 1e-9);
  }
  for (uint64_t seed = 0; seed < 3; ++seed) {
    const auto path = wild_camera_path(cfg, frames, fps, seed, root);
    for (int i = 0; i < frames; ++i) {
      std::vector<Eigen::Vector3d> box = subject_box();
      for (auto& p : box) p += Eigen::Vector3d(root[i].x(), 0, root[i].z());
      expect_in_frame(path[i], box, 0.02, "walking, frame " + std::to_string(i));
    }
    // The same walk with a fixed aim loses the subject.
    const auto fixed = wild_camera_path(cfg, frames, fps, seed);
    const Eigen::Vector2d last = fixed.back().project(Eigen::Vector3d(root.back().x() + 0.55, 0, root.back().z()));
    EXPECT_GT(last.x(), fixed.back().width) << "the fixed camera should have lost the subject (test premise)";
  }
  // follow_subject false: the track is ignored.
  still.follow_subject = false;
  const auto ignored = wild_camera_path(still, frames, fps, 4, root), plain = wild_camera_path(still, frames, fps, 4);
  for (int i = 0; i < frames; ++i) EXPECT_EQ(ignored[i].t, plain[i].t);
}

TEST(WildCamera, TrackSmoothingKeepsLinesAndRemovesJitter) {
  std::vector<Eigen::Vector3d> line(60), jitter(60);
  for (int i = 0; i < 60; ++i) {
    line[i] = Eigen::Vector3d(0.1 * i, 1.0, -0.05 * i);
    jitter[i] = Eigen::Vector3d((i % 2 ? 0.02 : -0.02), 0, 0);
  }
  const auto smooth_line = smooth_track(line, 4.0), smooth_jitter = smooth_track(jitter, 4.0);
  for (int i = 0; i < 60; ++i) {  // a steady motion, up to the ends, without lag
    EXPECT_LT((smooth_line[i] - line[i]).norm(), 1e-9) << i;
    EXPECT_LT(smooth_jitter[i].norm(), i >= 12 && i < 48 ? 2e-4 : 5e-3) << i;  // ±2 cm jitter
  }
  EXPECT_EQ(smooth_track(line, 0.0), line);
  expect_error([&] { smooth_track(line, -1); }, {"sigma"});
  WildCameraConfig cfg;
  expect_error([&] { wild_camera_path(cfg, 10, 30, 1, std::vector<Eigen::Vector3d>(9)); }, {"track", "9", "10"});
  std::vector<Eigen::Vector3d> bad(10, Eigen::Vector3d::Zero());
  bad[3].x() = NAN;
  expect_error([&] { wild_camera_path(cfg, 10, 30, 1, bad); }, {"track", "frame 3"});
}

TEST(WildCamera, ExposureStaysInRangeAndChangesSmoothly) {
  WildCameraConfig cfg;
  cfg.exposure_min = 0.5;
  cfg.exposure_max = 1.5;
  cfg.exposure_frequency_hz = 0.5;
  const double fps = 25;
  for (uint64_t seed = 0; seed < 8; ++seed) {
    const std::vector<double> e = wild_exposure(cfg, 250, fps, seed);
    ASSERT_EQ(e.size(), 250u);
    double lo = e[0], hi = e[0];
    for (size_t i = 0; i < e.size(); ++i) {
      EXPECT_GE(e[i], cfg.exposure_min);
      EXPECT_LE(e[i], cfg.exposure_max);
      lo = std::min(lo, e[i]);
      hi = std::max(hi, e[i]);
      if (i > 0) {
        EXPECT_LE(std::abs(e[i] - e[i - 1]),
                  2 * M_PI * cfg.exposure_frequency_hz * 0.5 * (cfg.exposure_max - cfg.exposure_min) / fps + 1e-12);
      }
    }
    EXPECT_GT(hi - lo, 0.1 * (cfg.exposure_max - cfg.exposure_min)) << "seed " << seed;  // lighting does change
  }
}

TEST(WildCamera, InvalidArgumentsNameTheField) {
  WildCameraConfig cfg;
  expect_error([&] { wild_camera_path(cfg, 0, 30, 1); }, {"frames"});
  expect_error([&] { wild_camera_path(cfg, 10, 0, 1); }, {"fps"});
  cfg.exposure_min = 2;
  expect_error([&] { wild_exposure(cfg, 10, 30, 1); }, {"exposure_min"});
  cfg = {};
  cfg.shake_position_m = -1;
  expect_error([&] { wild_camera_path(cfg, 10, 30, 1); }, {"shake_position_m"});
}
