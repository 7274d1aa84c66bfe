// `weft train`: trains PoseNet and PADefNet on a dataset in the method's three stages
// (capture/training/trainer.h; docs/TRAINING.md), with a progress bar, a log in RUN/train.log,
// losses.csv and losses.png, validation and checkpoints; --resume continues a stopped run.
#include <spdlog/sinks/basic_file_sink.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "capture/training/trainer.h"

namespace weft::apps {

namespace {

void run_train(const capture::TrainOptions& o) {
  std::filesystem::create_directories(o.run);
  auto file = std::make_shared<spdlog::sinks::basic_file_sink_mt>((std::filesystem::path(o.run) / "train.log").string());
  spdlog::default_logger()->sinks().push_back(file);
  spdlog::info("weft train --config {} --data {} --out {}{}", o.config, o.data, o.run, o.resume ? " --resume" : "");
  std::unique_ptr<ProgressBar> bar;
  std::string bar_stage;
  const capture::TrainSummary s = capture::train(o, [&](const capture::TrainProgress& p) {
    if (p.stage != bar_stage) bar = std::make_unique<ProgressBar>(p.stage), bar_stage = p.stage;
    bar->update(int(p.step), int(p.total));
  });
  spdlog::info("trained steps {}–{} in {:.1f} s ({:.2f} s/step){}", s.first_step, s.last_step, s.seconds,
               s.seconds / std::max<int64_t>(1, s.last_step - s.first_step + 1),
               s.simulation_windows ? fmt::format("; {} of {} simulation windows failed and were dropped",
                                                  s.simulation_failures, s.simulation_windows)
                                    : std::string());
  for (const auto& [status, count] : s.failure_statuses)
    spdlog::info("  simulation windows that stopped with '{}': {}", status, count);
  spdlog::info("run folder {}: losses.csv, losses.png, validation.csv, checkpoints/, train.log", o.run);
  spdlog::default_logger()->sinks().pop_back();
}

}  // namespace

void add_train_command(CLI::App& app) {
  auto o = std::make_shared<capture::TrainOptions>();
  auto* cmd = app.add_subcommand(
      "train",
      "Train the method's networks on a multi-view dataset (a `weft synth` dataset or a studio\n"
      "recording laid out the same way): (a) PoseNet on the 2D keypoints of every view, (b)\n"
      "PADefNet's warm start on silhouettes, keypoints, ARAP and attachment with PoseNet frozen,\n"
      "(c) the physics-aware stage with the cloth simulator rolled over short windows from the\n"
      "networks' own predictions. Writes RUN/losses.csv, losses.png, validation.csv, train.log,\n"
      "checkpoints/ and model.safetensors. Config keys and the data layout: docs/TRAINING.md.");
  cmd->add_option("--config", o->config, "Training config, e.g. configs/train/default.yaml")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--data", o->data, "Dataset folder (holds dataset.yaml)")->required()->check(CLI::ExistingDirectory);
  cmd->add_option("--out", o->run, "Run folder (created if missing)")->required();
  cmd->add_flag("--resume", o->resume, "Continue the run in --out from its last checkpoint, exactly");
  cmd->add_option("--stop-after", o->stop_after, "Stop after this global step (checkpointed), as if interrupted")
      ->check(CLI::NonNegativeNumber);
  cmd->callback([o] { run_train(*o); });
}

}  // namespace weft::apps
