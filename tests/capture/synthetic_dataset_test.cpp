// The synthetic dataset reader against a small dataset written here with OpenCV and weft's
// own writers: dataset.yaml checks, the crop and its camera, keypoints, normalisation,
// distance transforms, batches, and the prefetcher's order under different thread counts.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <set>

#include "capture/render/renderer.h"
#include "capture/dataset/synthetic_dataset.h"
#include "files/strict_yaml.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::ScratchDir;
namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 80, kHeight = 64, kFrames = 6;
const std::vector<std::string> kViews = {"cam00", "cam01", "cam02"};
const cv::Vec3b kBackground(10, 20, 200);  // BGR
const cv::Vec3b kPerson(200, 50, 30);      // BGR
const cv::Vec3b kMarker(200, 255, 30);     // BGR: only its green exceeds the person's

// A camera 4 units from the origin looking at it, with some lens distortion.
Camera look_at_camera(const std::string& name, double azimuth) {
  Camera c;
  c.name = name;
  const Eigen::Vector3d centre(4 * std::sin(azimuth), 0.3, -4 * std::cos(azimuth));
  const Eigen::Vector3d z = (-centre).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d(0, -1, 0)).normalized();
  const Eigen::Vector3d y = z.cross(x);
  c.R.row(0) = x.transpose();
  c.R.row(1) = y.transpose();
  c.R.row(2) = z.transpose();
  c.t = -c.R * centre;
  c.K << 70, 0, 40.5, 0, 72, 31.25, 0, 0, 1;
  c.dist << 0.05, -0.01, 0.001, -0.002, 0.003;
  c.width = kWidth;
  c.height = kHeight;
  return c;
}

// World positions of the 25 "joints": a small cloud around the origin.
Eigen::Vector3d joint(int k) { return {0.05 * (k % 5 - 2), 0.06 * (k / 5 - 2), 0.01 * k}; }
bool undetected(int k) { return k == 3 || k == 17; }

cv::Point2i ellipse_centre(const Camera& cam, int frame, int view) {
  if (view == 2) return {6, 30 + frame};  // at the left border: the crop reaches past it
  const Eigen::Vector2d p = cam.project(Eigen::Vector3d::Zero());
  return {int(std::lround(p.x())) + frame % 3, int(std::lround(p.y()))};
}
const cv::Size kAxes(10, 15);
cv::Point2i marker_pixel(const cv::Point2i& centre) { return centre + cv::Point2i(3, 5); }

struct FakeDataset {
  std::string dir;
  std::vector<Camera> cameras;  // by view
};

void make_dirs(const std::string& dir) {
  for (const char* kind : {"images", "masks", "keypoints"})
    for (const std::string& v : kViews) fs::create_directories(fs::path(dir) / kind / v);
  fs::create_directories(fs::path(dir) / "character");
  std::ofstream(fs::path(dir) / "character" / "character.yaml") << "name: fake\n";
}

const char* kSplits = "splits:\n  train: [0, 1, 2, 3]\n  val: [4]\n  test: [5]\n";

std::string dataset_yaml(const std::string& extra = "", const std::string& splits = kSplits,
                         const std::string& failed = "[]") {
  return "format: weft-synth/1\nname: tiny\nseed: 7\nfps: 30.0\nmetres_per_unit: 1.0\nframes: 6\n"
         "views: [cam00, cam01, cam02]\nimage_width: 80\nimage_height: 64\ncamera_per_frame: false\n"
         "character: character/character.yaml\ndt_scale: 16\n" +
         splits + "failed_frames: " + failed + "\n" + extra;
}

// Frame 3 of cam01 has an empty mask (the crop falls back to keypoints); frame 4 of
// cam01 has neither mask nor keypoints (the whole image).
FakeDataset write_dataset(const ScratchDir& scratch) {
  FakeDataset d;
  d.dir = scratch.file("tiny");
  make_dirs(d.dir);
  for (size_t v = 0; v < kViews.size(); ++v) d.cameras.push_back(look_at_camera(kViews[v], 0.4 * double(v)));
  write_cameras_yaml((fs::path(d.dir) / "cameras.yaml").string(), d.cameras);
  std::ofstream(fs::path(d.dir) / "dataset.yaml") << dataset_yaml();
  DatasetInfo info;
  info.dir = d.dir;
  for (int f = 0; f < kFrames; ++f)
    for (int v = 0; v < int(kViews.size()); ++v) {
      const Camera& cam = d.cameras[size_t(v)];
      cv::Mat image(kHeight, kWidth, CV_8UC3, cv::Scalar(kBackground[0], kBackground[1], kBackground[2]));
      cv::Mat mask(kHeight, kWidth, CV_8UC1, cv::Scalar(0));
      const bool empty_mask = v == 1 && (f == 3 || f == 4);
      const cv::Point2i c = ellipse_centre(cam, f, v);
      if (!empty_mask) {
        cv::ellipse(mask, c, kAxes, 0, 0, 360, cv::Scalar(255), cv::FILLED);
        image.setTo(cv::Scalar(kPerson[0], kPerson[1], kPerson[2]), mask);
        cv::rectangle(image, cv::Rect(marker_pixel(c) - cv::Point2i(1, 1), cv::Size(3, 3)),
                      cv::Scalar(kMarker[0], kMarker[1], kMarker[2]), cv::FILLED);
      }
      EXPECT_TRUE(cv::imwrite(dataset_image_path(info, f, kViews[size_t(v)]), image));
      EXPECT_TRUE(cv::imwrite(dataset_mask_path(info, f, kViews[size_t(v)]), mask));
      OpenPoseFrame op;
      if (!(v == 1 && f == 4)) {
        Body25 kp = Body25::Zero();
        for (int k = 0; k < kBody25Count; ++k)
          if (!undetected(k)) kp.row(k) << cam.project(joint(k)).transpose(), 0.5 + 0.02 * k;
        op.people.push_back(kp);
      }
      write_openpose_json(dataset_keypoints_path(info, f, kViews[size_t(v)]), op);
    }
  return d;
}

