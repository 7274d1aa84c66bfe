#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "capture/io/camera.h"
#include "capture/io/openpose.h"
#include "files/text_reader.h"
#include "tests/capture/opencv_silhouette.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::expect_error;

namespace {

Camera test_camera() {
  Camera c;
  c.name = "cam 0";
  c.K << 1100, 0, 640.5, 0, 1090, 355.25, 0, 0, 1;
  c.dist << -0.21, 0.07, 0.0013, -0.0021, 0.012;
  c.R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 1, 0.1).normalized()).toRotationMatrix();
  c.t << 50, -120, 3200;  // mm
  c.width = 1280;
  c.height = 720;
  return c;
}

TEST(Camera, ProjectionMatchesOpenCvProjectPoints) {
  const Camera c = test_camera();
  Vertices X(6, 3);
  X << 0, 0, 0, 400, 800, 100, -600, 1500, -300, 900, -200, 200, 10, 20, 30, -800, -900, 0;
  TriangleMesh points;
  points.V = X;
  const std::vector<cv::Point2d> ref = weft::capture::testing::opencv_projection(c, points);
  const Points2 uv = project_points(c, X);
  for (int i = 0; i < X.rows(); ++i) {
    EXPECT_NEAR(uv(i, 0), ref[i].x, 1e-6) << i;
    EXPECT_NEAR(uv(i, 1), ref[i].y, 1e-6) << i;
  }
}

TEST(Camera, YamlRoundTrip) {
  ScratchDir dir("cams");
  Camera b = test_camera();
  b.name = "side";
  b.t << -10, 0, 2000;
  write_cameras_yaml(dir.file("cams.yaml"), {test_camera(), b});
  const std::vector<Camera> r = read_cameras_yaml(dir.file("cams.yaml"));
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[0].name, "cam 0");
  EXPECT_EQ(r[1].name, "side");
  EXPECT_TRUE(r[0].K.isApprox(test_camera().K, 1e-12));
  EXPECT_TRUE(r[0].R.isApprox(test_camera().R, 1e-12));
  EXPECT_TRUE(r[0].dist.isApprox(test_camera().dist, 1e-12));
  EXPECT_TRUE(r[1].t.isApprox(b.t, 1e-12));
  EXPECT_EQ(r[1].width, 1280);
  EXPECT_EQ(r[1].height, 720);
}

TEST(Camera, MalformedYamlNamesFileAndKey) {
  ScratchDir dir("badcams");
  write_cameras_yaml(dir.file("good.yaml"), {test_camera()});
  std::string text = read_file_bytes(dir.file("good.yaml"));
  auto variant = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const size_t at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    t.replace(at, from.size(), to);
    return dir.write("bad.yaml", t);
  };
  expect_error([&] { read_cameras_yaml(variant("image_width", "image_widht")); }, {"bad.yaml", "unknown key 'image_widht'"});
  expect_error([&] { read_cameras_yaml(variant("dist:", "distortion:")); }, {"bad.yaml", "unknown key"});
  expect_error([&] { read_cameras_yaml(variant("cameras:", "kameras:")); }, {"bad.yaml", "'cameras'"});
  expect_error([&] { read_cameras_yaml(dir.write("bad.yaml", "%YAML:1.0\n---\ncameras: [ {name: a, K: [1, 2\n")); },
               {"bad.yaml"});
  expect_error([&] { read_cameras_yaml(dir.file("missing.yaml")); }, {"missing.yaml", "cannot open"});
}

TEST(Camera, SkeletoolCalibrationImport) {
  ScratchDir dir("calib");
  const std::string p = dir.write(
      "c.calibration",
      "Skeletool Camera Calibration File V1.0\r\n"
      "name          0\r\n  sensor      14.1864 10.3776\r\n  size        1285 940\r\n  animated    0\r\n"
      "  intrinsic   766.3206 0 635.1871 0 0 765.7619 448.8466 0 0 0 1 0 0 0 0 1 \r\n"
      "  extrinsic   1 0 0 703.8 0 1 0 150.7 0 0 1 4868.0 0 0 0 1 \r\n  radial      -0.1\r\n"
      "name          1\r\n  sensor      14.1864 10.3776\r\n  size        640 480\r\n  animated    0\r\n"
      "  intrinsic   500 0 320 0 0 500 240 0 0 0 1 0 0 0 0 1\r\n"
      "  extrinsic   1 0 0 0 0 1 0 0 0 0 1 3000 0 0 0 1\r\n  radial      0\r\n");
  const std::vector<Camera> cams = read_skeletool_calibration(p);
  ASSERT_EQ(cams.size(), 2u);
  EXPECT_EQ(cams[0].name, "0");
  EXPECT_DOUBLE_EQ(cams[0].K(0, 2), 635.1871);
  EXPECT_DOUBLE_EQ(cams[0].t(2), 4868.0);
  EXPECT_DOUBLE_EQ(cams[0].dist(0), -0.1);
  EXPECT_EQ(cams[1].width, 640);
  EXPECT_TRUE(cams[1].project(Eigen::Vector3d(0, 0, 0)).isApprox(Eigen::Vector2d(320, 240)));
  std::string bad = read_file_bytes(p);
  bad.replace(bad.find("1 0 0 0 0 1 0 0 0 0 1 3000 0 0 0 1"), 9, "1 0 0 0");
  expect_error([&] { read_skeletool_calibration(dir.write("b.calibration", bad)); }, {"b.calibration:14:", "17 fields"});
  expect_error([&] { read_skeletool_calibration(dir.write("b.calibration", "Skeletool Camera Calibration File V1.0\nname 0\nsize 2 2\n")); },
               {"b.calibration", "no 'intrinsic'"});
}

TEST(OpenPose, RoundTripAndErrors) {
  ScratchDir dir("openpose");
  OpenPoseFrame f;
  Body25 a = Body25::Zero();  // an undetected keypoint is 0, 0, 0
  for (int k = 0; k < 25; ++k)
    if (k % 3) a.row(k) << 100.5 + k, 200.25 - k, 0.01 * k;
  f.people = {a, Body25::Constant(3.0)};
  write_openpose_json(dir.file("f_keypoints.json"), f);
  const OpenPoseFrame r = read_openpose_json(dir.file("f_keypoints.json"));
  ASSERT_EQ(r.people.size(), 2u);
  EXPECT_EQ(r.people[0], a);
  EXPECT_EQ(r.people[1], Body25::Constant(3.0));
  EXPECT_EQ(body25_index("RHeel"), 24);
  EXPECT_EQ(body25_index("MidHip"), 8);
  expect_error([] { parse_openpose_json("{\"people\": [{\"pose_keypoints_2d\": [1, 2, 3]}]}", "k.json"); },
               {"k.json", "people[0]", "expected 75 numbers", "found 3"});
  expect_error([] { parse_openpose_json("{\n\"people\": [\n{\"pose_keypoints_2d\": [1, 2,\n", "k.json"); },
               {"k.json:", "invalid JSON"});
  expect_error([] { parse_openpose_json("{\"version\": 1.3}", "k.json"); }, {"k.json", "'people'"});
  std::string text = "{\"people\": [{\"pose_keypoints_2d\": [";
  for (int i = 0; i < 75; ++i) text += (i ? "," : "") + std::string(i == 7 ? "\"x\"" : "1");
  expect_error([&] { parse_openpose_json(text + "]}]}", "k.json"); }, {"k.json", "pose_keypoints_2d[7]", "expected a number"});
}

}  // namespace
