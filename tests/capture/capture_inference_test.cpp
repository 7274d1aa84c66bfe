// The pieces of `weft infer` that need no trained model: the temporal filter, green-screen
// keying, frame sources and per-frame files, the capture config, and the BVH export of a
// Skeletool skeleton's motion.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "capture/character/skeletool_io.h"
#include "capture/inference/capture_config.h"
#include "capture/inference/frame_source.h"
#include "capture/inference/green_screen.h"
#include "capture/inference/sequence_input.h"
#include "capture/io/camera.h"
#include "capture/inference/temporal_filter.h"
#include "capture/motion/skeleton_bvh.h"
#include "capture/render/renderer.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::ScratchDir;

TEST(TemporalFilter, KeepsConstantsAndLinesAndAveragesAnImpulseWithGaussianWeights) {
  const std::vector<int> ids = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  Eigen::MatrixXd x(9, 2);
  for (int i = 0; i < 9; ++i) x(i, 0) = 3.0, x(i, 1) = 0.0;
  x(4, 1) = 1.0;
  const Eigen::MatrixXd y = gaussian_filter_frames(x, ids, 1.0, 2);
  for (int i = 0; i < 9; ++i) EXPECT_NEAR(y(i, 0), 3.0, 1e-12);
  // The impulse spreads with weights exp(−k²/2) / Σ_{|k|≤2} exp(−k²/2).
  const double norm = 1 + 2 * std::exp(-0.5) + 2 * std::exp(-2.0);
  EXPECT_NEAR(y(4, 1), 1 / norm, 1e-12);
  EXPECT_NEAR(y(3, 1), std::exp(-0.5) / norm, 1e-12);
  EXPECT_NEAR(y(2, 1), std::exp(-2.0) / norm, 1e-12);
  EXPECT_NEAR(y(1, 1), 0.0, 1e-12);
  // A linear ramp stays a ramp away from the ends (symmetric window).
  Eigen::MatrixXd ramp(9, 1);
  for (int i = 0; i < 9; ++i) ramp(i, 0) = 2.0 * i;
  const Eigen::MatrixXd r = gaussian_filter_frames(ramp, ids, 1.0, 2);
  for (int i = 2; i < 7; ++i) EXPECT_NEAR(r(i, 0), 2.0 * i, 1e-12);
  // sigma 0: unchanged.
  EXPECT_EQ(gaussian_filter_frames(x, ids, 0.0, 2), x);
}

TEST(TemporalFilter, DoesNotAverageAcrossAGapInFrameIds) {
  const std::vector<int> ids = {0, 1, 2, 10, 11, 12};
  Eigen::MatrixXd x(6, 1);
  x << 0, 0, 0, 5, 5, 5;
  const Eigen::MatrixXd y = gaussian_filter_frames(x, ids, 1.5, 2);
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(y(i, 0), 0.0, 1e-12);
  for (int i = 3; i < 6; ++i) EXPECT_NEAR(y(i, 0), 5.0, 1e-12);
  expect_error([&] { gaussian_filter_frames(x, {0, 1}, 1.0, 2); }, {"2 frame ids"});
}

TEST(GreenScreen, KeysTheRenderedGreenBackgroundAndKeepsThePerson) {
  // A person-coloured disc and a red rectangle over the renderer's chroma green, plus a
  // speck of noise that the opening removes.
  cv::Mat image(120, 160, CV_8UC3, Background().color);
  cv::circle(image, {60, 60}, 25, cv::Scalar(140, 170, 220), cv::FILLED);
  cv::rectangle(image, cv::Rect(70, 70, 30, 40), cv::Scalar(40, 40, 200), cv::FILLED);
  cv::Mat truth = cv::Mat::zeros(image.size(), CV_8UC1);
  cv::circle(truth, {60, 60}, 25, 255, cv::FILLED);
  cv::rectangle(truth, cv::Rect(70, 70, 30, 40), 255, cv::FILLED);
  image.at<cv::Vec3b>(10, 150) = cv::Vec3b(200, 200, 200);
  const cv::Mat mask = key_green_screen(image, KeyingConfig());
  ASSERT_EQ(mask.size(), image.size());
  EXPECT_GT(mask_iou(mask, truth), 0.97);
  EXPECT_EQ(mask.at<uint8_t>(10, 150), 0);  // the speck is gone
  // A second region away from the person is dropped when only the largest is kept.
  cv::rectangle(image, cv::Rect(130, 5, 20, 20), cv::Scalar(40, 40, 200), cv::FILLED);
  EXPECT_EQ(key_green_screen(image, KeyingConfig()).at<uint8_t>(15, 140), 0);
  KeyingConfig all;
  all.largest_component = false;
  EXPECT_EQ(key_green_screen(image, all).at<uint8_t>(15, 140), 255);
}