// The full image's colour at a pixel, black beyond the border (the crop's padding).
cv::Vec3b full_pixel(const cv::Mat& image, int x, int y) {
  if (x < 0 || y < 0 || x >= image.cols || y >= image.rows) return {0, 0, 0};
  return image.at<cv::Vec3b>(y, x);
}

// True when every full-image pixel that can contribute to crop pixel (x', y') under
// cv::resize (its footprint widened by one pixel for linear interpolation) has one colour.
bool uniform_footprint(const cv::Mat& image, const CropWindow& crop, int xc, int yc, cv::Vec3b& colour) {
  const double u0 = crop.left + xc / crop.scale, u1 = crop.left + (xc + 1) / crop.scale;
  const double v0 = crop.top + yc / crop.scale, v1 = crop.top + (yc + 1) / crop.scale;
  colour = full_pixel(image, int(std::floor(u0)) - 1, int(std::floor(v0)) - 1);
  for (int y = int(std::floor(v0)) - 1; y <= int(std::ceil(v1)) + 1; ++y)
    for (int x = int(std::floor(u0)) - 1; x <= int(std::ceil(u1)) + 1; ++x)
      if (full_pixel(image, x, y) != colour) return false;
  return true;
}

double normalised(uint8_t value, int rgb_channel) {
  const double mean[3] = {0.485, 0.456, 0.406}, stddev[3] = {0.229, 0.224, 0.225};
  return (value / 255.0 - mean[rgb_channel]) / stddev[rgb_channel];
}

}  // namespace

// ---------------------------------------------------------------------- dataset.yaml

TEST(SyntheticDatasetInfo, ReadsEveryKey) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const DatasetInfo info = read_dataset_info(d.dir);
  EXPECT_EQ(info.format, "weft-synth/1");
  EXPECT_EQ(info.name, "tiny");
  EXPECT_EQ(info.seed, 7u);
  EXPECT_EQ(info.fps, 30.0);
  EXPECT_EQ(info.frames, 6);
  EXPECT_EQ(info.views, kViews);
  EXPECT_EQ(info.image_width, kWidth);
  EXPECT_EQ(info.image_height, kHeight);
  EXPECT_FALSE(info.camera_per_frame);
  EXPECT_EQ(info.dt_scale, 16.0);
  EXPECT_TRUE(fs::equivalent(info.character, fs::path(d.dir) / "character" / "character.yaml"));
  EXPECT_EQ(info.splits.at("train"), (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(info.splits.at("val"), (std::vector<int>{4}));
  EXPECT_EQ(info.splits.at("test"), (std::vector<int>{5}));
  EXPECT_TRUE(info.failed_frames.empty());
  EXPECT_TRUE(info.segments.empty());  // one clip
  for (int a = 0; a < 6; ++a)
    for (int b = 0; b < 6; ++b) EXPECT_TRUE(same_segment(info, a, b));
}

TEST(SyntheticDatasetInfo, SegmentsSplitTheFramesIntoClips) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  std::ofstream(fs::path(d.dir) / "dataset.yaml") << dataset_yaml("segments: [0, 2, 5]\n");
  const DatasetInfo info = read_dataset_info(d.dir);
  EXPECT_EQ(info.segments, (std::vector<int>{0, 2, 5}));
  EXPECT_TRUE(same_segment(info, 0, 1));
  EXPECT_FALSE(same_segment(info, 1, 2));
  EXPECT_TRUE(same_segment(info, 2, 4));
  EXPECT_TRUE(same_segment(info, 4, 2));
  EXPECT_FALSE(same_segment(info, 0, 5));
  EXPECT_FALSE(same_segment(info, 4, 5));
  EXPECT_TRUE(same_segment(info, 5, 5));  // the last clip: one frame
  expect_error([&] { same_segment(info, 0, 6); }, {"same_segment", "frame 6", "0..5"});
  expect_error([&] { same_segment(info, -1, 0); }, {"same_segment", "frame -1"});
}

TEST(SyntheticDatasetInfo, BadSegmentsNameFileLineAndKey) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  auto rewrite = [&](const std::string& segments) {
    std::ofstream(fs::path(d.dir) / "dataset.yaml") << dataset_yaml("segments: " + segments + "\n");
  };
  // dataset_yaml puts the extra keys on line 18.
  rewrite("[2, 4]");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml:18: segments", "starts at frame 0, found 2"});
  rewrite("[0, 4, 3]");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml:18: segments", "frame 3 after 4", "increasing"});
  rewrite("[0, 2, 2]");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml:18: segments", "frame 2 after 2"});
  rewrite("[0, 6]");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml:18: segments", "frame 6 out of range (frames: 6)"});
  rewrite("[0, two]");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml:18: segments", "expected a frame id"});
  rewrite("[]");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml:18: segments", "expected a list"});
  rewrite("0");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml:18: segments", "expected a list"});
}

