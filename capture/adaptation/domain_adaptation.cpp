#include "capture/adaptation/domain_adaptation.h"

#include <spdlog/fmt/fmt.h>
#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <algorithm>
#include <memory>

#include "capture/dataset/synthetic_dataset.h"
#include "capture/inference/capture_config.h"
#include "capture/inference/sequence_input.h"
#include "graph/atomic_file.h"
#include "capture/io/openpose.h"
#include "capture/io/png_file.h"
#include "capture/model/model_folder.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

// The sequence as a one-view dataset (docs/DATASET.md), frames renumbered 0 … N − 1 in
// input order; returns the number of frames. Written into a sibling folder and renamed,
// so an interrupted write never leaves a dataset that looks complete.
int write_sequence_dataset(const AdaptOptions& o, const ModelFolder& model, const KeyingConfig& keying,
                           const fs::path& dir) {
  const fs::path staging = dir.string() + ".partial";
  fs::remove_all(staging);
  // Without --masks or --keypoints the model's person detector finds them, when it has one.
  SequenceInputOptions in{o.input, o.camera, o.camera_name, o.masks, o.keypoints, keying};
  std::unique_ptr<Character> character;
  std::unique_ptr<CaptureNetworks> nets;
  if (in.wants_detector() && model.network.detector.enabled) {
    character = std::make_unique<Character>(load_character(model.character));
    nets = std::make_unique<CaptureNetworks>(*character, model.network, model.seed);
    load_capture_networks(model.weights, *nets);
    in.detector = nets->detector.get();
  }
  SequenceInput input(in);
  spdlog::info("{}", input.describe());
  const std::string view = input.cameras().name();
  for (const char* sub : {"images", "masks", "keypoints"}) fs::create_directories(staging / sub / view);
  std::vector<Camera> cameras;
  int n = 0, width = 0, height = 0, detected = 0;
  SequenceFrame f;
  while ((o.max_frames < 0 || n < o.max_frames) && input.next(f)) {
    const std::string id = dataset_frame_name(n);
    write_png_atomically((staging / "images" / view / (id + ".png")).string(), f.frame.bgr);
    write_png_atomically((staging / "masks" / view / (id + ".png")).string(), f.mask);
    OpenPoseFrame people;
    if (f.has_detections) people.people.push_back(f.detections), ++detected;
    write_openpose_json((staging / "keypoints" / view / (id + "_keypoints.json")).string(), people);
    Camera c = f.camera;
    c.name = input.cameras().per_frame() ? view + "_" + id : view;
    if (input.cameras().per_frame() || cameras.empty()) cameras.push_back(c);
    width = f.frame.bgr.cols, height = f.frame.bgr.rows;
    ++n;
  }
  WEFT_CHECK(n > 0, o.input, ": no frames read");
  WEFT_CHECK(detected > 0, o.keypoints.empty() ? std::string("the person detector of ") + o.model : o.keypoints,
             ": no detections for any frame of ", o.input, " (domain adaptation needs them: L_lm and the root translation)");
  write_cameras_yaml((staging / "cameras.yaml").string(), cameras);
  fs::copy(fs::path(model.character).parent_path(), staging / "character", fs::copy_options::recursive);
  const double fps = o.fps > 0 ? o.fps : input.source().fps() > 0 ? input.source().fps() : 30.0;
  YAML::Emitter y;
  y << YAML::BeginMap;
  y << YAML::Key << "format" << YAML::Value << "weft-synth/1";
  y << YAML::Key << "name" << YAML::Value << "adaptation";
  y << YAML::Key << "fps" << YAML::Value << fps;
  y << YAML::Key << "metres_per_unit" << YAML::Value << YAML::Node(1.0);
  y << YAML::Key << "frames" << YAML::Value << n;
  y << YAML::Key << "views" << YAML::Value << YAML::Flow << std::vector<std::string>{view};
  y << YAML::Key << "image_width" << YAML::Value << width;
  y << YAML::Key << "image_height" << YAML::Value << height;
  y << YAML::Key << "camera_per_frame" << YAML::Value << input.cameras().per_frame();
  y << YAML::Key << "character" << YAML::Value << ("character/" + fs::path(model.character).filename().string());
  y << YAML::Key << "dt_scale" << YAML::Value << 16;
  std::vector<int> all(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) all[size_t(i)] = i;
  y << YAML::Key << "splits" << YAML::Value << YAML::BeginMap << YAML::Key << "train" << YAML::Value << YAML::Flow
    << all << YAML::EndMap;
  y << YAML::EndMap;
  // The model's garment simulation goes with it: adaptation's physics stage reads it here.
  write_text_atomically((staging / "dataset.yaml").string(),
                        "# The test sequence of `weft adapt` as a one-view dataset (docs/DATASET.md).\n" +
                            std::string(y.c_str()) + "\n" +
                            (model.simulation ? simulation_config_yaml(*model.simulation) : std::string()));
  fs::remove_all(dir);
  fs::rename(staging, dir);
  spdlog::info("sequence: {} frames of {} ({} with detections) written to {}", n, view, detected, dir.string());
  return n;
}