TEST(FrameSource, ReadsAnImageFolderInNameOrderWithNumberedIds) {
  ScratchDir dir("frames");
  for (int id : {12, 3, 7}) {
    char name[32];
    std::snprintf(name, sizeof(name), "%04d.png", id);
    cv::imwrite(dir.file(name), cv::Mat(8, 10, CV_8UC3, cv::Scalar(id, 0, 0)));
  }
  FrameSource source(dir.file(""));
  EXPECT_FALSE(source.is_video());
  EXPECT_EQ(source.size(), 3);
  std::vector<int> ids;
  InputFrame f;
  while (source.next(f)) {
    ids.push_back(f.id);
    EXPECT_EQ(f.bgr.at<cv::Vec3b>(0, 0)[0], f.id);
  }
  EXPECT_EQ(ids, (std::vector<int>{3, 7, 12}));
  source.rewind();
  ASSERT_TRUE(source.next(f));
  EXPECT_EQ(f.name, "0003");

  // Per-frame files by name, and by number for OpenPose's video naming.
  ScratchDir kp("keypoints");
  kp.write("0007_keypoints.json", "{}");
  kp.write("clip_000000000012_keypoints.json", "{}");
  const FrameFiles files(kp.file(""), "_keypoints.json");
  InputFrame seven{7, "0007", {}}, twelve{12, "0012", {}}, three{3, "0003", {}};
  EXPECT_EQ(files.find(seven), kp.file("0007_keypoints.json"));
  EXPECT_EQ(files.find(twelve), kp.file("clip_000000000012_keypoints.json"));
  EXPECT_EQ(files.find(three), "");
}

TEST(FrameSource, BadInputsNameThePath) {
  ScratchDir dir("bad_frames");
  expect_error([&] { FrameSource s(dir.file("missing.mp4")); }, {"missing.mp4", "not found"});
  expect_error([&] { FrameSource s(dir.file("")); }, {"no images"});
  const std::string fake = dir.write("clip.mp4", "this is not a video");
  expect_error([&] { FrameSource s(fake); }, {"clip.mp4", "cannot be opened as a video"});
  dir.write("broken.png", "not a png");
  expect_error(
      [&] {
        FrameSource s(dir.file(""));
        InputFrame f;
        s.next(f);
      },
      {"broken.png", "cannot be read"});
  expect_error([&] { FrameFiles f(dir.file("nothing"), ".png"); }, {"nothing", "not found"});
}

TEST(CaptureConfig, ReadsTheDefaultsFileAndNamesBadKeys) {
  const CaptureConfig c = load_capture_config(weft::capture::testing::repo_file("configs/infer/default.yaml"));
  EXPECT_EQ(c.filter_radius_frames, 2);
  EXPECT_DOUBLE_EQ(c.filter_sigma_frames, 1.0);
  EXPECT_EQ(c.mesh_formats, (std::vector<std::string>{"ply", "obj"}));
  expect_error([] { parse_capture_config("filter: {sigma: 1}\n", "x.yaml"); }, {"x.yaml", "filter.sigma"});
  expect_error([] { parse_capture_config("output: {meshes: [stl]}\n", "x.yaml"); }, {"output.meshes", "stl"});
  expect_error([] { parse_capture_config("keying: {hue_min: 90, hue_max: 40}\n", "x.yaml"); }, {"keying.hue_min"});
  expect_error([] { parse_capture_config("batch_size: 0\n", "x.yaml"); }, {"batch_size"});
  // The fit to the detections is on by default, with the setting chosen on the held-out
  // tuning clip (docs/RESULTS.md); the file and the built-in defaults agree.
  const CaptureConfig built_in = parse_capture_config("batch_size: 8\n", "b.yaml");
  for (const CaptureConfig* d : {&c, &built_in}) {
    EXPECT_EQ(d->refine.iterations, 300);
    EXPECT_DOUBLE_EQ(d->refine.prior, 1e-4);
    EXPECT_DOUBLE_EQ(d->refine.lr, 0.05);
    EXPECT_DOUBLE_EQ(d->refine.depth_prior, 10);
  }
  const CaptureConfig r = parse_capture_config("refine: {iterations: 0, prior: 1.0e-3, depth_prior: 0}\n", "r.yaml");
  EXPECT_EQ(r.refine.iterations, 0) << "off: the network's output as it is";
  EXPECT_DOUBLE_EQ(r.refine.prior, 1e-3);
  EXPECT_DOUBLE_EQ(r.refine.depth_prior, 0);
  EXPECT_DOUBLE_EQ(r.refine.lr, 0.05);
  expect_error([] { parse_capture_config("refine: {steps: 3}\n", "x.yaml"); }, {"x.yaml", "refine.steps"});
  expect_error([] { parse_capture_config("refine: {lr: -1}\n", "x.yaml"); }, {"x.yaml", "refine.lr"});
}

