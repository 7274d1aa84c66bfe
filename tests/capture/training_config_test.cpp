// configs/train/*.yaml: the shipped configs parse, and a bad key, type, value or a missing
// section is one error naming the file, the line and the key.
#include <gtest/gtest.h>

#include <filesystem>

#include "capture/training/training_config.h"
#include "test_files.h"
#include "tests/test_requirements.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;

using weft::capture::testing::kHuman;
using weft::capture::testing::repo_file;

namespace {
const char* kStages = "stages:\n  pose: {steps: 4, landmarks: 1}\n";
}  // namespace

TEST(TrainingConfig, ShippedConfigsParse) {
  for (const char* name : {"tiny", "default", "default_arap_only", "demo", "paper"}) {
    const TrainingConfig c = load_training_config(repo_file(std::string("configs/train/") + name + ".yaml"));
    EXPECT_GT(c.total_steps(), 0) << name;
    ASSERT_EQ(c.stages.size(), 4u);
    EXPECT_EQ(c.stages[0].kind, StageKind::pose);
    EXPECT_GT(c.stages[1].steps + c.stages[2].steps, 0) << name << ": PADefNet's stages";
  }
  // The default: PoseNet a lifting network, trained on virtual poses too.
  const TrainingConfig d = load_training_config(repo_file("configs/train/default.yaml"));
  EXPECT_FALSE(d.network.image_input);
  EXPECT_TRUE(d.network.keypoint_input);
  EXPECT_TRUE(d.virtual_poses.enabled());
  EXPECT_GT(d.stages[0].weights.virtual_landmarks, 0);
  EXPECT_GT(d.stages[2].steps, 0) << "the physics stage";
}

// The DeepCap-like baseline differs from the default only in what follows the warm start:
// the same PoseNet stage, and its warm start as long as the default's two later stages.
TEST(TrainingConfig, TheArapOnlyBaselineMatchesTheDefaultsComputeAndPoseNet) {
  const TrainingConfig d = load_training_config(repo_file("configs/train/default.yaml"));
  const TrainingConfig a = load_training_config(repo_file("configs/train/default_arap_only.yaml"));
  EXPECT_EQ(a.network.input_size, d.network.input_size);
  EXPECT_EQ(a.network.image_input, d.network.image_input);
  EXPECT_EQ(a.stages[0].steps, d.stages[0].steps);
  EXPECT_EQ(a.stages[0].weights.virtual_landmarks, d.stages[0].weights.virtual_landmarks);
  EXPECT_EQ(a.virtual_poses.enabled(), d.virtual_poses.enabled());
  EXPECT_EQ(a.stages[1].steps, d.stages[1].steps + d.stages[2].steps);
  EXPECT_EQ(a.stages[2].steps, 0);
}

// default_detector.yaml adds the person detector to a run of default.yaml (`weft train
// --init RUN/model.safetensors`): its networks must be default.yaml's, plus the detector,
// and it trains the detector alone.
TEST(TrainingConfig, TheDetectorConfigFitsARunOfTheDefault) {
  const TrainingConfig d = load_training_config(repo_file("configs/train/default.yaml"));
  const TrainingConfig a = load_training_config(repo_file("configs/train/default_detector.yaml"));
  EXPECT_EQ(a.network.backbone, d.network.backbone);
  EXPECT_EQ(a.network.input_size, d.network.input_size);
  EXPECT_EQ(a.network.margin, d.network.margin);
  EXPECT_EQ(a.network.keypoint_input, d.network.keypoint_input);
  EXPECT_EQ(a.network.image_input, d.network.image_input);
  EXPECT_EQ(a.network.dof_scale, d.network.dof_scale);
  EXPECT_EQ(a.network.angle_scale, d.network.angle_scale);
  EXPECT_EQ(a.network.translation_scale_m, d.network.translation_scale_m);
  EXPECT_FALSE(d.network.detector.enabled);
  EXPECT_TRUE(a.network.detector.enabled);
  for (const StageConfig& s : a.stages) EXPECT_EQ(s.steps > 0, s.kind == StageKind::detector) << stage_name(s.kind);
}

