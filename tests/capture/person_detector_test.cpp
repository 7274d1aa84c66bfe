// The person detector (capture/detection/): its heatmap codec in both directions
// (known answers and a round trip), the mask threshold and its placement in the frame, the
// pixel shuffle, the network's output shapes, and the error a model without a detector
// gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "capture/detection/keypoint_heatmaps.h"
#include "capture/detection/person_detection.h"
#include "capture/detection/person_detector.h"
#include "capture/model/capture_networks.h"
#include "capture/render/detection_drawing.h"
#include "capture/render/photos.h"
#include "capture/studio/scene_dressing.h"
#include "capture/studio/synthetic_studio.h"
#include "capture/training/training_config.h"
#include "graph/autograd.h"
#include "tests/capture/stick_figure.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;

namespace {

HeatmapCodec codec_64() {
  HeatmapCodec c;
  c.input_size = 64;
  c.stride = 4;
  c.sigma_px = 3;
  return c;
}

}  // namespace

TEST(KeypointHeatmaps, ACellsPeakDecodesToItsCentre) {
  // One heatmap with a single peak at row 5, column 9 (and nothing on either side): the
  // cell's centre, u = 4 (9 + ½) − ½ = 37.5, v = 4 (5 + ½) − ½ = 21.5, confidence 0.8.
  const HeatmapCodec c = codec_64();
  Tensor hm = Tensor::zeros({2, kBody25Count, 16, 16});
  hm.data<float>()[(1 * kBody25Count + 4) * 256 + 5 * 16 + 9] = 0.8f;
  hm.data<float>()[(1 * kBody25Count + 6) * 256 + 3 * 16 + 2] = 0.05f;  // below min_confidence
  const Body25 k = decode_heatmaps(hm, 1, c);
  EXPECT_DOUBLE_EQ(k(4, 0), 37.5);
  EXPECT_DOUBLE_EQ(k(4, 1), 21.5);
  EXPECT_FLOAT_EQ(float(k(4, 2)), 0.8f);
  // Undetected as OpenPose writes it: 0, 0, 0.
  EXPECT_EQ(k.row(6), Eigen::RowVector3d::Zero());
  EXPECT_EQ(k.row(0), Eigen::RowVector3d::Zero());
  // Confidences are clamped to 1.
  hm.data<float>()[(1 * kBody25Count + 4) * 256 + 5 * 16 + 9] = 1.7f;
  EXPECT_DOUBLE_EQ(decode_heatmaps(hm, 1, c)(4, 2), 1.0);
}

TEST(KeypointHeatmaps, EncodeThenDecodeGivesTheKeypointBack) {
  const HeatmapCodec c = codec_64();
  Tensor kp = Tensor::zeros({1, kBody25Count, 3});
  float* p = kp.data<float>();
  for (int m = 0; m < kBody25Count; ++m) {
    if (m == 7) continue;  // undetected: weight 0, an empty plane
    p[3 * m] = float(6.3 + 2.1 * m);
    p[3 * m + 1] = float(50.8 - 1.7 * m);
    p[3 * m + 2] = float(0.5 + 0.02 * m);
  }
  const HeatmapTargets t = encode_heatmaps(kp, c);
  ASSERT_EQ(t.heatmaps.shape(), (Shape{1, kBody25Count, 16, 16}));
  EXPECT_FLOAT_EQ(t.weights.data<float>()[3], 0.56f);
  EXPECT_EQ(t.weights.data<float>()[7], 0.0f);
  // The target's value at a cell: exp(−d² / 2σ²) of the cell centre's distance d.
  const double du = c.cell_u(2) - 6.3, dv = c.cell_v(12) - 50.8;
  EXPECT_NEAR(t.heatmaps.data<float>()[12 * 16 + 2], std::exp(-(du * du + dv * dv) / 18), 1e-6);
  const Body25 k = decode_heatmaps(t.heatmaps, 0, c);
  for (int m = 0; m < kBody25Count; ++m) {
    if (m == 7) {
      EXPECT_EQ(k.row(m), Eigen::RowVector3d::Zero());
      continue;
    }
    // The log-parabola is exact for a Gaussian: float32 rounding is all that is left.
    EXPECT_NEAR(k(m, 0), p[3 * m], 2e-3) << m;
    EXPECT_NEAR(k(m, 1), p[3 * m + 1], 2e-3) << m;
    EXPECT_GT(k(m, 2), 0.7) << m;  // the peak of a Gaussian sampled within a cell of it
  }
}

