#pragma once
// The oracle pose perturbed as PoseNet errs (training config key oracle_pose_noise): the
// physics claim's quick check (bench/physics_claim.sh) needs a pose that puts the garment
// inside the body, as a predicted pose does, while staying cheap and seeded.
//
// Each listed dof d gets an error b_d + e_d(f) over the motion's frames f: the measured
// bias b_d (PoseNet's mean error: the same on every frame, as a network errs alike on
// alike images) plus a stationary first-order autoregressive process (AR(1)) with the
// measured spread (the error's standard deviation about its mean) and the measured
// correlation time τ (frames):
//   e_d(0) = σ_d·n_0,   e_d(f) = ρ·e_d(f−1) + σ_d·√(1 − ρ²)·n_f,   ρ = exp(−1/τ),
// n_f independent standard normal draws of a generator seeded by (seed, dof). So every
// frame's error has spread σ_d, consecutive frames err alike (as a network's prediction of
// consecutive images does; an independent draw per frame would shake the body inside a
// simulation window), and the whole perturbed motion is a function of the config alone:
// both arms of an experiment, its training and its evaluation see the same poses. The
// perturbed dofs are clamped to their limits (PoseNet's outputs stay inside them,
// capture/model/pose_dofs.h). Dofs not listed (the root chain, locked dofs) keep the truth.
//
// b_d, σ_d and τ come from a trained PoseNet's errors on a validation split: `weft train
// --evaluate val` writes them (evaluation_val.json: dof_errors' mean and std,
// dof_error_correlation_frames)
// and configs/noise/posenet_dof_error.yaml holds the default run's.
//
//   oracle_pose_noise: configs/noise/posenet_dof_error.yaml   # a file holding the mapping below, or:
//   oracle_pose_noise:
//     seed: 1                  # the draws (default 1)
//     scale: 1.0               # multiplies every spread and bias (default 1)
//     correlation_frames: 3.0  # τ (frames; default 1)
//     spread: {l_hip_x: 0.12, ...}  # dof name → standard deviation (radians, or character units for a translation dof)
//     bias: {l_hip_x: 0.05, ...}    # dof name → mean error (optional; a dof may have either or both)
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "capture/character/skeletool_io.h"
#include "capture/character/skeleton.h"
#include "files/strict_yaml.h"

namespace weft::capture {

struct PoseNoiseConfig {
  std::string file;  // where the spread was read from (the training config, or the file it names)
  uint64_t seed = 1;
  double scale = 1.0;
  double correlation_frames = 1.0;
  std::vector<std::pair<std::string, double>> spread;  // dof name → σ (the dof's own units)
  std::vector<std::pair<std::string, double>> bias;    // dof name → b (the dof's own units)
  bool enabled() const { return !spread.empty() || !bias.empty(); }
};

// The mapping (or a file path holding it, relative to y.dir) at `node`; errors name `key`.
PoseNoiseConfig parse_pose_noise(const StrictYaml& y, const YAML::Node& node, const std::string& key);

// `truth` with the errors above added to the listed dofs of every frame (clamped to the
// limits). A listed dof the skeleton does not have is an error naming it and config.file.
Motion perturbed_motion(const Motion& truth, const Skeleton& skeleton, const PoseNoiseConfig& config);

}  // namespace weft::capture
