// `weft infer`: captures a single-camera video or image folder with a trained model:
// body and cloth meshes per frame, the pose as .motion and BVH, overlays and an overlay
// video (capture/inference/sequence_capture.h; docs/CAPTURE.md).
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "capture/inference/sequence_capture.h"

namespace weft::apps {

void add_infer_command(CLI::App& app) {
  auto o = std::make_shared<capture::CaptureOptions>();
  auto* cmd = app.add_subcommand(
      "infer",
      "Capture a single-camera video (or a folder of images) with a model trained by `weft train`:\n"
      "segmentation (a mask folder, the model's person detector, or green-screen keying), PoseNet and PADefNet per frame, the\n"
      "temporal Gaussian filter over 5 frames, the global translation from OpenPose keypoints (or\n"
      "the silhouette), and the deformation layer. Writes OUT/meshes/{body,cloth}_<frame>.{ply,obj},\n"
      "pose.motion, pose.bvh, overlays/<frame>.png, overlay.mp4 and capture.json (what `weft eval`\n"
      "reads). docs/CAPTURE.md explains the options and files.");
  cmd->add_option("--model", o->model, "Model folder: the --out folder of `weft train`")
      ->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--weights", o->weights,
                  "Weights to use instead of the model folder's: one of its checkpoints "
                  "(RUN/checkpoints/step_NNNNNNN.safetensors) or a model.safetensors of the same networks")
      ->check(CLI::ExistingFile);
  cmd->add_option("--input", o->input, "A video file, or a folder of images (frames in name order)")
      ->required()->check(CLI::ExistingPath);
  cmd->add_option("--camera", o->camera,
                  "The camera: OpenCV FileStorage YAML as `weft synth` writes (cameras.yaml); K, dist, R, t, image size")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--camera-name", o->camera_name,
                  "Which camera of the file (default: its only camera, or its only family of per-frame cameras "
                  "<name>_<frame>, e.g. wild_0003)");
  cmd->add_option("--masks", o->masks,
                  "Folder of person masks <frame>.png (255 person); default: the model's person detector, or "
                  "green-screen keying for a model without one")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--keypoints", o->keypoints,
                  "Folder of OpenPose BODY_25 JSON (<frame>_keypoints.json): the global translation from the keypoint "
                  "rays; default: the model's person detector, or, for a model without one, the translation from the "
                  "silhouette")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--config", o->config, "Capture settings (configs/infer/default.yaml; default: its values)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--fps", o->fps, "Frame rate of pose.bvh and overlay.mp4 (default: the video's, else 30)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-frames", o->max_frames, "Capture only the first N frames")->check(CLI::NonNegativeNumber);
  cmd->add_flag("--resolve-collisions", o->resolve_collisions,
                "The paper's final collision resolution: cloth vertices pushed out of the body in a few quasi-static "
                "Newton steps (membrane, bending, collisions; the garment material of the model's synth config)");
  cmd->add_option("--out", o->out, "Output folder (created if missing)")->required();
  cmd->callback([o] {
    std::filesystem::create_directories(o->out);
    auto file = std::make_shared<spdlog::sinks::basic_file_sink_mt>((std::filesystem::path(o->out) / "infer.log").string(), true);
    spdlog::default_logger()->sinks().push_back(file);
    spdlog::info("weft infer --model {} --input {} --camera {} --out {}", o->model, o->input, o->camera, o->out);
    std::unique_ptr<ProgressBar> bar;
    std::string pass;
    const capture::CaptureSummary s = capture::capture_sequence(*o, [&](const std::string& p, int done, int total) {
      if (p != pass) bar = std::make_unique<ProgressBar>(p), pass = p;
      bar->update(done, total);
    });
    std::string parts;
    for (const auto& [part, seconds] : s.part_seconds)
      parts += fmt::format("{}{} {:.1f} ms", parts.empty() ? "" : ", ", part, 1000 * seconds / s.frames);
    spdlog::info("captured {} frames in {:.1f} s ({:.1f} frames/s); translation from keypoints {}, from the silhouette {}",
                 s.frames, s.seconds, s.fps(), s.translations_from_keypoints, s.translations_from_silhouette);
    spdlog::info("per frame: {}", parts);
    if (o->resolve_collisions)
      spdlog::info("collision resolution: deepest cloth vertex inside the body {:.2f} mm before, {:.2f} mm after",
                   1000 * s.penetration_before * s.metres_per_unit, 1000 * s.penetration_after * s.metres_per_unit);
    spdlog::info("wrote {}/capture.json, meshes/, pose.motion, pose.bvh, overlays/", o->out);
    spdlog::default_logger()->sinks().pop_back();
  });
}

}  // namespace weft::apps
