#pragma once
// Times a ResNet training step (forward, MSE loss, backward, Adam) and inference (eval
// mode, no graph) on random data: the work behind `weft bench resnet`. Figures are medians
// over the timed steps, after warm-up steps; memory is the process's resident set.
#include <cstdint>
#include <string>
#include <vector>

namespace weft::nn {

struct ResNetBenchmarkOptions {
  std::string arch = "resnet50";
  int64_t batch = 8, size = 128, in_channels = 3, outputs = 1000;
  int64_t steps = 10, warmup = 2;  // timed steps and untimed warm-up steps, per phase
  uint64_t seed = 0;
  // After the timed steps, `steps` more of each phase with per-op timing on, for the
  // breakdown below (not part of the medians above).
  bool breakdown = false;
};

// Where a step's time goes: mean milliseconds per step of each part. The parts are
// measured, not derived, except the "outside ops" ones: the wall time of the forward
// or backward pass minus the ops timed inside it (graph building, the autograd engine's
// bookkeeping, allocation between ops).
struct StepPart {
  std::string name;
  double ms = 0;
};
struct StepBreakdown {
  std::vector<StepPart> parts;
  double parts_ms = 0;  // their sum
  double step_ms = 0;   // mean wall time of the same steps, timed as a whole
};

struct ResNetBenchmarkResult {
  std::vector<double> train_ms, infer_ms;  // every timed step
  double train_median_ms = 0, infer_median_ms = 0;
  double train_images_per_s = 0, infer_images_per_s = 0;
  double peak_rss_mib = 0;  // the process's peak resident set (getrusage)
  // Resident set after the first and the last timed training step: growth means a leak.
  double rss_first_step_mib = 0, rss_last_step_mib = 0;
  int64_t parameters = 0;
  StepBreakdown train_breakdown, infer_breakdown;  // when options.breakdown
};

ResNetBenchmarkResult benchmark_resnet(const ResNetBenchmarkOptions& options);

}  // namespace weft::nn
