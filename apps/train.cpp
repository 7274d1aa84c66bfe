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
#include "graph/atomic_file.h"
#include "capture/training/split_evaluation.h"
#include "capture/training/trainer.h"
#include "graph/error.h"
#include "graph/threads.h"
#include "nn/process_group.h"

namespace weft::apps {

namespace {

void run_evaluation(const capture::TrainOptions& o, const std::string& split) {
  namespace fs = std::filesystem;
  const fs::path model = fs::path(o.run) / "model.safetensors";
  WEFT_CHECK(fs::exists(model), model.string(), ": no trained model (train the run to its end first)");
  spdlog::info("evaluating {} on the {} split of {}", model.string(), split, o.data);
  const capture::SplitEvaluation e = capture::evaluate_split(o.config, o.data, model.string(), split);
  const std::string out = (fs::path(o.run) / ("evaluation_" + split + ".json")).string();
  weft::write_text_atomically(out, e.to_json());
  spdlog::info("{} frames × {} views ({:.1f} s){}: keypoints {:.2f} px (mean pose with the true root rotation {:.2f}), "
               "joints {:.1f} mm, root-relative {:.1f} mm (mean pose with the true root rotation {:.1f}), root rotation "
               "{:.1f}° mean, {:.1f}° median, {:.1f} % above 45° (heading {:.1f}° median, {:.1f} % above 45°); silhouette IoU {:.4f} (template {:.4f}); cloth {:.1f} mm, Chamfer {:.1f} mm (PADefNet off {:.1f}, "
               "the template skinned by the true pose {:.1f}), body {:.1f} mm",
               e.frames, e.views, e.seconds, e.oracle_pose ? " under the oracle pose" : "", e.keypoint_error_px,
               e.mean_pose_keypoint_error_px, e.joint_error_mm, e.joint_error_root_relative_mm,
               e.mean_pose_joint_error_root_relative_mm, e.root_rotation_error_deg, e.root_rotation_median_deg,
               100 * e.root_rotation_above_45, e.root_heading_median_deg, 100 * e.root_heading_above_45,
               e.silhouette_iou,
               e.template_silhouette_iou, e.cloth_error_mm, e.chamfer_mm, e.template_cloth_error_mm,
               e.skinned_true_pose_cloth_error_mm, e.body_error_mm);
  spdlog::info("penetration {:.2f} mm mean over the vertices inside, {:.3f} over all, {:.2f} max, {:.2f} % of cloth "
               "vertices; out-of-balance over {} frames: mean {:.3g} N ({:.3g} m g), p95 {:.3g}, p99 {:.3g}, max {:.3g} N; "
               "outside the body mean {:.3g} N; terms: inertia {:.3g}, elastic {:.3g}, collision {:.3g}, friction {:.3g} N",
               e.penetration_mean_mm, e.penetration_mean_all_mm, e.penetration_max_mm, 100 * e.penetrating_fraction,
               e.oob_frames, e.oob_n.mean, e.oob_rel.mean, e.oob_n.p95, e.oob_n.p99, e.oob_n.max, e.oob_outside_n.mean,
               e.inertia_mean_n, e.elastic_mean_n, e.collision_mean_n, e.friction_mean_n);
  spdlog::info("wrote {}", out);
}

void train_and_report(const capture::TrainOptions& o) {
  std::unique_ptr<ProgressBar> bar;
  std::string bar_stage;
  const capture::TrainSummary s = capture::train(o, [&](const capture::TrainProgress& p) {
    if (p.stage != bar_stage) bar = std::make_unique<ProgressBar>(p.stage), bar_stage = p.stage;
    bar->update(int(p.step), int(p.total));
  });
  spdlog::info("trained steps {}–{} in {:.1f} s ({:.2f} s/step){}", s.first_step, s.last_step, s.seconds,
               s.seconds / std::max<int64_t>(1, s.last_step - s.first_step + 1),
               s.simulation_windows ? fmt::format("; {} of {} simulation windows had a failed step (their converged frames kept)",
                                                  s.simulation_failures, s.simulation_windows)
                                    : std::string());
  for (const auto& [status, count] : s.failure_statuses)
    spdlog::info("  simulation windows that stopped with '{}': {}", status, count);
  spdlog::info("run folder {}: losses.csv, losses.png, validation.csv, checkpoints/, train.log", o.run);
}

// Under mpirun every rank runs this; rank 0 alone logs (train.log, the progress bar) and
// writes files. An error on any rank ends the whole job with the rank's name.
void run_train(const capture::TrainOptions& o) {
  nn::ProcessGroup& group = nn::ProcessGroup::world();
  if (!group.is_root()) spdlog::set_level(spdlog::level::warn);
  std::filesystem::create_directories(o.run);
  if (group.is_root()) {
    auto file = std::make_shared<spdlog::sinks::basic_file_sink_mt>((std::filesystem::path(o.run) / "train.log").string());
    spdlog::default_logger()->sinks().push_back(file);
  }
  spdlog::info("weft train --config {} --data {} --out {}{} ({} thread{} per rank{})", o.config, o.data, o.run,
               o.resume ? " --resume" : "", num_threads(), num_threads() == 1 ? "" : "s",
               group.distributed() ? fmt::format(", {} ranks", group.size()) : std::string());
  try {
    train_and_report(o);
  } catch (const std::exception& e) {
    if (group.distributed()) {
      spdlog::error("{}: {}", group.describe(), e.what());
      spdlog::default_logger()->flush();
      group.abort("");
    }
    group.finalize();
    throw;  // main logs it, to train.log too (the file sink stays)
  }
  if (group.is_root()) spdlog::default_logger()->sinks().pop_back();
  group.finalize();
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
  cmd->add_option("--init", o->init_weights,
                  "Start from these weights (a model.safetensors or checkpoint of the same networks) instead of a "
                  "fresh initialisation, e.g. to branch several physics-stage runs from one warm start")
      ->check(CLI::ExistingFile);
  cmd->add_option("--stop-after", o->stop_after, "Stop after this global step (checkpointed), as if interrupted")
      ->check(CLI::NonNegativeNumber);
  auto threads = std::make_shared<int>(0);
  cmd->add_option("--threads", *threads,
                  "Threads of this process (under mpirun: per rank) for OpenMP and TBB; 0: the global --threads, "
                  "WEFT_NUM_THREADS or all cores. With N ranks on a machine of C cores, use C / N")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--parameter-checksums", o->parameter_checksums,
                "Write RUN/parameters.csv: per step a checksum of both networks' parameters and batch-norm "
                "statistics (under mpirun every step checks that all ranks hold the same)");
  auto evaluate = std::make_shared<std::string>();
  cmd->add_option("--evaluate", *evaluate,
                  "Instead of training: measure RUN/model.safetensors on this split of --data (e.g. test) against "
                  "its 3D ground truth (keypoints, joints, silhouette IoU, penetration, out-of-balance force); "
                  "writes RUN/evaluation_SPLIT.json");
  cmd->footer(
      "\nOn a cluster (docs/TRAINING.md, \"On a cluster\"): mpirun -np N weft train ... --threads T runs N\n"
      "data-parallel ranks: each computes a shard of every batch and the gradients are averaged\n"
      "(MPI all-reduce); rank 0 writes the run folder, which must be on a file system all ranks see.");
  cmd->callback([o, evaluate, threads] {
    if (*threads > 0) set_num_threads(*threads);
    if (!evaluate->empty())
      run_evaluation(*o, *evaluate);
    else
      run_train(*o);
  });
}

}  // namespace weft::apps