namespace {

// A root chain (3 prismatic + 3 revolute at zero offset), a spine with a zero-offset
// chain, and two branches; dofs drive every joint with weight 1.
Skeleton branching_skeleton() {
  const char* joints[][10] = {
      {"root_tx", "prismatic", "none", "0", "0.9", "0", "1", "0", "0", "1"},
      {"root_ty", "prismatic", "root_tx", "0", "0", "0", "0", "1", "0", "1"},
      {"root_tz", "prismatic", "root_ty", "0", "0", "0", "0", "0", "1", "1"},
      {"root_rx", "revolute", "root_tz", "0", "0", "0", "1", "0", "0", "1"},
      {"root_ry", "revolute", "root_rx", "0", "0", "0", "0", "1", "0", "1"},
      {"root", "revolute", "root_ry", "0", "0", "0", "0", "0", "1", "1"},
      {"spine_rx", "revolute", "root", "0", "0.2", "0", "1", "0", "0", "1"},
      {"spine", "revolute", "spine_rx", "0", "0", "0", "0", "1", "0", "1"},
      {"l_arm", "revolute", "spine", "0.2", "0.3", "0", "0", "0", "1", "1"},
      {"r_arm", "revolute", "spine", "-0.2", "0.3", "0", "0", "0", "1", "1"},
      {"l_hand", "revolute", "l_arm", "0.25", "0", "0", "1", "0", "0", "1"},
  };
  std::string text = "Skeletool Skeleton Definition V1.0\njoints: 11\n";
  for (const auto& j : joints) {
    text += " ";
    for (const char* f : j) text += std::string(" ") + f;
    text += "\n";
  }
  text += "markers: 0\ndofs: 11\n";
  for (const auto& j : joints) text += std::string("  ") + j[0] + " 1\n    nolimits\n    " + j[0] + " 1\n";
  return parse_skeleton(text, "branching.skeleton");
}

}  // namespace