TEST(SyntheticDatasetInfo, ErrorsNameFileKeyAndExpectation) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const std::string yaml = (fs::path(d.dir) / "dataset.yaml").string();
  auto rewrite = [&](const std::string& text) { std::ofstream(yaml) << text; };

  rewrite(dataset_yaml("colour: red\n"));
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml", "colour", "unknown key"});

  rewrite(dataset_yaml("", "splits:\n  train: [0, 9]\n"));
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml", "splits.train", "frame 9 out of range"});

  rewrite(dataset_yaml("", "splits:\n  train: [0, 1]\n  test: [1]\n"));
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml", "splits.test", "also in split 'train'"});

  rewrite(dataset_yaml("", "splits:\n  train: [0, 5]\n", "[5]"));
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml", "failed_frames", "frame 5", "split 'train'"});

  std::string text = dataset_yaml();
  text.replace(text.find("frames: 6"), 9, "frames: six");
  rewrite(text);
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml", "frames", "expected an integer"});

  text = dataset_yaml();
  text.replace(text.find("dt_scale: 16\n"), 13, "");
  rewrite(text);
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml", "missing key 'dt_scale'"});

  rewrite(dataset_yaml());
  fs::remove(fs::path(d.dir) / "character" / "character.yaml");
  expect_error([&] { read_dataset_info(d.dir); }, {"dataset.yaml", "character", "file not found"});

  std::ofstream(fs::path(d.dir) / "character" / "character.yaml") << "name: fake\n";
  fs::remove(fs::path(d.dir) / "cameras.yaml");
  expect_error([&] { read_dataset_info(d.dir); }, {"cameras.yaml", "file not found"});

  fs::remove(yaml);
  expect_error([&] { read_dataset_info(d.dir); }, {yaml, "cannot open"});
}

// ---------------------------------------------------------------------- samples

TEST(SyntheticDataset, SplitSizesAndIndexOrder) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  EXPECT_EQ(SyntheticDataset(d.dir).size(), 4 * 3);
  EXPECT_EQ(SyntheticDataset(d.dir, {"val"}).size(), 3);
  EXPECT_EQ(SyntheticDataset(d.dir, {"test"}).size(), 3);
  expect_error([&] { SyntheticDataset holdout(d.dir, {"holdout"}); }, {"dataset.yaml", "no split 'holdout'", "train"});

  const SyntheticDataset train(d.dir, {"train", 32});
  const Sample s = train.load(7);  // frame-major: frame index 2, view index 1
  EXPECT_EQ(s.frame, 2);
  EXPECT_EQ(s.view, "cam01");
  EXPECT_EQ(train.load(2, "cam01").index, 7);
  expect_error([&] { train.load(4, "cam00"); }, {"frame 4", "not in split 'train'"});
  expect_error([&] { train.load(12); }, {"index 12 out of range"});
}

TEST(SyntheticDataset, CropIsASquareHoldingTheWholeMask) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 40, 0.15});
  int padded = 0;
  for (int i = 0; i < train.size(); ++i) {
    const Sample s = train.load(i);
    const cv::Mat full = cv::imread(dataset_mask_path(train.info(), s.frame, s.view), cv::IMREAD_UNCHANGED);
    if (cv::countNonZero(full) == 0) continue;
    SCOPED_TRACE("frame " + std::to_string(s.frame) + " " + s.view);
    EXPECT_EQ(s.crop.source, CropSource::mask);
    ASSERT_EQ(s.mask.size(), cv::Size(40, 40));
    EXPECT_EQ(s.image.size(), cv::Size(40, 40));
    EXPECT_EQ(s.dt.size(), cv::Size(40, 40));
    const cv::Rect box = cv::boundingRect(full);
    EXPECT_LE(s.crop.left, box.x);
    EXPECT_LE(s.crop.top, box.y);
    EXPECT_GE(s.crop.left + s.crop.side, box.x + box.width);
    EXPECT_GE(s.crop.top + s.crop.side, box.y + box.height);
    EXPECT_EQ(s.crop.side, int(std::ceil(std::max(box.width, box.height) * 1.3 - 1e-9)));
    EXPECT_NEAR(s.crop.left + s.crop.side / 2.0, box.x + box.width / 2.0, 1.0);  // centred
    EXPECT_NEAR(s.crop.top + s.crop.side / 2.0, box.y + box.height / 2.0, 1.0);
    // The mask moved with the crop: its centroid lands where the crop map sends the full one.
    const cv::Moments mf = cv::moments(full, true), mc = cv::moments(s.mask, true);
    const Eigen::Vector2d expected = s.crop.to_crop({mf.m10 / mf.m00, mf.m01 / mf.m00});
    EXPECT_NEAR(mc.m10 / mc.m00, expected.x(), 0.25);
    EXPECT_NEAR(mc.m01 / mc.m00, expected.y(), 0.25);
    EXPECT_NEAR(mc.m00, mf.m00 * s.crop.scale * s.crop.scale, 0.1 * mf.m00 * s.crop.scale * s.crop.scale);
    double lo, hi;
    cv::minMaxLoc(s.mask, &lo, &hi);
    EXPECT_EQ(lo, 0);
    EXPECT_EQ(hi, 1);
    if (s.crop.left < 0) ++padded;
  }
  EXPECT_EQ(padded, 4);  // cam02's person stands at the border in every frame
}

