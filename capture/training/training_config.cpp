#include "capture/training/training_config.h"

#include <fmt/format.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "files/strict_yaml.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

const char* stage_name(StageKind kind) {
  switch (kind) {
    case StageKind::pose: return "pose";
    case StageKind::warmup: return "warmup";
    case StageKind::physics: return "physics";
    case StageKind::detector: return "detector";
  }
  return "?";
}

int TrainingConfig::total_steps() const {
  int n = 0;
  for (const StageConfig& s : stages) n += s.steps;
  return n;
}

const std::vector<LossTerm>& loss_terms() {
  static const std::vector<LossTerm> table = {
      {"landmarks", &LossWeights::landmarks, "L_lm: confidence-weighted squared pixel error of the projected keypoints"},
      {"keypoints_3d", &LossWeights::keypoints_3d,
       "L_3d: squared distance (m²) of the keypoints to those triangulated from the frame's detections in every view"},
      {"silhouette", &LossWeights::silhouette, "L_sil: squared distance-transform value at the boundary vertices"},
      {"arap", &LossWeights::arap, "L_arap: as-rigid-as-possible energy of the embedded graphs"},
      {"attachment", &LossWeights::attachment, "L_att: squared distance of the garment's anchors to their body triangles"},
      {"simulation", &LossWeights::simulation, "L_sim: squared distance of the predicted cloth to its simulation"},
      {"lumbopelvic", &LossWeights::lumbopelvic,
       "L_lp: squared distance of the pelvis's up axis to where the human lumbopelvic share of the trunk's lean puts it"},
      {"virtual_landmarks", &LossWeights::virtual_landmarks,
       "L_lm of PoseNet's lifting branch alone on virtual poses: motions no camera filmed, their detections drawn "
       "from the detector error model in the dataset's cameras"},
      {"heatmaps", &LossWeights::heatmaps,
       "L_hm: the person detector's keypoint heatmaps against Gaussians at the dataset's detections, squared error "
       "per heatmap weighted by the detection's confidence"},
      {"mask", &LossWeights::mask, "L_mask: the person detector's mask logits against the dataset's mask, binary cross-entropy"},
  };
  return table;
}

const StageConfig& TrainingConfig::stage_of(int64_t step, int64_t* stage_start) const {
  int64_t start = 0;
  for (const StageConfig& s : stages) {
    if (step <= start + s.steps) {
      if (stage_start) *stage_start = start;
      return s;
    }
    start += s.steps;
  }
  fail(file, ": step ", step, " is past the last stage (", total_steps(), " steps in all)");
}

namespace {

void parse_stage(const StrictYaml& y, const YAML::Node& n, StageConfig& s) {
  const std::string where = std::string("stages.") + stage_name(s.kind) + ".";
  std::vector<NumberKey> numbers = {{"lr", &s.lr, 0, 10},
                                    {"weight_decay", &s.weight_decay, 0, 10},
                                    {"final_lr_fraction", &s.final_lr_fraction, 0, 1}};
  for (const LossTerm& t : loss_terms()) {
    numbers.push_back({t.name, &(s.weights.*t.weight), 0, 1e9});
    if (t.weight == &LossWeights::arap) numbers.push_back({"cloth_arap", &s.weights.cloth_arap, 0, 1e9});
  }
  y.numbers(n, where, numbers, {{"steps", &s.steps, 0, 1e8}, {"batch_size", &s.batch_size, 1, 4096}}, {});
  if (s.weights.cloth_arap < 0) s.weights.cloth_arap = s.weights.arap;
  if (s.weights.cloth_arap > 0 && s.weights.arap <= 0)
    y.fail_at(n["cloth_arap"], where + "cloth_arap", "needs arap > 0 (arap weighs the body's graph; cloth_arap the garment's)");
  if (s.kind == StageKind::pose && (s.weights.silhouette > 0 || s.weights.arap > 0 || s.weights.cloth_arap > 0 ||
                                    s.weights.attachment > 0 || s.weights.simulation > 0))
    y.fail_at(n, where + "landmarks",
              "the pose stage trains PoseNet on landmarks, keypoints_3d, lumbopelvic and virtual_landmarks only: "
              "other weights must be 0");
  const bool detector_term = s.weights.heatmaps > 0 || s.weights.mask > 0;
  if (s.kind == StageKind::detector) {
    for (const LossTerm& t : loss_terms())
      if (t.weight != &LossWeights::heatmaps && t.weight != &LossWeights::mask && s.weights.*t.weight > 0)
        y.fail_at(n[t.name], where + t.name, "the detector stage trains the person detector on heatmaps and mask only");
  } else if (detector_term) {
    const char* key = s.weights.heatmaps > 0 ? "heatmaps" : "mask";
    y.fail_at(n[key], where + key, "the person detector learns in stages.detector only");
  }
  if (s.kind != StageKind::pose && s.weights.virtual_landmarks > 0)
    y.fail_at(n["virtual_landmarks"], where + "virtual_landmarks",
              "PoseNet learns in the pose stage only: the virtual poses belong there");
  if (s.kind == StageKind::warmup && s.weights.simulation > 0)
    y.fail_at(n["simulation"], where + "simulation", "the warm start has no simulation loss (that is the physics stage)");
}

}  // namespace

