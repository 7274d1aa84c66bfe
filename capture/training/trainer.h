#pragma once
// The staged trainer behind `weft train` (docs/TRAINING.md): PoseNet on L_lm, then
// PADefNet's warm start (L_sil + L_lm + L_arap + L_att, PoseNet frozen), then the
// physics-aware stage (L_sil + L_lm + L_sim + L_att) with the simulator rolled over short
// windows that start from the networks' own predictions, all in one process and graph.
//
// A run folder RUN holds: config.yaml (the config it was started with), train.log,
// losses.csv and losses.png (every step's loss terms), validation.csv (every validation),
// checkpoints/step_NNNNNNN.safetensors (the last K; model, optimiser, step, stage) and
// model.safetensors (the networks' weights at the end). Resuming continues from the last
// checkpoint exactly as a run that was never stopped: batches and windows are functions
// of (seed, step), the optimiser's state and the batch-norm statistics are in the
// checkpoint, and losses.csv is cut back to the checkpoint's step.
//
// Under mpirun the trainer is data-parallel (nn/data_parallel.h; docs/TRAINING.md, "On a
// cluster"): every rank computes its shards of each global batch, the gradients and the
// batch-norm statistics are averaged over the shards with MPI all-reduces, and rank 0
// alone writes the run folder.
#include <cstdint>
#include <functional>
#include <limits>
#include <map>
#include <string>

#include "capture/training/training_config.h"

namespace weft::capture {

struct TrainOptions {
  std::string config;   // configs/train/NAME.yaml
  std::string data;     // a `weft synth` dataset or a studio recording laid out the same way
  std::string run;      // the run folder
  bool resume = false;  // continue from RUN's last checkpoint (RUN must hold one)
  int64_t stop_after = -1;  // stop after this global step (tests; −1: train to the end)
  // Start from these weights (model.safetensors or a checkpoint of the same networks)
  // instead of a fresh initialisation: domain adaptation refines a trained model. A
  // resumed run ignores it (its checkpoint holds the weights).
  std::string init_weights;
  // Write RUN/parameters.csv: per step a checksum of every parameter and batch-norm
  // statistic (data-parallel runs check that all ranks hold the same).
  bool parameter_checksums = false;
};

struct TrainProgress {
  int64_t step = 0, total = 0;
  std::string stage;
  std::map<std::string, double> terms;  // this step's loss terms
};

struct ValidationReport {
  int64_t step = 0;
  int samples = 0;
  double keypoint_error_px = 0;   // mean 2D keypoint error over all views (full-image px)
  double joint_error_mm = -1;     // mean 3D BODY_25 error against gt/pose.motion (−1: no ground truth)
  // The same with both pivot joints at the origin (the articulated pose alone), and the
  // root orientation's geodesic error over the samples: median and fraction above 45°
  // (front/back confusion). NaN: not measured (no ground truth; the rotation under oracle_pose).
  double joint_error_root_relative_mm = std::numeric_limits<double>::quiet_NaN();
  double root_rotation_median_deg = std::numeric_limits<double>::quiet_NaN();
  double root_rotation_above_45 = std::numeric_limits<double>::quiet_NaN();
  // The heading error's (the turn about the vertical alone: front/back confusion).
  double root_heading_median_deg = std::numeric_limits<double>::quiet_NaN();
  double root_heading_above_45 = std::numeric_limits<double>::quiet_NaN();
  double silhouette_iou = 0;      // predicted body+cloth vs mask, mean over samples × views
  double penetration_mean_mm = 0; // mean depth of cloth vertices inside the body (over those inside)
  double penetration_max_mm = 0;
  double penetrating_fraction = 0;  // cloth vertices inside the body / all
};

struct TrainSummary {
  int64_t first_step = 1, last_step = 0;  // the steps this call ran
  double seconds = 0;
  int simulation_windows = 0, simulation_failures = 0;  // windows with a failed step (their converged frames still count)
  std::map<std::string, int> failure_statuses;  // per failed window, its first failed step's status
  ValidationReport last_validation;
};

// Runs (or resumes) training; errors (bad config, missing file, non-finite loss) are
// weft::Errors naming the file, the key or the step, and leave the last good checkpoint.
TrainSummary train(const TrainOptions& options,
                   const std::function<void(const TrainProgress&)>& progress = {});

// Validation of the networks stored in a checkpoint or weights file on one split.
ValidationReport validate_checkpoint(const std::string& config, const std::string& data,
                                     const std::string& weights, const std::string& split, int samples);

}  // namespace weft::capture
