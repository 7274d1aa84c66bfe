// `weft detect`: the person's BODY_25 keypoints (OpenPose JSON) and mask (PNG) in every frame
// of a video or an image folder, predicted by a model's person detector
// (capture/inference/sequence_detection.h; docs/CAPTURE.md); with --truth, measured against a
// dataset's view (capture/evaluation/detection_accuracy.h).
#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "capture/evaluation/detection_accuracy.h"
#include "capture/inference/sequence_detection.h"
#include "graph/atomic_file.h"

namespace weft::apps {

void add_detect_command(CLI::App& app) {
  auto o = std::make_shared<capture::DetectOptions>();
  auto truth = std::make_shared<std::string>();
  auto view = std::make_shared<std::string>("wild");
  auto measure = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "detect",
      "Find the person in every frame of a video (or a folder of images) with the person detector of a model\n"
      "trained by `weft train` (network.detector, stages.detector): a coarse pass on the whole frame, then\n"
      "the crop. Writes OUT/keypoints/<frame>_keypoints.json (OpenPose BODY_25), OUT/masks/<frame>.png\n"
      "(255 person) and OUT/detect.json; `weft infer --keypoints OUT/keypoints --masks OUT/masks` reads them.\n"
      "With --truth DATA, also OUT/detection_accuracy.json: mask IoU and keypoint errors against the dataset.\n"
      "With --measure DIR (a folder with keypoints/ and masks/, e.g. another detector's), only that measurement.");
  cmd->add_option("--model", o->model, "Model folder: the --out folder of `weft train` (required unless --measure)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--weights", o->weights, "Weights to use instead of the model folder's")->check(CLI::ExistingFile);
  cmd->add_option("--input", o->input,
                  "A video file, or a folder of images (frames in name order) (required unless --measure)")
      ->check(CLI::ExistingPath);
  cmd->add_option("--max-frames", o->max_frames, "Only the first N frames")->check(CLI::NonNegativeNumber);
  cmd->add_option("--batch-size", o->batch_size, "Frames per pass of the detector (default 8)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--overlays", o->overlays,
                "Also OUT/overlays/<frame>.png: the mask's outline and the keypoints drawn over each frame");
  cmd->add_option("--truth", *truth,
                  "A dataset (weft synth) whose view --truth-view the input is: measure the detections against its "
                  "masks, its ground-truth pose and its detections")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--truth-view", *view, "The dataset's view the input shows (default: wild)");
  cmd->add_option("--measure", *measure,
                  "Detect nothing: measure this folder's keypoints/<frame>_keypoints.json and masks/<frame>.png against "
                  "--truth (written to OUT/detection_accuracy.json)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", o->out, "Output folder (created if missing)")->required();
  cmd->callback([o, truth, view, measure] {
    if (!measure->empty()) {
      if (truth->empty()) throw CLI::ValidationError("--measure", "needs --truth DATA");
      const capture::DetectionAccuracy a = capture::measure_detections(*measure, *truth, *view);
      for (const std::string& line : capture::detection_accuracy_lines(a)) spdlog::info("{}", line);
      std::filesystem::create_directories(o->out);
      write_text_atomically((std::filesystem::path(o->out) / "detection_accuracy.json").string(),
                            capture::detection_accuracy_json(a));
      return;
    }
    if (o->model.empty() || o->input.empty()) throw CLI::ValidationError("--model, --input", "required (unless --measure)");
    spdlog::info("weft detect --model {} --input {} --out {}", o->model, o->input, o->out);
    auto bar = std::make_unique<ProgressBar>("detect");
    const capture::DetectSummary s = capture::detect_sequence(*o, [&](int done, int total) { bar->update(done, total); });
    bar.reset();
    spdlog::info("{} frames in {:.1f} s ({:.1f} frames/s for the detector; {:.1f} s in all); a person in {}", s.frames,
                 s.seconds, s.fps(), s.total_seconds, s.found);
    if (!truth->empty()) {
      const capture::DetectionAccuracy a = capture::measure_detections(o->out, *truth, *view);
      for (const std::string& line : capture::detection_accuracy_lines(a)) spdlog::info("{}", line);
      write_text_atomically((std::filesystem::path(o->out) / "detection_accuracy.json").string(),
                            capture::detection_accuracy_json(a));
    }
    spdlog::info("wrote {}/keypoints/, masks/, detect.json", o->out);
  });
}

}  // namespace weft::apps