TrainingConfig parse_training_config(const std::string& text, const std::string& name, const std::string& base_dir) {
  StrictYaml y;
  y.file = name;
  y.dir = base_dir.empty() ? fs::path(name).parent_path() : fs::path(base_dir);
  const YAML::Node root = y.parse(text);
  if (!root.IsMap()) y.fail_at(root, "(document)", "expected a mapping of config keys");
  y.check_keys(root, "", {"seed", "network", "stages", "silhouette_size", "loader_threads", "log_every",
                          "validate_every", "validation_samples", "checkpoint_every", "keep_checkpoints",
                          "shards", "oracle_pose", "oracle_pose_noise", "physics", "augmentation", "lumbar_share",
                          "virtual_poses", "detector_augmentation"});
  TrainingConfig c;
  c.file = name;
  if (root["seed"]) c.seed = y.get<uint64_t>(root["seed"], "seed", "a non-negative integer");
  y.numbers(root, "", {{"lumbar_share", &c.lumbar_share, 0, 1}},
            {{"silhouette_size", &c.silhouette_size, 16, 4096},
             {"loader_threads", &c.loader_threads, 0, 64},
             {"log_every", &c.log_every, 1, 1e8},
             {"validate_every", &c.validate_every, 0, 1e8},
             {"validation_samples", &c.validation_samples, 1, 1e6},
             {"checkpoint_every", &c.checkpoint_every, 1, 1e8},
             {"keep_checkpoints", &c.keep_checkpoints, 1, 1000},
             {"shards", &c.shards, 0, 4096}},
            {"seed", "network", "stages", "oracle_pose", "oracle_pose_noise", "physics", "augmentation", "virtual_poses",
             "detector_augmentation"});
  if (root["virtual_poses"]) c.virtual_poses = parse_virtual_pose_config(y, root["virtual_poses"]);
  if (root["augmentation"]) c.augmentation = parse_augmentation(y, root["augmentation"], "augmentation");
  if (root["detector_augmentation"])
    c.detector_augmentation = parse_augmentation(y, root["detector_augmentation"], "detector_augmentation");
  if (root["oracle_pose"]) c.oracle_pose = y.get<bool>(root["oracle_pose"], "oracle_pose", "true or false");
  if (const YAML::Node n = root["oracle_pose_noise"]) {
    if (!c.oracle_pose)
      y.fail_at(n, "oracle_pose_noise", "perturbs the oracle pose, but oracle_pose is not true");
    c.oracle_pose_noise = parse_pose_noise(y, n, "oracle_pose_noise");
  }
  if (root["network"]) parse_network_config(y, root["network"], c.network);
  for (StageKind kind : {StageKind::pose, StageKind::warmup, StageKind::physics, StageKind::detector}) {
    StageConfig s;
    s.kind = kind;
    c.stages.push_back(s);
  }
  if (!root["stages"]) y.fail_at(root, "stages", "missing: the stages section (pose, warmup, physics, detector)");
  const YAML::Node st = root["stages"];
  y.check_keys(st, "stages.", {"pose", "warmup", "physics", "detector"});
  for (StageConfig& s : c.stages)
    if (const YAML::Node n = st[stage_name(s.kind)]) parse_stage(y, n, s);
  if (c.total_steps() == 0) y.fail_at(st, "stages", "every stage has 0 steps: nothing to train");
  if (c.stages[3].steps > 0 && !c.network.detector.enabled)
    y.fail_at(st["detector"], "stages.detector",
              "trains the person detector, but the config has no network.detector section (input_size, width, margin, "
              "sigma_px)");
  if (root["detector_augmentation"] && c.stages[3].steps == 0)
    y.fail_at(root["detector_augmentation"], "detector_augmentation", "augments the detector stage, which has 0 steps");
  if (c.stages[0].weights.virtual_landmarks > 0) {
    if (!c.virtual_poses.enabled())
      y.fail_at(st["pose"]["virtual_landmarks"], "stages.pose.virtual_landmarks",
                "weighs the virtual poses' loss, but the config has no virtual_poses section (motions, mapping)");
    if (!c.network.keypoint_input)
      y.fail_at(st["pose"]["virtual_landmarks"], "stages.pose.virtual_landmarks",
                "the virtual poses train PoseNet's lifting branch: set network.keypoint_input: true");
  }
  if (const YAML::Node n = root["physics"]) {
    PhysicsConfig& p = c.physics;
    y.numbers(n, "physics.",
              {{"tolerance", &p.tolerance, 1e-8, 10},
               {"ray_stiffness", &p.ray_stiffness, 0, 1e8},
               {"ray_max_pixels", &p.ray_max_pixels, 0, 1e4}},
              {{"window_frames", &p.window_frames, 2, 64}, {"max_iterations", &p.max_iterations, 1, 10000}},
              {"synth_config", "resolve_start", "freeze_batch_norm"});
    if (n["resolve_start"]) p.resolve_start = y.get<bool>(n["resolve_start"], "physics.resolve_start", "true or false");
    if (n["freeze_batch_norm"])
      p.freeze_batch_norm = y.get<bool>(n["freeze_batch_norm"], "physics.freeze_batch_norm", "true or false");
    if (n["synth_config"])
      y.fail_at(n["synth_config"], "physics.synth_config",
                "no longer read: the garment is simulated with the settings the dataset was made with "
                "(dataset.yaml's simulation section, which weft synth writes); remove the key, and regenerate a "
                "dataset without that section with weft synth");
  }
  return c;
}

std::string physics_config_yaml(const PhysicsConfig& c) {
  // fmt's {} prints the shortest form that reads back exactly.
  return fmt::format(
      "{{window_frames: {}, max_iterations: {}, tolerance: {}, ray_stiffness: {}, ray_max_pixels: {}, "
      "resolve_start: {}, freeze_batch_norm: {}}}",
      c.window_frames, c.max_iterations, c.tolerance, c.ray_stiffness, c.ray_max_pixels, c.resolve_start,
      c.freeze_batch_norm);
}

TrainingConfig load_training_config(const std::string& path) {
  return parse_training_config(read_file_bytes(path), path);
}

TrainingConfig model_training_config(const ModelFolder& model) {
  return parse_training_config(read_file_bytes(model.config), model.config, model.config_dir);
}

}  // namespace weft::capture