TEST(SyntheticDataset, EmptyMaskFallsBackToKeypointsThenTheWholeImage) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const Sample s = SyntheticDataset(d.dir, {"train", 32}).load(3, "cam01");
  EXPECT_EQ(s.crop.source, CropSource::keypoints);
  EXPECT_EQ(cv::countNonZero(s.mask), 0);
  for (int k = 0; k < kBody25Count; ++k) {
    if (undetected(k)) continue;
    EXPECT_GE(s.keypoints(k, 0), -0.5);
    EXPECT_LT(s.keypoints(k, 0), 31.5);
    EXPECT_GE(s.keypoints(k, 1), -0.5);
    EXPECT_LT(s.keypoints(k, 1), 31.5);
  }
  const Sample w = SyntheticDataset(d.dir, {"val", 32}).load(4, "cam01");
  EXPECT_EQ(w.crop.source, CropSource::whole_image);
  EXPECT_EQ(w.crop.side, kWidth);
  EXPECT_TRUE((w.keypoints.array() == 0).all());
  // Nothing in the crop: the distance is the crop's diagonal everywhere.
  double lo, hi;
  cv::minMaxLoc(w.dt, &lo, &hi);
  EXPECT_NEAR(lo, 32 * std::sqrt(2.0), 1e-3);
  EXPECT_NEAR(hi, 32 * std::sqrt(2.0), 1e-3);
}

TEST(SyntheticDataset, CropCameraProjectsIntoTheCrop) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  for (int size : {20, 120}) {  // shrinking and growing
    const SyntheticDataset train(d.dir, {"train", size});
    for (int i = 0; i < train.size(); ++i) {
      const Sample s = train.load(i);
      EXPECT_EQ(s.crop_camera.width, size);
      EXPECT_EQ(s.crop_camera.height, size);
      EXPECT_EQ(s.crop_camera.R, s.camera.R);
      EXPECT_EQ(s.crop_camera.t, s.camera.t);
      EXPECT_EQ(s.crop_camera.dist, s.camera.dist);
      for (int k = 0; k < 20; ++k) {
        const Eigen::Vector3d X(0.3 * std::sin(k), 0.4 * std::cos(1.7 * k), 0.25 * std::sin(2.3 * k));
        const Eigen::Vector2d full = s.camera.project(X);
        const Eigen::Vector2d expected(s.crop.scale * (full.x() - s.crop.x0), s.crop.scale * (full.y() - s.crop.y0));
        EXPECT_LT((s.crop_camera.project(X) - expected).norm(), 1e-6);
      }
      // Keypoints moved like the camera: each lands on its joint's crop projection.
      for (int k = 0; k < kBody25Count; ++k) {
        if (undetected(k)) {
          EXPECT_EQ(s.keypoints.row(k), Eigen::RowVector3d::Zero().eval());
          continue;
        }
        if (s.frame == 4 && s.view == "cam01") continue;
        EXPECT_LT((s.keypoints.row(k).head<2>().transpose() - s.crop_camera.project(joint(k))).norm(), 1e-6);
        EXPECT_EQ(s.keypoints(k, 2), 0.5 + 0.02 * k);
      }
    }
  }
}

TEST(SyntheticDataset, ImagePixelsSitWhereTheCropMapSendsThem) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  for (int size : {20, 120}) {  // scale ≈ 0.4 and ≈ 2.4: a half-pixel slip would show
    DatasetOptions o{"train", size};
    o.normalize = false;
    const SyntheticDataset train(d.dir, o);
    for (int i = 0; i < train.size(); ++i) {
      const Sample s = train.load(i);
      if (s.crop.source != CropSource::mask) continue;
      SCOPED_TRACE("size " + std::to_string(size) + " frame " + std::to_string(s.frame) + " " + s.view);
      // The marker's green above the person's, centroid in the crop vs the mapped centre.
      double sw = 0, sx = 0, sy = 0;
      for (int y = 0; y < size; ++y)
        for (int x = 0; x < size; ++x) {
          const double w = std::max(0.0, s.image.at<cv::Vec3f>(y, x)[1] * 255.0 - kPerson[1]);
          sw += w, sx += w * x, sy += w * y;
        }
      const cv::Point2i m = marker_pixel(ellipse_centre(d.cameras[size_t(i % 3)], s.frame, i % 3));
      const Eigen::Vector2d expected = s.crop.to_crop({m.x, m.y});
      ASSERT_GT(sw, 0);
      EXPECT_NEAR(sx / sw, expected.x(), 0.1);
      EXPECT_NEAR(sy / sw, expected.y(), 0.1);
    }
  }
}