TEST(TrainingConfig, TheGarmentsArapFollowsTheBodysUnlessGiven) {
  const TrainingConfig c = parse_training_config(
      "stages:\n  warmup: {steps: 2, arap: 3}\n  physics: {steps: 2, arap: 3, cloth_arap: 0.5, simulation: 1}\n",
      "t.yaml");
  EXPECT_EQ(c.stages[1].weights.cloth_arap, 3);
  EXPECT_EQ(c.stages[2].weights.cloth_arap, 0.5);
}

TEST(TrainingConfig, StagesFollowEachOther) {
  const TrainingConfig c = parse_training_config(
      "stages:\n  pose: {steps: 3, landmarks: 1}\n  warmup: {steps: 2, silhouette: 1}\n", "t.yaml");
  EXPECT_EQ(c.total_steps(), 5);
  int64_t start = -1;
  EXPECT_EQ(c.stage_of(3, &start).kind, StageKind::pose);
  EXPECT_EQ(start, 0);
  EXPECT_EQ(c.stage_of(4, &start).kind, StageKind::warmup);
  EXPECT_EQ(start, 3);
  expect_error([&] { c.stage_of(6); }, {"t.yaml", "step 6", "5 steps"});
}

TEST(TrainingConfig, TheDetectorStageNeedsItsNetworkAndTrainsOnItsOwnTerms) {
  REQUIRE_DEBIAN_FILE("/usr/share/backgrounds/mate/nature/Aqua.jpg", "mate-backgrounds");
  const TrainingConfig c = parse_training_config(
      "network: {detector: {input_size: 96, width: 8, margin: 0.3, sigma_px: 2}}\n"
      "stages:\n  detector: {steps: 5, batch_size: 4, heatmaps: 1, mask: 0.5}\n"
      "detector_augmentation: {shift: 0.2, scale: 0.5, backgrounds: /usr/share/backgrounds/mate/nature,\n"
      "  background_probability: 0.8, background_photos: [Aqua.jpg, Dune.jpg]}\n",
      "c.yaml");
  ASSERT_EQ(c.stages.size(), 4u);
  EXPECT_EQ(c.stages[3].kind, StageKind::detector);
  EXPECT_STREQ(stage_name(c.stages[3].kind), "detector");
  EXPECT_EQ(c.stages[3].steps, 5);
  EXPECT_EQ(c.stages[3].weights.heatmaps, 1);
  EXPECT_EQ(c.stages[3].weights.mask, 0.5);
  EXPECT_TRUE(c.network.detector.enabled);
  EXPECT_EQ(c.network.detector.input_size, 96);
  EXPECT_EQ(c.network.detector.width, 8);
  EXPECT_EQ(c.network.detector.margin, 0.3);
  EXPECT_EQ(c.detector_augmentation.background_photos, (std::vector<std::string>{"Aqua.jpg", "Dune.jpg"}));
  EXPECT_FALSE(parse_training_config(kStages, "c.yaml").network.detector.enabled);
  // Each error names the key.
  expect_error([] { parse_training_config("stages:\n  detector: {steps: 5, heatmaps: 1}\n", "c.yaml"); },
               {"c.yaml", "stages.detector", "network.detector"});
  expect_error([] { parse_training_config("network: {detector: {input_size: 100}}\n" + std::string(kStages), "c.yaml"); },
               {"c.yaml", "network.detector.input_size", "multiple of 16"});
  expect_error([] { parse_training_config("network: {detector: {depth: 3}}\n" + std::string(kStages), "c.yaml"); },
               {"c.yaml", "network.detector", "depth"});
  expect_error([] { parse_training_config("stages:\n  pose: {steps: 4, landmarks: 1, heatmaps: 1}\n", "c.yaml"); },
               {"c.yaml", "stages.pose.heatmaps", "stages.detector only"});
  expect_error(
      [] {
        parse_training_config("network: {detector: {}}\nstages:\n  detector: {steps: 5, mask: 1, landmarks: 1}\n",
                              "c.yaml");
      },
      {"c.yaml", "stages.detector.landmarks", "heatmaps and mask only"});
  expect_error(
      [] {
        parse_training_config("network: {detector: {}}\nstages:\n  detector: {steps: 5, mask: 1}\n"
                              "detector_augmentation: {backgrounds: /usr/share/backgrounds/mate/nature,\n"
                              "  background_photos: [NoSuchPhoto.jpg]}\n",
                              "c.yaml");
      },
      {"c.yaml", "detector_augmentation.background_photos", "NoSuchPhoto.jpg"});
  expect_error([] { parse_training_config("detector_augmentation: {shift: 0.1}\n" + std::string(kStages), "c.yaml"); },
               {"c.yaml", "detector_augmentation", "0 steps"});
}

