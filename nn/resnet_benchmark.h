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
};

struct ResNetBenchmarkResult {
  std::vector<double> train_ms, infer_ms;  // every timed step
  double train_median_ms = 0, infer_median_ms = 0;
  double train_images_per_s = 0, infer_images_per_s = 0;
  double peak_rss_mib = 0;  // the process's peak resident set (getrusage)
  // Resident set after the first and the last timed training step: growth means a leak.
  double rss_first_step_mib = 0, rss_last_step_mib = 0;
  int64_t parameters = 0;
};

ResNetBenchmarkResult benchmark_resnet(const ResNetBenchmarkOptions& options);

}  // namespace weft::nn