TEST(SyntheticDataset, NormalisesRgbWithImageNetStatistics) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 24});
  const Sample s = train.load(1, "cam02");  // at the border: background, person and padding
  ASSERT_EQ(s.image.type(), CV_32FC3);
  const cv::Mat full = cv::imread(dataset_image_path(train.info(), 1, "cam02"), cv::IMREAD_COLOR);
  std::set<std::vector<int>> colours_seen;
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 24; ++x) {
      cv::Vec3b bgr;
      if (!uniform_footprint(full, s.crop, x, y, bgr)) continue;
      colours_seen.insert({bgr[0], bgr[1], bgr[2]});
      const cv::Vec3f rgb = s.image.at<cv::Vec3f>(y, x);
      for (int c = 0; c < 3; ++c) EXPECT_NEAR(rgb[c], normalised(bgr[2 - c], c), 1e-5) << x << "," << y;
    }
  EXPECT_EQ(colours_seen.size(), 3u);  // background, person, black padding
  // One pixel written out: the person's centre, red channel (BGR 30 → R = 30/255).
  const cv::Point2i c = ellipse_centre(d.cameras[2], 1, 2);
  const Eigen::Vector2d at = s.crop.to_crop({c.x - 2, c.y - 4});
  EXPECT_NEAR(s.image.at<cv::Vec3f>(int(std::lround(at.y())), int(std::lround(at.x())))[0],
              (30 / 255.0 - 0.485) / 0.229, 1e-5);
}

TEST(SyntheticDataset, DistanceTransformIsInCropPixelsAlsoInThePadding) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 48});
  const Sample s = train.load(2, "cam02");
  ASSERT_LT(s.crop.left, 0);
  const cv::Mat full = cv::imread(dataset_mask_path(train.info(), 2, "cam02"), cv::IMREAD_UNCHANGED);
  std::vector<cv::Point> fg;
  cv::findNonZero(full, fg);
  int checked_padding = 0;
  for (int y = 0; y < 48; y += 3)
    for (int x = 0; x < 48; x += 3) {
      // Brute force: the distance from the pixel's full-image position to the person.
      const double u = s.crop.x0 + x / s.crop.scale, v = s.crop.y0 + y / s.crop.scale;
      double best = 1e9;
      for (const cv::Point& p : fg) best = std::min(best, std::hypot(p.x - u, p.y - v));
      EXPECT_NEAR(s.dt.at<float>(y, x), best * s.crop.scale, 1.0) << x << "," << y;
      if (s.mask.at<uint8_t>(y, x)) {
        EXPECT_LT(s.dt.at<float>(y, x), 1.0);
      }
      if (u < -0.5) ++checked_padding;
    }
  EXPECT_GT(checked_padding, 10);
}

TEST(SyntheticDataset, MissingOrBrokenFilesNameThePath) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 32});
  const std::string image = dataset_image_path(train.info(), 1, "cam00");
  fs::remove(image);
  expect_error([&] { train.load(1, "cam00"); }, {image, "not found"});
  std::ofstream(image) << "not a png";
  expect_error([&] { train.load(1, "cam00"); }, {image, "cannot read"});
  const std::string keypoints = dataset_keypoints_path(train.info(), 2, "cam01");
  std::ofstream(keypoints) << "{\"people\": 3}";
  expect_error([&] { train.load(2, "cam01"); }, {keypoints, "people"});
  const std::string mask = dataset_mask_path(train.info(), 0, "cam02");
  cv::imwrite(mask, cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)));
  expect_error([&] { train.load(0, "cam02"); }, {mask, "10x10", "expected 80x64"});
}

TEST(SyntheticDataset, CameraPerFrameNamesCamerasByViewAndFrame) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  std::vector<Camera> per_frame;
  for (int f = 0; f < kFrames; ++f)
    for (size_t v = 0; v < kViews.size(); ++v) {
      Camera c = look_at_camera(kViews[v] + "_000" + std::to_string(f), 0.4 * double(v) + 0.1 * f);
      per_frame.push_back(c);
    }
  write_cameras_yaml((fs::path(d.dir) / "cameras.yaml").string(), per_frame);
  std::string text = dataset_yaml();
  text.replace(text.find("camera_per_frame: false"), 23, "camera_per_frame: true");
  std::ofstream(fs::path(d.dir) / "dataset.yaml") << text;
  const SyntheticDataset train(d.dir, {"train", 32});
  EXPECT_EQ(train.camera(3, "cam02").name, "cam02_0003");
  EXPECT_EQ(train.load(3, "cam02").camera.R, per_frame[3 * 3 + 2].R);

  per_frame.erase(per_frame.begin() + 4);  // cam01_0001
  write_cameras_yaml((fs::path(d.dir) / "cameras.yaml").string(), per_frame);
  expect_error([&] { SyntheticDataset reopened(d.dir, {"train"}); }, {"cameras.yaml", "no camera 'cam01_0001'"});
}

// ---------------------------------------------------------------------- batches

