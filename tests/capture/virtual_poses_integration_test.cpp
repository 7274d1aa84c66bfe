// Virtual poses for PoseNet's lifting branch (capture/training/virtual_poses.h) on the
// tiny dataset: every chosen view's detections and the input crop are of one posed
// person (noise-free detector: the views triangulate to points that reproject onto every
// detection, and the crop camera maps them onto the branch's input); a step's batch is a
// function of (seed, step); training on them lowers their loss and resumes exactly; bad
// config keys are errors naming the key.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "capture/character/skeletool_io.h"
#include "capture/model/global_pose.h"
#include "capture/training/loss_log.h"
#include "capture/training/trainer.h"
#include "capture/training/training_config.h"
#include "capture/training/virtual_poses.h"
#include "capture/model/capture_networks.h"
#include "capture/model/network_config.h"
#include "graph/autograd.h"
#include "graph/error.h"
#include "ops/ops.h"
#include "tests/capture/shared_fixture.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
namespace fs = std::filesystem;
using weft::capture::testing::repo_file;

namespace {

// A short random motion (4 s, 40 poses at 10 fps) in the test's scratch folder.
std::string short_motion() {
  const fs::path dir = weft::capture::testing::process_scratch("virtual_poses");
  const fs::path spec = dir / "short_random.yaml";
  if (!fs::exists(spec))
    std::ofstream(spec) << "name: short_random\nfps: 10\nsegments:\n  - {type: random, duration: 4, seed: 5}\n";
  return spec.string();
}

VirtualPoseConfig exact_config() {
  VirtualPoseConfig c;
  c.motions = {short_motion()};
  c.mapping = repo_file("configs/retarget/humanoid_to_makehuman.yaml");
  c.batch_size = 3;
  c.views = 4;
  c.keypoints = KeypointNoiseConfig();  // gaussian, made exact:
  c.keypoints.noise_px = 0;
  c.keypoints.dropout = 0;
  c.keypoints.occluded_dropout = 0;
  c.keypoints.confidence_jitter = 0;
  return c;
}

TEST(VirtualPoses, EveryViewAndTheCropSeeOnePose) {
  REQUIRE_HUMAN();
  const fs::path data = weft::capture::testing::tiny_dataset();
  const DatasetInfo info = read_dataset_info(data.string());
  const Character ch = load_character(info.character);
  const MultiviewSupervision sup(info, info.splits.at("train"), 64);
  constexpr int S = 64;
  const VirtualPoses poses(ch, exact_config(), sup, info.splits.at("train"), S, 0.15, AugmentationOptions());
  EXPECT_EQ(poses.poses(), 40);
  const VirtualBatch v = poses.batch(3, 7);
  ASSERT_EQ(v.views.size(), 3u);
  ASSERT_EQ(v.input.size(), 3);
  ASSERT_EQ(v.input.keypoints.size(0), 3);
  const Vertices rest = pose_character(ch, ch.rest_dofs).body25;  // NaN rows: keypoints the character lacks
  std::vector<double> mask(kBody25Count);
  for (int m = 0; m < kBody25Count; ++m) mask[m] = rest.row(m).allFinite() ? 1.0 : 0.0;
  for (int b = 0; b < 3; ++b) {
    ASSERT_EQ(v.views[b].size(), 4u);
    std::set<std::string> names;
    for (const KeypointView& kv : v.views[b]) names.insert(kv.camera.name);
    EXPECT_EQ(names.size(), 4u) << "four different cameras";
    EXPECT_EQ(v.input.views[b], v.views[b][0].camera.name) << "the first view is the input";
    const Body25 q = triangulate_keypoints(v.views[b], mask);
    int checked = 0;
    for (int m = 0; m < kBody25Count; ++m) {
      if (!q.row(m).allFinite()) continue;
      for (const KeypointView& kv : v.views[b]) {
        if (!(kv.detections(m, 2) > 0)) continue;
        const Eigen::Vector2d uv = kv.camera.project(q.row(m).transpose());
        EXPECT_NEAR(uv.x(), kv.detections(m, 0), 1e-6) << "sample " << b << " keypoint " << m;
        EXPECT_NEAR(uv.y(), kv.detections(m, 1), 1e-6) << "sample " << b << " keypoint " << m;
        ++checked;
      }
      const float* in = v.input.keypoints.data<float>() + (b * kBody25Count + m) * 3;
      if (!(in[2] > 0)) continue;
      const Eigen::Vector2d c = v.input.cameras[b].project(q.row(m).transpose());
      EXPECT_NEAR(c.x(), in[0], 1e-3) << "the crop camera maps the pose onto the branch's input";
      EXPECT_NEAR(c.y(), in[1], 1e-3);
      EXPECT_TRUE(in[0] > -0.5 && in[0] < S - 0.5 && in[1] > -0.5 && in[1] < S - 0.5)
          << "keypoint " << m << " outside the crop: " << in[0] << ", " << in[1];
    }
    EXPECT_GT(checked, 40) << "sample " << b;
  }
  // A function of (seed, step).
  const VirtualBatch again = poses.batch(3, 7), next = poses.batch(3, 8);
  for (int64_t i = 0; i < v.input.keypoints.numel(); ++i)
    ASSERT_EQ(again.input.keypoints.data<float>()[i], v.input.keypoints.data<float>()[i]);
  double differ = 0;
  for (int64_t i = 0; i < v.input.keypoints.numel(); ++i)
    differ += std::abs(next.input.keypoints.data<float>()[i] - v.input.keypoints.data<float>()[i]);
  EXPECT_GT(differ, 1.0) << "another step draws other poses";
}

std::string virtual_training_config(const std::string& extra_pose_keys = ", virtual_landmarks: 1") {
  return "seed: 4\n"
         "network: {backbone: resnet18, input_size: 64, keypoint_input: true}\n"
         "stages:\n"
         "  pose: {steps: 12, batch_size: 2, lr: 2.0e-3, final_lr_fraction: 1, landmarks: 1" +
         extra_pose_keys +
         "}\n"
         "silhouette_size: 64\nloader_threads: 0\nlog_every: 4\nvalidate_every: 0\nvalidation_samples: 4\n"
         "checkpoint_every: 4\nkeep_checkpoints: 5\n"
         "virtual_poses:\n"
         "  motions: [" + short_motion() + "]\n"
         "  mapping: " + repo_file("configs/retarget/humanoid_to_makehuman.yaml") + "\n"
         "  batch_size: 8\n  views: 3\n";
}

TEST(VirtualPoses, TrainingOnThemLowersTheirLossAndResumesExactly) {
  REQUIRE_HUMAN();
  const fs::path data = weft::capture::testing::tiny_dataset();
  const fs::path dir = weft::capture::testing::process_scratch("virtual_poses");
  const fs::path config = dir / "virtual.yaml";
  std::ofstream(config) << virtual_training_config();
  TrainOptions o;
  o.config = config.string();
  o.data = data.string();
  o.run = (dir / "whole").string();
  train(o);
  const auto rows = read_loss_log((dir / "whole" / "losses.csv").string());
  ASSERT_EQ(rows.size(), 12u);
  auto mean = [&](size_t first) {
    double s = 0;
    for (size_t i = first; i < first + 4; ++i) s += rows.at(i).terms.at("virtual_landmarks");
    return s / 4;
  };
  EXPECT_LT(mean(8), mean(0)) << "the virtual poses' L_lm falls";
  EXPECT_GT(rows[0].terms.at("virtual_keypoint_px"), 0.0);

  // Stopped after 6 steps and resumed: the same losses, step for step.
  o.run = (dir / "resumed").string();
  o.stop_after = 6;
  train(o);
  o.stop_after = -1;
  o.resume = true;
  train(o);
  EXPECT_EQ(weft::capture::testing::slurp(dir / "resumed" / "losses.csv"),
            weft::capture::testing::slurp(dir / "whole" / "losses.csv"));
}

TEST(VirtualPoses, ConfigErrorsNameTheKey) {
  const std::string base = virtual_training_config();
  auto error_of = [](const std::string& yaml) -> std::string {
    try {
      parse_training_config(yaml, "virtual.yaml", ".");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  // The weight without the section.
  std::string no_section = base.substr(0, base.find("virtual_poses:"));
  EXPECT_NE(error_of(no_section).find("stages.pose.virtual_landmarks"), std::string::npos) << error_of(no_section);
  // The section without a mapping.
  std::string no_mapping = base;
  no_mapping.erase(no_mapping.find("  mapping:"), no_mapping.find("  batch_size") - no_mapping.find("  mapping:"));
  EXPECT_NE(error_of(no_mapping).find("virtual_poses.mapping"), std::string::npos) << error_of(no_mapping);
  // A key of the other detector model, and an unknown key.
  EXPECT_NE(error_of(base + "  keypoints: {model: gaussian, swap_probability: 0.1}\n")
                .find("virtual_poses.keypoints.swap_probability"),
            std::string::npos);
  EXPECT_NE(error_of(base + "  view: 3\n").find("virtual_poses.view"), std::string::npos) << error_of(base + "  view: 3\n");
  // Without the lifting branch there is nothing for them to train.
  std::string no_branch = base;
  no_branch.replace(no_branch.find(", keypoint_input: true"), 22, "");
  EXPECT_NE(error_of(no_branch).find("network.keypoint_input"), std::string::npos) << error_of(no_branch);
}

// network.image_input: false makes PoseNet the lifting branch alone: its output is the
// branch's on the detections whatever the images, and only the branch trains.
TEST(VirtualPoses, PoseNetWithoutImagesIsTheLiftingBranchAlone) {
  REQUIRE_HUMAN();
  const fs::path data = weft::capture::testing::tiny_dataset();
  const DatasetInfo info = read_dataset_info(data.string());
  const Character ch = load_character(info.character);
  NetworkConfig config;
  config.input_size = 64;
  config.keypoint_input = true;
  config.image_input = false;
  DatasetOptions options;
  options.input_size = config.input_size;
  const SyntheticDataset ds(data.string(), options);
  Batch batch = make_batch({ds.load(0), ds.load(1)});
  CaptureNetworks nets(ch, config, 5);
  for (const auto& p : nets.pose_parameters()) EXPECT_EQ(p.name.rfind("pose_lift.", 0), 0u) << p.name;
  // A non-zero branch, so that the comparison below can fail.
  for (auto p : nets.pose_lift->named_parameters()) p.tensor.fill(0.01);
  weft::NoGradGuard no_grad;
  const weft::Tensor a = nets.pose(batch);
  batch.images = weft::ops::scale(batch.images, 0.0);  // other pixels: the same output
  const weft::Tensor b = nets.pose(batch), lift = nets.pose_from_keypoints(batch);
  ASSERT_EQ(a.numel(), b.numel());
  double norm = 0;
  for (int64_t i = 0; i < a.numel(); ++i) {
    ASSERT_EQ(a.data<float>()[i], b.data<float>()[i]);
    ASSERT_EQ(a.data<float>()[i], lift.data<float>()[i]);
    norm += std::abs(a.data<float>()[i]);
  }
  EXPECT_GT(norm, 0.0);
  // Without either input there is no PoseNet: an error naming the key.
  StrictYaml y;
  y.file = "net.yaml";
  NetworkConfig c;
  try {
    parse_network_config(y, y.parse("{image_input: false}"), c);
    ADD_FAILURE() << "no input accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("network.image_input"), std::string::npos) << e.what();
  }
}

}  // namespace