std::string stage_line(const char* name, int steps, const StageConfig& s, const LossWeights& w) {
  // The learning rate where the model's stage ended; fmt's {} prints the shortest exact form.
  return fmt::format(
      "  {}: {{steps: {}, batch_size: {}, lr: {}, weight_decay: {}, final_lr_fraction: 1, landmarks: {}, "
      "silhouette: {}, arap: {}, cloth_arap: {}, attachment: {}, simulation: {}}}\n",
      name, steps, s.batch_size, s.lr * s.final_lr_fraction, s.weight_decay, w.landmarks, w.silhouette, w.arap,
      w.arap > 0 ? w.cloth_arap : 0.0, w.attachment, w.simulation);
}

// The trainer's config for the adaptation (see the header).
std::string adaptation_config(const ModelFolder& model, int iterations) {
  const TrainingConfig c = model_training_config(model);
  const bool physics = c.stages[2].steps > 0;
  std::string y = fmt::format(
      "# `weft adapt` of {}: both networks refined on the test sequence with one camera's\n"
      "# losses (capture/adaptation/domain_adaptation.h); generated from the model's config.\n"
      "seed: {}\n"
      "network: {}\n"  // every key, the detector's included (carried over; the adaptation does not train it)
      "stages:\n",
      model.dir, c.seed, network_config_yaml(c.network));
  LossWeights pose_weights;
  pose_weights.landmarks = c.stages[0].weights.landmarks > 0 ? c.stages[0].weights.landmarks : 1;
  y += stage_line("pose", iterations, c.stages[0], pose_weights);
  y += stage_line("warmup", physics ? 0 : iterations, c.stages[1], c.stages[1].weights);
  y += stage_line("physics", physics ? iterations : 0, c.stages[2], c.stages[2].weights);
  if (physics) y += "physics: " + physics_config_yaml(c.physics) + "\n";  // every key: the model's simulation loss
  y += fmt::format(
      "silhouette_size: {}\nloader_threads: {}\nlog_every: {}\nvalidate_every: 0\nvalidation_samples: 1\n"
      "checkpoint_every: {}\nkeep_checkpoints: 2\n",
      c.silhouette_size, c.loader_threads, std::clamp(c.log_every, 1, 25), std::clamp(c.checkpoint_every, 1, 50));
  return y;
}

}  // namespace

AdaptSummary adapt_model(const AdaptOptions& o, const std::function<void(const TrainProgress&)>& progress) {
  WEFT_CHECK(o.iterations >= 1, "weft adapt: --iterations ", o.iterations, ", expected ≥ 1");
  const ModelFolder model = read_model_folder(o.model);
  if (o.keypoints.empty() && !model.network.detector.enabled)
    fail("weft adapt: --keypoints is required (L_lm and the root translation come from the sequence's OpenPose "
         "detections), because ", o.model, " has no person detector to find them (retrain it with network.detector and "
         "stages.detector.steps > 0; docs/TRAINING.md, \"The person detector\")");
  const CaptureConfig cfg = o.config.empty() ? CaptureConfig{} : load_capture_config(o.config);
  const fs::path out(o.out);
  WEFT_CHECK(fs::absolute(out).lexically_normal() != fs::absolute(o.model).lexically_normal(), o.out,
             ": the adapted model needs a folder of its own (not the model's)");
  fs::create_directories(out);
  AdaptSummary summary;
  const fs::path sequence = out / "sequence";
  summary.sequence = sequence.string();
  const fs::path config = out / "adapt_config.yaml";
  if (o.resume && fs::exists(sequence / "dataset.yaml") && fs::exists(config)) {
    summary.frames = read_dataset_info(sequence.string()).frames;
    spdlog::info("resuming the adaptation in {} ({} frames)", o.out, summary.frames);
  } else {
    summary.frames = write_sequence_dataset(o, model, cfg.keying, sequence);
    write_text_atomically(config.string(), adaptation_config(model, o.iterations));
  }
  TrainOptions t;
  t.config = config.string();
  t.data = sequence.string();
  t.run = o.out;
  t.resume = o.resume;
  t.stop_after = o.stop_after;
  t.init_weights = model.weights;
  summary.training = train(t, progress);
  return summary;
}

}  // namespace weft::capture