TEST(SyntheticDatasetBatch, StacksSamplesAsNchwTensors) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 16});
  const std::vector<Sample> samples = {train.load(0), train.load(5)};
  const Batch b = make_batch(samples);
  EXPECT_EQ(b.images.shape(), (weft::Shape{2, 3, 16, 16}));
  EXPECT_EQ(b.keypoints.shape(), (weft::Shape{2, 25, 3}));
  EXPECT_EQ(b.masks.shape(), (weft::Shape{2, 1, 16, 16}));
  EXPECT_EQ(b.dt.shape(), (weft::Shape{2, 1, 16, 16}));
  EXPECT_EQ(b.indices, (std::vector<int>{0, 5}));
  for (int i = 0; i < 2; ++i)
    for (int y = 0; y < 16; y += 5)
      for (int x = 0; x < 16; x += 3) {
        for (int c = 0; c < 3; ++c)
          EXPECT_EQ(b.images.at({i, c, y, x}), samples[size_t(i)].image.at<cv::Vec3f>(y, x)[c]);
        EXPECT_EQ(b.masks.at({i, 0, y, x}), samples[size_t(i)].mask.at<uint8_t>(y, x));
        EXPECT_EQ(b.dt.at({i, 0, y, x}), samples[size_t(i)].dt.at<float>(y, x));
      }
  EXPECT_EQ(b.keypoints.at({1, 7, 0}), float(samples[1].keypoints(7, 0)));
  EXPECT_EQ(b.cameras[1].K, samples[1].crop_camera.K);
  expect_error([&] { make_batch({}); }, {"make_batch", "no samples"});
}

// ---------------------------------------------------------------------- prefetcher

namespace {

// The (epoch, index) stream of `batches` batches.
std::vector<std::pair<int64_t, int>> stream(const SyntheticDataset& data, PrefetchOptions o, int batches) {
  DatasetPrefetcher p(data, o);
  std::vector<std::pair<int64_t, int>> out;
  for (int k = 0; k < batches; ++k) {
    const Batch b = p.next();
    for (int i : b.indices) out.emplace_back(b.epoch, i);
  }
  return out;
}

}  // namespace

TEST(DatasetPrefetcher, OrderDependsOnSeedAloneNotOnThreads) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 16});
  PrefetchOptions o;
  o.batch_size = 5;  // 12 samples: batches of 5, 5, 2
  o.seed = 11;
  o.batches_ahead = 3;
  std::vector<std::pair<int64_t, int>> one_thread, two_threads, again, caller_only, more_loaders;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    o.loader_threads = 1;
    one_thread = stream(train, o, 7);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);  // caller + 1 loader
    o.loader_threads = 1;
    two_threads = stream(train, o, 7);
    again = stream(train, o, 7);
  }
  o.loader_threads = 0;  // everything on the calling thread
  caller_only = stream(train, o, 7);
  o.loader_threads = 3;  // more loaders than cores
  more_loaders = stream(train, o, 7);
  ASSERT_EQ(one_thread.size(), 12u * 2 + 5);
  EXPECT_EQ(one_thread, two_threads);
  EXPECT_EQ(two_threads, again);
  EXPECT_EQ(two_threads, caller_only);
  EXPECT_EQ(two_threads, more_loaders);

  // Every sample once per epoch, in a new order each epoch.
  std::vector<int> epoch0, epoch1;
  for (const auto& [e, i] : one_thread) (e == 0 ? epoch0 : epoch1).push_back(i);
  epoch1.resize(12);  // the first batch of epoch 2 is in the stream too
  std::vector<int> all(12);
  for (int i = 0; i < 12; ++i) all[size_t(i)] = i;
  for (const auto* e : {&epoch0, &epoch1}) {
    std::vector<int> sorted = *e;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(sorted, all);
  }
  EXPECT_NE(epoch0, epoch1);
  EXPECT_NE(epoch0, all);  // shuffled

  o.seed = 12;
  const auto other_seed = stream(train, o, 3);
  const std::vector<std::pair<int64_t, int>> first_epoch(one_thread.begin(), one_thread.begin() + 12);
  EXPECT_NE(first_epoch, other_seed);
}

TEST(DatasetPrefetcher, BatchesHoldTheSamplesTheyName) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 16});
  PrefetchOptions o;
  o.batch_size = 5;
  o.drop_last = true;
  DatasetPrefetcher p(train, o);
  EXPECT_EQ(p.batches_per_epoch(), 2);
  for (int k = 0; k < 3; ++k) {
    const Batch b = p.next();
    ASSERT_EQ(b.size(), 5);
    std::vector<Sample> direct;
    for (int i : b.indices) direct.push_back(train.load(i));
    const Batch expected = make_batch(direct);
    EXPECT_EQ(b.images.to_vector(), expected.images.to_vector());
    EXPECT_EQ(b.keypoints.to_vector(), expected.keypoints.to_vector());
    EXPECT_EQ(b.frames, expected.frames);
    EXPECT_EQ(b.views, expected.views);
    EXPECT_EQ(b.epoch, k / 2);
  }
}

// Data parallelism: the shards of batch k, in shard order, are batch k of the unsharded
// stream, cut at ⌊j·n/S⌋; batch_rows cuts a loaded batch the same way.
TEST(DatasetPrefetcher, ShardsOfABatchAreItsConsecutiveSlices) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 16});
  PrefetchOptions o;
  o.batch_size = 5;
  o.drop_last = true;
  DatasetPrefetcher whole(train, o);
  o.shards = 2;
  o.shard = 0;
  DatasetPrefetcher first(train, o);
  o.shard = 1;
  DatasetPrefetcher second(train, o);
  for (int k = 0; k < 3; ++k) {
    const Batch b = whole.next(), b0 = first.next(), b1 = second.next();
    ASSERT_EQ(b0.size(), 2);  // ⌊5/2⌋
    ASSERT_EQ(b1.size(), 3);
    EXPECT_EQ(b0.whole_size, 5);
    EXPECT_EQ(b1.whole_size, 5);
    std::vector<int> joined = b0.indices;
    joined.insert(joined.end(), b1.indices.begin(), b1.indices.end());
    EXPECT_EQ(joined, b.indices) << "batch " << k;
    const Batch tail = batch_rows(b, 2, 5);
    EXPECT_EQ(tail.indices, b1.indices);
    EXPECT_EQ(tail.images.to_vector(), b1.images.to_vector());
    EXPECT_EQ(tail.dt.to_vector(), b1.dt.to_vector());
  }
  o.shard = 2;
  EXPECT_THROW(DatasetPrefetcher(train, o), weft::Error);
  o.shard = 0;
  o.shards = 6;
  EXPECT_THROW(DatasetPrefetcher(train, o), weft::Error) << "6 shards of a batch of 5";
}

