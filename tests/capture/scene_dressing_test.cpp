// The synthetic studio's scene dressing: lights drawn per clip and photo backgrounds, what a
// config gets for a bad key, and that both are reproducible from the seed.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "files/strict_yaml.h"
#include "capture/studio/scene_dressing.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::ScratchDir;

namespace {

StudioLightingConfig lighting(const std::string& text) {
  const StrictYaml y{"light.yaml", "."};
  return parse_studio_lighting(y, y.parse(text), "render.lighting");
}

}  // namespace

TEST(StudioLighting, ParsesEveryKeyAndNamesBadOnes) {
  const StudioLightingConfig c =
      lighting("{ambient: 0.2, headlight: 0, lights: 3, intensity: [0.4, 0.5], elevation_deg: [10, 20]}");
  EXPECT_DOUBLE_EQ(c.ambient, 0.2);
  EXPECT_DOUBLE_EQ(c.headlight, 0);
  EXPECT_EQ(c.lights, 3);
  EXPECT_DOUBLE_EQ(c.intensity_min, 0.4);
  EXPECT_DOUBLE_EQ(c.elevation_max_deg, 20);
  expect_error([] { lighting("{ambient: 0.2, spot: 1}"); }, {"light.yaml", "render.lighting.spot", "unknown key"});
  expect_error([] { lighting("{intensity: [0.6, 0.3]}"); }, {"light.yaml:1", "render.lighting.intensity", "min"});
  expect_error([] { lighting("{elevation_deg: [10, 120]}"); }, {"render.lighting.elevation_deg"});
  expect_error([] { lighting("{lights: 20}"); }, {"render.lighting.lights"});
  expect_error([] { lighting("{ambient: 0, headlight: 0, lights: 0}"); }, {"render.lighting", "no light"});
}

TEST(StudioLighting, DirectionsAreDrawnPerClipAboveTheHorizon) {
  StudioLightingConfig c;
  c.lights = 4;
  c.headlight = 0;
  c.elevation_min_deg = 20;
  c.elevation_max_deg = 50;
  const Lighting a = draw_lighting(c, 7, 0), again = draw_lighting(c, 7, 0), other = draw_lighting(c, 7, 1);
  ASSERT_EQ(a.lights.size(), 4u);
  EXPECT_DOUBLE_EQ(a.headlight, 0);
  double differ = 0;
  for (size_t i = 0; i < a.lights.size(); ++i) {
    const Eigen::Vector3d d = a.lights[i].direction;
    EXPECT_NEAR(d.norm(), 1, 1e-12);
    // Travelling downward at 20°..50° below the horizon.
    const double elevation = std::asin(-d.y()) * 180 / std::numbers::pi;
    EXPECT_GE(elevation, 20 - 1e-9);
    EXPECT_LE(elevation, 50 + 1e-9);
    EXPECT_GE(a.lights[i].intensity, c.intensity_min);
    EXPECT_LE(a.lights[i].intensity, c.intensity_max);
    EXPECT_EQ(d, again.lights[i].direction);  // the same seed and clip: the same lights
    differ += (d - other.lights[i].direction).norm();
  }
  EXPECT_GT(differ, 0.1);  // another clip: other lights
}

TEST(PhotoBackground, CropsAreReproducibleAndComeFromThePhotos) {
  ScratchDir dir("photos");
  // Two "photos": a horizontal and a vertical gradient, of different sizes.
  cv::Mat h(300, 400, CV_8UC3), v(500, 350, CV_8UC3);
  for (int y = 0; y < h.rows; ++y)
    for (int x = 0; x < h.cols; ++x) h.at<cv::Vec3b>(y, x) = cv::Vec3b(uchar(x * 255 / 399), 40, 200);
  for (int y = 0; y < v.rows; ++y)
    for (int x = 0; x < v.cols; ++x) v.at<cv::Vec3b>(y, x) = cv::Vec3b(10, uchar(y * 255 / 499), 90);
  cv::imwrite(dir.file("a.png"), h);
  cv::imwrite(dir.file("b.jpg"), v);
  dir.write("notes.txt", "not a photo");
  const std::vector<std::string> photos = list_photos(dir.file(""), "render.photos");
  ASSERT_EQ(photos.size(), 2u);
  EXPECT_NE(photos[0].find("a.png"), std::string::npos);  // sorted, the text file left out
  int from_a = 0, from_b = 0;
  for (int view = 0; view < 12; ++view) {
    const cv::Mat crop = draw_photo_background(photos, 64, 48, 3, 0, view);
    ASSERT_EQ(crop.size(), cv::Size(64, 48));
    ASSERT_EQ(crop.type(), CV_8UC3);
    EXPECT_EQ(cv::norm(crop, draw_photo_background(photos, 64, 48, 3, 0, view), cv::NORM_INF), 0);
    const cv::Vec3b p = crop.at<cv::Vec3b>(24, 32);
    if (std::abs(p[1] - 40) <= 3 && std::abs(p[2] - 200) <= 3) ++from_a;
    else if (std::abs(p[0] - 10) <= 8 && std::abs(p[2] - 90) <= 8) ++from_b;
  }
  EXPECT_EQ(from_a + from_b, 12);  // every crop is of one of the photos
  EXPECT_GT(from_a, 0);
  EXPECT_GT(from_b, 0);
  // Another clip or seed: another crop.
  EXPECT_GT(cv::norm(draw_photo_background(photos, 64, 48, 3, 0, 0), draw_photo_background(photos, 64, 48, 4, 0, 0)),
            0);
}

TEST(PhotoBackground, AFolderWithoutPhotosIsOneClearError) {
  ScratchDir dir("nophotos");
  dir.write("readme.txt", "x");
  expect_error([&] { list_photos(dir.file(""), "bad.yaml: render.photos"); },
               {"bad.yaml: render.photos", "no .jpg", "mate-backgrounds"});
  expect_error([] { list_photos("/nonexistent/photos", "render.photos"); }, {"/nonexistent/photos"});
  dir.write("broken.jpg", "not a jpeg");
  const std::vector<std::string> photos = list_photos(dir.file(""), "render.photos");
  expect_error([&] { draw_photo_background(photos, 8, 8, 1, 0, 0); }, {"broken.jpg", "cannot read"});
}