TEST(KeypointHeatmaps, MaskLogitsThresholdAtTheGivenProbability) {
  // Logits on a 2×2 grid over a 4×4 crop: cell centres at pixels 0.5 and 2.5.
  Tensor z = Tensor::from_data({1, 1, 2, 2}, std::vector<float>{-2.f, 2.f, 0.5f, -0.5f});
  const cv::Mat crop = mask_logits_in_crop(z, 0, 4);
  ASSERT_EQ(crop.size(), cv::Size(4, 4));
  // Bilinear between the cell centres: pixel (1, 0) lies ¼ of the way from −2 to 2.
  EXPECT_FLOAT_EQ(crop.at<float>(0, 1), -1.0f);
  EXPECT_FLOAT_EQ(crop.at<float>(0, 0), -2.0f);  // beyond the first centre: the border value
  const cv::Mat half = threshold_mask(crop, 0.5);
  EXPECT_EQ(half.type(), CV_8UC1);
  EXPECT_EQ(half.at<uint8_t>(0, 3), 255);  // logit 2
  EXPECT_EQ(half.at<uint8_t>(0, 0), 0);    // logit −2
  EXPECT_EQ(half.at<uint8_t>(3, 0), 255);  // logit 0.5 > logit(0.5) = 0
  // At probability 0.7 (logit 0.847) the 0.5 cell is background.
  EXPECT_EQ(threshold_mask(crop, 0.7).at<uint8_t>(3, 0), 0);
  EXPECT_EQ(threshold_mask(crop, 0.7).at<uint8_t>(0, 3), 255);
  expect_error([&] { threshold_mask(crop, 1.0); }, {"threshold"});
}

TEST(PersonDetection, ACropsMaskLandsWhereTheCropCameFrom) {
  // A crop of side 40 at (10, 20) of a 64×48 frame, read at 20² (scale ½): crop pixel
  // (u', v') is frame pixel (2u' + ½ + 10 − ½ ... ) = u'/scale + x0.
  const cv::Mat mask = cv::Mat::zeros(48, 64, CV_8UC1);
  cv::Mat box = mask.clone();
  cv::rectangle(box, cv::Rect(20, 30, 12, 8), cv::Scalar(255), cv::FILLED);
  const CropWindow crop = choose_crop(box, Body25::Zero(), 20, 0.0);
  // The crop's own logits: +5 inside the box, −5 outside, at crop resolution.
  cv::Mat logits(20, 20, CV_32FC1, cv::Scalar(-5.0f));
  for (int v = 0; v < 20; ++v)
    for (int u = 0; u < 20; ++u) {
      const double x = u / crop.scale + crop.x0, y = v / crop.scale + crop.y0;
      if (x >= 20 && x < 32 && y >= 30 && y < 38) logits.at<float>(v, u) = 5.0f;
    }
  const cv::Mat frame = crop_mask_in_frame(logits, crop, 64, 48);
  ASSERT_EQ(frame.size(), cv::Size(64, 48));
  cv::Mat both, either;
  cv::bitwise_and(frame, box, both);
  cv::bitwise_or(frame, box, either);
  EXPECT_GT(cv::countNonZero(both) / double(cv::countNonZero(either)), 0.8);
  EXPECT_EQ(frame.at<uint8_t>(5, 5), 0);  // outside the crop: background
  // The largest region alone.
  cv::Mat two = box.clone();
  cv::rectangle(two, cv::Rect(0, 0, 3, 3), cv::Scalar(255), cv::FILLED);
  EXPECT_EQ(cv::countNonZero(largest_region(two)), 12 * 8);
  EXPECT_EQ(cv::countNonZero(largest_region(mask)), 0);
}

TEST(PersonDetector, PixelShuffleMovesChannelsToSpace) {
  std::vector<float> v(2 * 8 * 2 * 3);
  for (size_t i = 0; i < v.size(); ++i) v[i] = float(i);
  const Tensor x = Tensor::from_data({2, 8, 2, 3}, v);  // [B, 4C, H, W], C = 2
  const Tensor y = pixel_shuffle2(x);
  ASSERT_EQ(y.shape(), (Shape{2, 2, 4, 6}));
  // out[b, c, 2i + di, 2j + dj] = in[b, 4c + 2di + dj, i, j]
  for (int b = 0; b < 2; ++b)
    for (int c = 0; c < 2; ++c)
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 3; ++j)
          for (int di = 0; di < 2; ++di)
            for (int dj = 0; dj < 2; ++dj)
              EXPECT_EQ(y.data<float>()[((b * 2 + c) * 4 + 2 * i + di) * 6 + 2 * j + dj],
                        x.data<float>()[((b * 8 + 4 * c + 2 * di + dj) * 2 + i) * 3 + j]);
}

TEST(PersonDetector, OutputsHeatmapsAtAQuarterAndTheMaskAtHalfTheCrop) {
  DetectorConfig c;
  c.enabled = true;
  c.input_size = 32;
  c.width = 4;
  PersonDetector net(c, 1);
  NoGradGuard no_grad;
  const DetectorOutput out = net.run(Tensor::zeros({2, 3, 32, 32}));
  EXPECT_EQ(out.heatmaps.shape(), (Shape{2, kBody25Count, 8, 8}));
  EXPECT_EQ(out.mask_logits.shape(), (Shape{2, 1, 16, 16}));
  expect_error([&] { net.run(Tensor::zeros({1, 3, 64, 64})); }, {"PersonDetector", "[1, 3, 64, 64]"});
  // On whole frames of any size: a mask of the frame's size.
  const std::vector<PersonDetection> d = detect_people(net, {cv::Mat(50, 70, CV_8UC3, cv::Scalar(0, 200, 0))});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].mask.size(), cv::Size(70, 50));
  EXPECT_TRUE(net.is_training());  // the caller's mode is restored
}