TEST(DatasetPrefetcher, LoaderErrorsSurfaceInNextWithThePath) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 16});
  const std::string image = dataset_image_path(train.info(), 2, "cam01");
  fs::remove(image);
  for (int threads : {0, 1, 2}) {
    PrefetchOptions o;
    o.batch_size = 4;
    o.loader_threads = threads;
    DatasetPrefetcher p(train, o);
    int errors = 0, samples = 0;
    for (int k = 0; k < p.batches_per_epoch(); ++k) {
      try {
        samples += p.next().size();
      } catch (const weft::Error& e) {
        ++errors;
        EXPECT_NE(std::string(e.what()).find(image), std::string::npos) << e.what();
      }
    }
    EXPECT_EQ(errors, 1);
    EXPECT_EQ(samples, 8);  // the other two batches of the epoch
  }
}

TEST(DatasetPrefetcher, StopsCleanlyWithBatchesInFlight) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  const SyntheticDataset train(d.dir, {"train", 16});
  PrefetchOptions o;
  o.batch_size = 2;
  o.batches_ahead = 4;
  o.loader_threads = 2;
  { DatasetPrefetcher untouched(train, o); }
  {
    DatasetPrefetcher p(train, o);
    EXPECT_EQ(p.next().size(), 2);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);  // no workers
    o.loader_threads = 1;
    DatasetPrefetcher p(train, o);
    EXPECT_EQ(p.next().size(), 2);
  }
  o.batch_size = 0;
  expect_error([&] { DatasetPrefetcher p(train, o); }, {"batch_size"});
}

// ---------------------------------------------------------------------- augmentation

TEST(DatasetAugmentation, JitteredCropsKeepCameraKeypointsAndImageTogether) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  DatasetOptions o{"train", 60};
  o.normalize = false;
  o.augmentation.shift = 0.15;
  o.augmentation.scale = 0.3;
  const SyntheticDataset train(d.dir, o);
  int moved = 0;
  for (int i = 0; i < train.size(); ++i)
    for (uint64_t seed : {1u, 2u, 3u}) {
      const Sample plain = train.load(i), s = train.load(i, seed);
      if (s.crop.source != CropSource::mask) continue;
      SCOPED_TRACE("sample " + std::to_string(i) + " seed " + std::to_string(seed));
      EXPECT_EQ(cv::norm(s.image, train.load(i, seed).image, cv::NORM_INF), 0);  // a seed is one draw
      if (s.crop.left != plain.crop.left || s.crop.side != plain.crop.side) ++moved;
      // The crop camera and the keypoints follow the crop.
      for (int k = 0; k < kBody25Count; ++k) {
        if (undetected(k)) continue;
        EXPECT_LT((s.keypoints.row(k).head<2>().transpose() - s.crop_camera.project(joint(k))).norm(), 1e-6);
      }
      // The image shows the marker where the crop map sends it (as for plain crops).
      double sw = 0, sx = 0, sy = 0;
      for (int y = 0; y < 60; ++y)
        for (int x = 0; x < 60; ++x) {
          const double w = std::max(0.0, s.image.at<cv::Vec3f>(y, x)[1] * 255.0 - kPerson[1]);
          sw += w, sx += w * x, sy += w * y;
        }
      const cv::Point2i m = marker_pixel(ellipse_centre(d.cameras[size_t(i % 3)], s.frame, i % 3));
      const Eigen::Vector2d expected = s.crop.to_crop({m.x, m.y});
      if (expected.minCoeff() < 2 || expected.maxCoeff() > 57) continue;  // jittered off the edge
      ASSERT_GT(sw, 0);
      EXPECT_NEAR(sx / sw, expected.x(), 0.25);
      EXPECT_NEAR(sy / sw, expected.y(), 0.25);
      // The mask moved with the image: the person's colour sits on the mask.
      EXPECT_EQ(s.mask.at<uint8_t>(int(std::lround(expected.y())), int(std::lround(expected.x()))), 1);
    }
  EXPECT_GT(moved, 10);
}