TEST(SkeletonBvh, ReproducesTheChainEndsOfEveryFrame) {
  const Skeleton s = branching_skeleton();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  std::vector<Transforms> globals;
  for (int f = 0; f < 12; ++f) {
    Eigen::VectorXd dofs(s.num_dofs());
    for (int d = 0; d < s.num_dofs(); ++d) dofs(d) = u(rng);
    globals.push_back(forward_kinematics(s, dofs));
  }
  std::vector<int> bvh_of;
  const BvhMotion m = skeleton_motion_bvh(s, globals, 1.0 / 30, &bvh_of);
  // root_tx … root → "root", spine_rx, spine → "spine", and the three branches.
  ASSERT_EQ(m.joints.size(), 5u);
  EXPECT_EQ(m.joints[0].name, "root");
  EXPECT_EQ(m.joints[1].name, "spine");
  EXPECT_EQ(m.joints[0].channels.size(), 6u);  // the root moves
  EXPECT_EQ(m.joints[1].channels.size(), 3u);
  // Written and read back, the BVH poses its joints where the chain ends are.
  const BvhMotion back = parse_bvh(format_bvh(m), "export.bvh");
  ASSERT_EQ(back.num_frames(), 12);
  for (int f = 0; f < 12; ++f) {
    const BvhTransforms G = bvh_global_transforms(back, f);
    for (const BvhJoint& j : back.joints) {
      if (j.end_site) continue;
      const int k = s.joint_index(j.name);
      ASSERT_GE(k, 0) << j.name;
      const int b = &j - &back.joints[0];
      EXPECT_LT((G[size_t(b)].translation() - globals[size_t(f)][size_t(k)].translation()).norm(), 1e-7) << j.name;
      EXPECT_LT((G[size_t(b)].linear() - globals[size_t(f)][size_t(k)].linear()).norm(), 1e-7) << j.name;
    }
  }
  // Euler angles are unwrapped: a slow spin never jumps by more than a few degrees.
  std::vector<Transforms> spin;
  for (int f = 0; f < 200; ++f) {
    Eigen::VectorXd dofs = Eigen::VectorXd::Zero(s.num_dofs());
    dofs(5) = 0.05 * f;  // root about z, past ±π
    dofs(4) = 0.3;
    spin.push_back(forward_kinematics(s, dofs));
  }
  const BvhMotion sm = skeleton_motion_bvh(s, spin, 1.0 / 30);
  for (int f = 1; f < 200; ++f)
    for (int c = 3; c < 6; ++c) EXPECT_LT(std::abs(sm.frames(f, c) - sm.frames(f - 1, c)), 10.0) << f << " " << c;
}

TEST(SequenceInput, TakesMasksAndKeypointsFromFoldersElseTheDetectorElseKeying) {
  ScratchDir frames("frames"), masks("masks"), out("cameras");
  for (int id : {0, 1}) {
    char name[32];
    std::snprintf(name, sizeof(name), "%04d.png", id);
    cv::imwrite(frames.file(name), cv::Mat(40, 48, CV_8UC3, cv::Scalar(40, 180, 40)));
    cv::Mat m = cv::Mat::zeros(40, 48, CV_8UC1);
    cv::rectangle(m, cv::Rect(10, 5, 8, 20), cv::Scalar(255), cv::FILLED);
    cv::imwrite(masks.file(name), m);
  }
  Camera cam;
  cam.name = "cam";
  cam.K << 50, 0, 24, 0, 50, 20, 0, 0, 1;
  cam.width = 48;
  cam.height = 40;
  write_cameras_yaml(out.file("cameras.yaml"), {cam});
  DetectorConfig dc;
  dc.enabled = true;
  dc.input_size = 32;
  dc.width = 4;
  PersonDetector detector(dc, 3);
  {
    // No folders, no detector: keying, no detections (as before the detector existed).
    SequenceInput in({frames.file(""), out.file("cameras.yaml"), "", "", "", KeyingConfig{}});
    EXPECT_EQ(in.masks_from(), InputSource::keying);
    EXPECT_EQ(in.keypoints_from(), InputSource::none);
  }
  {
    // A detector and no folders: both from the detector, a mask of the frame's size.
    SequenceInput in({frames.file(""), out.file("cameras.yaml"), "", "", "", KeyingConfig{}, &detector});
    EXPECT_EQ(in.masks_from(), InputSource::detector);
    EXPECT_EQ(in.keypoints_from(), InputSource::detector);
    EXPECT_NE(in.describe().find("person detector"), std::string::npos) << in.describe();
    SequenceFrame f;
    ASSERT_TRUE(in.next(f));
    EXPECT_EQ(f.mask.size(), cv::Size(48, 40));
    EXPECT_EQ(f.mask.type(), CV_8UC1);
  }
  {
    // A mask folder overrides the detector's masks; the keypoints still come from it.
    SequenceInput in({frames.file(""), out.file("cameras.yaml"), "", masks.file(""), "", KeyingConfig{}, &detector});
    EXPECT_EQ(in.masks_from(), InputSource::folder);
    EXPECT_EQ(in.keypoints_from(), InputSource::detector);
    SequenceFrame f;
    ASSERT_TRUE(in.next(f));
    EXPECT_EQ(cv::countNonZero(f.mask), 8 * 20);
  }
  EXPECT_STREQ(input_source_name(InputSource::detector), "detector");
  EXPECT_STREQ(input_source_name(InputSource::keying), "keying");
}