TEST(TrainingConfig, ErrorsNameTheFileTheLineAndTheKey) {
  expect_error([] { parse_training_config(std::string(kStages) + "learning_rate: 3\n", "c.yaml"); },
               {"c.yaml", "learning_rate"});
  expect_error([] { parse_training_config("stages:\n  pose: {steps: many}\n", "c.yaml"); },
               {"c.yaml:2", "stages.pose.steps"});
  expect_error([] { parse_training_config("stages:\n  pose: {steps: 4, lr: -1}\n", "c.yaml"); },
               {"c.yaml", "stages.pose.lr"});
  expect_error([] { parse_training_config("stages:\n  pose: {steps: 4, silhouette: 1}\n", "c.yaml"); },
               {"c.yaml", "landmarks, keypoints_3d, lumbopelvic and virtual_landmarks only"});
  // The lumbopelvic prior and its share: a pose-stage weight, and a share in [0, 1].
  const TrainingConfig lp =
      parse_training_config("lumbar_share: 0.7\nstages:\n  pose: {steps: 4, landmarks: 1, lumbopelvic: 0.5}\n", "c.yaml");
  EXPECT_EQ(lp.stages[0].weights.lumbopelvic, 0.5);
  EXPECT_EQ(lp.lumbar_share, 0.7);
  EXPECT_EQ(parse_training_config(kStages, "c.yaml").lumbar_share, 0.6);
  expect_error([] { parse_training_config(std::string(kStages) + "lumbar_share: 1.5\n", "c.yaml"); },
               {"c.yaml", "lumbar_share"});
  expect_error([] { parse_training_config("stages:\n  pose: {steps: 4, lumbopelvic: -2}\n", "c.yaml"); },
               {"c.yaml", "stages.pose.lumbopelvic"});
  // L_3d is a pose-stage term: read as one of its weights.
  EXPECT_EQ(parse_training_config("stages:\n  pose: {steps: 4, landmarks: 1, keypoints_3d: 250}\n", "c.yaml")
                .stages[0]
                .weights.keypoints_3d,
            250.0);
  expect_error([] { parse_training_config("stages:\n  pose: {steps: 4, keypoints_3d: -1}\n", "c.yaml"); },
               {"c.yaml", "stages.pose.keypoints_3d"});
  expect_error([] { parse_training_config("stages:\n  poses: {steps: 4}\n", "c.yaml"); }, {"c.yaml", "poses"});
  expect_error([] { parse_training_config("seed: 1\n", "c.yaml"); }, {"c.yaml", "stages", "missing"});
  expect_error([] { parse_training_config("stages:\n  pose: {steps: 0}\n", "c.yaml"); }, {"c.yaml", "nothing to train"});
  expect_error([] { parse_training_config(std::string(kStages) + "network: {backbone: vgg16}\n", "c.yaml"); },
               {"c.yaml:3", "network.backbone", "vgg16"});
  EXPECT_TRUE(parse_training_config(std::string(kStages) + "network: {keypoint_input: true}\n", "c.yaml")
                  .network.keypoint_input);
  EXPECT_FALSE(parse_training_config(std::string(kStages), "c.yaml").network.keypoint_input);
  const TrainingConfig lift = parse_training_config(
      std::string(kStages) + "network: {keypoint_input: true, lift_width: 1024, lift_layers: 3}\n", "c.yaml");
  EXPECT_EQ(lift.network.lift_width, 1024);
  EXPECT_EQ(lift.network.lift_layers, 3);
  EXPECT_EQ(parse_training_config(std::string(kStages), "c.yaml").network.lift_width, 512);
  // network_config_yaml writes every key: parsing it gives the same networks back.
  NetworkConfig odd;
  odd.backbone = "resnet34", odd.input_size = 96, odd.margin = 0.2, odd.dof_scale = 0.125, odd.angle_scale = 0.03,
  odd.translation_scale_m = 0.02, odd.keypoint_input = true, odd.image_input = false, odd.lift_width = 100,
  odd.lift_layers = 3;
  odd.detector.enabled = true, odd.detector.input_size = 80, odd.detector.width = 12, odd.detector.margin = 0.3,
  odd.detector.sigma_px = 2.5;
  const NetworkConfig back =
      parse_training_config(std::string(kStages) + "network: " + network_config_yaml(odd) + "\n", "c.yaml").network;
  EXPECT_EQ(network_config_yaml(back), network_config_yaml(odd));
  EXPECT_FALSE(back.image_input);
  EXPECT_EQ(back.lift_width, 100);
  EXPECT_DOUBLE_EQ(back.dof_scale, 0.125);
  EXPECT_EQ(back.detector.input_size, 80);
  EXPECT_DOUBLE_EQ(back.detector.sigma_px, 2.5);
  // physics_config_yaml writes every key: parsing it gives the same settings back.
  PhysicsConfig physics;
  physics.window_frames = 3, physics.max_iterations = 77, physics.tolerance = 3e-3, physics.ray_stiffness = 0,
  physics.ray_max_pixels = 4.5, physics.resolve_start = false, physics.freeze_batch_norm = false;
  const PhysicsConfig physics_back =
      parse_training_config(std::string(kStages) + "physics: " + physics_config_yaml(physics) + "\n", "c.yaml").physics;
  EXPECT_EQ(physics_config_yaml(physics_back), physics_config_yaml(physics));
  EXPECT_EQ(physics_back.ray_stiffness, 0.0);
  EXPECT_FALSE(physics_back.resolve_start);
  EXPECT_DOUBLE_EQ(physics_back.tolerance, 3e-3);
  expect_error([] { parse_training_config(std::string(kStages) + "network: {lift_layers: 0}\n", "c.yaml"); },
               {"c.yaml:3", "network.lift_layers"});
  expect_error([] { parse_training_config(std::string(kStages) + "network: {keypoint_input: maybe}\n", "c.yaml"); },
               {"c.yaml:3", "network.keypoint_input", "true or false"});
  // The garment's simulation comes from the dataset (dataset.yaml), not from a recipe's path.
  expect_error(
      [] { parse_training_config("stages:\n  physics: {steps: 4, simulation: 1}\nphysics: {synth_config: x}\n", "c.yaml"); },
      {"c.yaml:3", "physics.synth_config", "dataset.yaml"});
  expect_error(
      [] { parse_training_config(std::string(kStages) + "physics: {window_frames: 1}\n", "c.yaml"); },
      {"c.yaml", "physics.window_frames"});
  expect_error(
      [] { parse_training_config(std::string(kStages) + "physics: {resolve_start: maybe}\n", "c.yaml"); },
      {"c.yaml", "physics.resolve_start", "true or false"});
  expect_error(
      [] { parse_training_config(std::string(kStages) + "physics: {ray_stiffness: -1}\n", "c.yaml"); },
      {"c.yaml", "physics.ray_stiffness"});
  expect_error(
      [] { parse_training_config(std::string(kStages) + "physics: {freeze_batchnorm: true}\n", "c.yaml"); },
      {"c.yaml", "freeze_batchnorm"});
  expect_error([] { parse_training_config("stages:\n  warmup: {steps: 4, silhouette: 1, cloth_arap: 2}\n", "c.yaml"); },
               {"c.yaml:2", "stages.warmup.cloth_arap", "arap > 0"});
  expect_error([] { load_training_config("/nonexistent/train.yaml"); }, {"/nonexistent/train.yaml", "cannot open"});
}