TEST(DatasetAugmentation, PhotosReplaceTheBackgroundOnlyAndColoursJitter) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  cv::Mat photo(50, 90, CV_8UC3, cv::Scalar(10, 200, 250));
  cv::imwrite(scratch.file("photo.png"), photo);
  DatasetOptions o{"train", 40};
  o.normalize = false;
  o.augmentation.backgrounds = scratch.file("photo.png");
  o.augmentation.background_probability = 1;
  const SyntheticDataset train(d.dir, o);
  const Sample plain = train.load(0), s = train.load(0, 5);
  ASSERT_EQ(s.crop.left, plain.crop.left);  // no crop jitter asked for
  int person = 0, back = 0;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) {
      const cv::Vec3f p = s.image.at<cv::Vec3f>(y, x), q = plain.image.at<cv::Vec3f>(y, x);
      if (plain.mask.at<uint8_t>(y, x) && cv::norm(q - cv::Vec3f(kPerson[2], kPerson[1], kPerson[0]) / 255.f) < 1e-3) {
        EXPECT_LT(cv::norm(p - q), 1e-5) << "the person is kept";
        ++person;
      } else if (!plain.mask.at<uint8_t>(y, x) && cv::norm(q - cv::Vec3f(kBackground[2], kBackground[1], kBackground[0]) / 255.f) < 1e-3) {
        // RGB of the photo's BGR (10, 200, 250).
        EXPECT_LT(cv::norm(p - cv::Vec3f(250, 200, 10) / 255.f), 1e-3) << "the studio's background is replaced";
        ++back;
      }
    }
  EXPECT_GT(person, 20);
  EXPECT_GT(back, 20);

  // Colour jitter: brightness scales, then clamps to [0, 1].
  AugmentationDraw draw;
  draw.brightness = 1.5;
  cv::Mat rgb(2, 2, CV_32FC3, cv::Scalar(0.2, 0.5, 0.8));
  jitter_colours(rgb, draw);
  const cv::Vec3f v = rgb.at<cv::Vec3f>(0, 0);
  EXPECT_NEAR(v[0], 0.3, 1e-6);
  EXPECT_NEAR(v[1], 0.75, 1e-6);
  EXPECT_NEAR(v[2], 1.0, 1e-6);
  draw = AugmentationDraw();
  draw.saturation = 0;  // grey
  jitter_colours(rgb, draw);
  EXPECT_NEAR(rgb.at<cv::Vec3f>(1, 1)[0], rgb.at<cv::Vec3f>(1, 1)[2], 1e-6);
}

namespace {
// Largest difference between sample i of batch a and sample j of batch b (their images).
double image_difference(const Batch& a, int i, const Batch& b, int j) {
  const int64_t n = a.images.numel() / a.size();
  const float* p = a.images.data<float>() + i * n;
  const float* q = b.images.data<float>() + j * n;
  double worst = 0;
  for (int64_t k = 0; k < n; ++k) worst = std::max(worst, double(std::abs(p[k] - q[k])));
  return worst;
}
}  // namespace

TEST(DatasetAugmentation, ThePrefetcherAugmentsPerEpochAndResumesExactly) {
  ScratchDir scratch("dataset");
  const FakeDataset d = write_dataset(scratch);
  DatasetOptions o{"train", 32};
  o.augmentation.shift = 0.1;
  o.augmentation.brightness = 0.3;
  const SyntheticDataset train(d.dir, o);
  PrefetchOptions p;
  p.batch_size = 4;
  p.seed = 9;
  p.loader_threads = 0;
  std::vector<Batch> stream;
  {
    DatasetPrefetcher all(train, p);
    for (int k = 0; k < 9; ++k) stream.push_back(all.next());
  }
  // Batch 5 onward again from a fresh prefetcher (a resumed run): the same tensors.
  p.first_batch = 5;
  DatasetPrefetcher resumed(train, p);
  for (int k = 5; k < 9; ++k) {
    const Batch b = resumed.next();
    ASSERT_EQ(b.indices, stream[size_t(k)].indices);
    for (int i = 0; i < b.size(); ++i) EXPECT_EQ(image_difference(b, i, stream[size_t(k)], i), 0.0) << "batch " << k;
  }
  // One sample in two epochs: two different draws.
  const int per_epoch = resumed.batches_per_epoch();
  ASSERT_LT(2 * per_epoch, 9);
  bool differs = false;
  for (int i = 0; i < 4 && !differs; ++i)
    for (int j = 0; j < 4; ++j)
      if (stream[0].indices[size_t(i)] == stream[size_t(per_epoch)].indices[size_t(j)])
        differs = image_difference(stream[0], i, stream[size_t(per_epoch)], j) > 0;
  EXPECT_TRUE(differs);
}

TEST(DatasetAugmentation, ConfigErrorsNameTheKey) {
  const StrictYaml y{"aug.yaml", "."};
  auto parse = [&](const std::string& text) { return parse_augmentation(y, y.parse(text), "augmentation"); };
  const AugmentationOptions a = parse("{shift: 0.1, scale: 0.2, brightness: 0.3, contrast: 0.1, saturation: 0.2}");
  EXPECT_DOUBLE_EQ(a.scale, 0.2);
  EXPECT_TRUE(a.enabled());
  EXPECT_FALSE(AugmentationOptions().enabled());
  expect_error([&] { parse("{shfit: 0.1}"); }, {"aug.yaml", "augmentation.shfit", "unknown key"});
  expect_error([&] { parse("{shift: 0.9}"); }, {"aug.yaml", "augmentation.shift"});
  expect_error([&] { parse("{background_probability: 0.5}"); }, {"augmentation.background_probability", "backgrounds"});
  expect_error([&] { parse("{backgrounds: /nonexistent/photos, background_probability: 0.5}"); },
               {"aug.yaml", "augmentation.backgrounds", "/nonexistent/photos"});
}