TEST(PersonDetector, AModelWithoutADetectorSaysWhatToRetrain) {
  // Any character will do: the networks' sizes are all the check needs.
  Character ch;
  ch.skeleton = weft::capture::testing::stick_figure_skeleton();
  ch.rest_dofs = Eigen::VectorXd::Zero(ch.skeleton.num_dofs());
  ch.body.graph.nodes = Vertices::Zero(4, 3);
  NetworkConfig n;
  n.input_size = 32;
  CaptureNetworks without(ch, n, 0);
  EXPECT_EQ(without.detector, nullptr);
  expect_error([&] { without.require_detector("runs/old"); },
               {"runs/old", "no person detector", "network.detector", "stages.detector.steps", "--init", "default_detector.yaml", "--keypoints", "--masks"});
  n.detector.enabled = true;
  n.detector.input_size = 32;
  n.detector.width = 4;
  CaptureNetworks with(ch, n, 0);
  EXPECT_EQ(&with.require_detector("runs/new"), with.detector.get());
  bool named = false;
  for (const auto& p : with.named_parameters()) named |= p.name.rfind("detector.stem_conv.weight", 0) == 0;
  EXPECT_TRUE(named);
}

TEST(PersonDetector, TheWildSequencesPhotosAreInNoTrainingShare) {
  REQUIRE_DEBIAN_FILE("/usr/share/backgrounds/mate/nature/GreenMeadow.jpg", "mate-backgrounds");
  // The photos the in-the-wild sequence over photographs draws (one per clip of its one
  // view), and the training share of every shipped config that trains the detector.
  const SynthConfig wild = load_synth_config(weft::capture::testing::repo_file("configs/synth/in_the_wild_photos.yaml"));
  std::vector<std::string> drawn;
  for (size_t k = 0; k < wild.motions.size(); ++k)
    drawn.push_back(std::filesystem::path(wild.render.photos.at(
                                              photo_background_index(wild.render.photos.size(), wild.seed, int(k), 0)))
                        .filename()
                        .string());
  ASSERT_FALSE(drawn.empty());
  int configs = 0;
  for (const char* name : {"tiny", "default", "default_arap_only", "demo", "paper", "default_detector"}) {
    const TrainingConfig c = load_training_config(weft::capture::testing::repo_file(std::string("configs/train/") + name + ".yaml"));
    if (c.stages[3].steps == 0) continue;
    ++configs;
    const AugmentationOptions& a = c.detector_augmentation;
    ASSERT_FALSE(a.background_photos.empty()) << name << ": the training share must be stated";
    for (const std::string& photo : drawn)
      EXPECT_EQ(std::count(a.background_photos.begin(), a.background_photos.end(), photo), 0)
          << name << ": " << photo << " is the wild sequence's background";
    EXPECT_LT(a.background_photos.size(), list_photos(a.backgrounds, "test").size()) << name << ": no test share";
  }
  EXPECT_GE(configs, 2);  // demo.yaml and default_detector.yaml train one
}

TEST(PersonDetection, TheOverlayDrawsTheMasksOutlineAndTheDetectedKeypoints) {
  const cv::Mat frame(40, 50, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::Mat mask = cv::Mat::zeros(40, 50, CV_8UC1);
  cv::rectangle(mask, cv::Rect(10, 8, 20, 24), cv::Scalar(255), cv::FILLED);
  Body25 k = Body25::Zero();
  k.row(1) << 20, 20, 0.9;  // Neck
  k.row(4) << 40, 5, 0.0;   // undetected: not drawn
  const cv::Mat out = draw_detection(frame, k, mask);
  ASSERT_EQ(out.size(), frame.size());
  const cv::Vec3b dot = out.at<cv::Vec3b>(20, 20), edge = out.at<cv::Vec3b>(8, 20), far = out.at<cv::Vec3b>(36, 45);
  EXPECT_GT(dot[1], 150);  // green (BGR)
  EXPECT_LT(dot[2], 100);
  EXPECT_GT(edge[2], 150);  // orange outline on the mask's top edge
  EXPECT_EQ(far, cv::Vec3b(0, 0, 0));
  EXPECT_EQ(out.at<cv::Vec3b>(5, 40), cv::Vec3b(0, 0, 0));
  EXPECT_EQ(frame.at<cv::Vec3b>(20, 20), cv::Vec3b(0, 0, 0));  // the frame itself untouched
}
