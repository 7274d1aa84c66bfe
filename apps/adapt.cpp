// `weft adapt`: domain adaptation of a trained model on the test sequence before capture
// (capture/adaptation/domain_adaptation.h; docs/CAPTURE.md).
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "capture/adaptation/domain_adaptation.h"

namespace weft::apps {

void add_adapt_command(CLI::App& app) {
  auto o = std::make_shared<capture::AdaptOptions>();
  auto* cmd = app.add_subcommand(
      "adapt",
      "Domain adaptation, as the paper does before testing: refine both networks of a model trained\n"
      "by `weft train` on the test sequence itself, with the losses one camera gives (L_lm on the\n"
      "sequence's keypoints, L_sil on its masks, L_att, and L_arap or\n"
      "L_sim as in the model's last stage): PoseNet for --iterations steps, then PADefNet. OUT is a\n"
      "model folder: capture the sequence with `weft infer --model OUT`. docs/CAPTURE.md.");
  cmd->add_option("--model", o->model, "Model folder to adapt (the --out of `weft train`)")
      ->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--input", o->input, "The test sequence: a video file or a folder of images")
      ->required()->check(CLI::ExistingPath);
  cmd->add_option("--camera", o->camera, "Its camera(s): OpenCV FileStorage YAML, as for `weft infer`")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--camera-name", o->camera_name, "Which camera of the file (as for `weft infer`)");
  cmd->add_option("--keypoints", o->keypoints,
                  "OpenPose BODY_25 JSON per frame; default: the model's person detector (required for a model "
                  "without one)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--masks", o->masks,
                  "Person masks <frame>.png; default: the model's person detector, or green-screen keying for a model "
                  "without one")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--config", o->config, "Capture settings for the keying (configs/infer/default.yaml)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--iterations", o->iterations, "Steps per network (the paper: 300)")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  cmd->add_option("--fps", o->fps, "The sequence's frame rate (default: the video's, else 30)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--max-frames", o->max_frames, "Use only the first N frames")->check(CLI::NonNegativeNumber);
  cmd->add_flag("--resume", o->resume, "Continue an interrupted adaptation in --out exactly");
  cmd->add_option("--stop-after", o->stop_after, "Stop after this step (checkpointed), as if interrupted")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--out", o->out, "The adapted model folder (created if missing)")->required();
  cmd->callback([o] {
    std::filesystem::create_directories(o->out);
    auto file = std::make_shared<spdlog::sinks::basic_file_sink_mt>((std::filesystem::path(o->out) / "adapt.log").string());
    spdlog::default_logger()->sinks().push_back(file);
    spdlog::info("weft adapt --model {} --input {} --out {} --iterations {}{}", o->model, o->input, o->out,
                 o->iterations, o->resume ? " --resume" : "");
    std::unique_ptr<ProgressBar> bar;
    std::string stage;
    const capture::AdaptSummary s = capture::adapt_model(*o, [&](const capture::TrainProgress& p) {
      if (p.stage != stage) bar = std::make_unique<ProgressBar>("adapt " + p.stage), stage = p.stage;
      bar->update(int(p.step), int(p.total));
    });
    spdlog::info("adapted on {} frames: steps {}–{} in {:.1f} s{}", s.frames, s.training.first_step,
                 s.training.last_step, s.training.seconds,
                 s.training.simulation_windows ? fmt::format("; {} of {} simulation windows failed", s.training.simulation_failures,
                                                             s.training.simulation_windows)
                                               : std::string());
    spdlog::info("adapted model folder {}: capture with `weft infer --model {}`", o->out, o->out);
    spdlog::default_logger()->sinks().pop_back();
  });
}

}  // namespace weft::apps
