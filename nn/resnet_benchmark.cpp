#include "nn/resnet_benchmark.h"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>

#include "graph/autograd.h"
#include "graph/error.h"
#include "graph/profiler.h"
#include "nn/optim.h"
#include "nn/resnet.h"
#include "ops/ops.h"

namespace weft::nn {

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double current_rss_mib() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  statm >> pages_total >> pages_resident;
  return static_cast<double>(pages_resident) * static_cast<double>(::sysconf(_SC_PAGESIZE)) /
         (1024.0 * 1024.0);
}

double peak_rss_mib() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;  // kilobytes on Linux
}

template <class Fn>
double time_ms(Fn&& fn) {
  const auto t0 = std::chrono::steady_clock::now();
  fn();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Ops that get a line of their own in a breakdown; the rest are summed as "other ops".
bool listed_op(const std::string& op) {
  for (const char* name : {"conv2d", "conv2d_affine", "batch_norm", "relu", "add", "max_pool2d",
                           "linear", "(gradient accumulation)"})
    if (op == name) return true;
  return false;
}

// Adds the profile recorded since the last reset (one pass) to `parts`: its ops, and the
// pass's wall time not spent in them.
void add_pass(std::map<std::string, double>& parts, const char* pass, bool backward,
              double pass_ms) {
  double inside = 0;
  for (const ProfileEntry& e : profile_entries()) {
    if (e.backward != backward) continue;
    inside += e.ms;
    parts[std::string(pass) + ": " + (listed_op(e.op) ? e.op : "other ops")] += e.ms;
  }
  parts[std::string(pass) + ": outside ops"] += pass_ms - inside;
  reset_profile();
}

StepBreakdown finish(const std::map<std::string, double>& sums, double step_sum, int64_t steps) {
  StepBreakdown b;
  for (const auto& [name, ms] : sums) b.parts.push_back({name, ms / static_cast<double>(steps)});
  std::sort(b.parts.begin(), b.parts.end(), [](auto& a, auto& c) { return a.ms > c.ms; });
  for (const StepPart& p : b.parts) b.parts_ms += p.ms;
  b.step_ms = step_sum / static_cast<double>(steps);
  return b;
}

}  // namespace

ResNetBenchmarkResult benchmark_resnet(const ResNetBenchmarkOptions& o) {
  if (o.batch <= 0 || o.size < 32 || o.steps <= 0 || o.warmup < 0)
    fail("bench resnet: need batch > 0, size >= 32, steps > 0 and warmup >= 0 (got batch ",
         o.batch, ", size ", o.size, ", steps ", o.steps, ", warmup ", o.warmup, ")");
  ResNetOptions ro;
  ro.in_channels = o.in_channels;
  ro.outputs = o.outputs;
  ro.seed = o.seed;
  auto net = make_resnet(o.arch, ro);
  Adam opt(net->named_parameters(), {});
  Generator gen(o.seed + 1);
  const Tensor x = Tensor::randn({o.batch, o.in_channels, o.size, o.size}, gen);
  const Tensor y = Tensor::randn({o.batch, o.outputs}, gen);

  ResNetBenchmarkResult r;
  r.parameters = net->num_parameters();
  net->train();
  for (int64_t i = 0; i < o.warmup + o.steps; ++i) {
    const double ms = time_ms([&] {
      opt.zero_grad();
      ops::mse_loss(net->forward(x), y).backward();
      opt.step();
    });
    if (i < o.warmup) continue;
    r.train_ms.push_back(ms);
    if (i == o.warmup) r.rss_first_step_mib = current_rss_mib();
  }
  r.rss_last_step_mib = current_rss_mib();

  net->eval();
  for (int64_t i = 0; i < o.warmup + o.steps; ++i) {
    const double ms = time_ms([&] {
      NoGradGuard no_grad;
      net->forward(x);
    });
    if (i >= o.warmup) r.infer_ms.push_back(ms);
  }
  if (o.breakdown) {
    // Training steps again, each part timed on its own and the ops profiled.
    const bool was_profiling = profiling_enabled();
    set_profiling(true);
    net->train();
    std::map<std::string, double> train, infer;
    double train_sum = 0, infer_sum = 0;
    for (int64_t i = 0; i < o.steps; ++i) {
      reset_profile();
      const auto t0 = std::chrono::steady_clock::now();
      const double zero_ms = time_ms([&] { opt.zero_grad(); });
      Tensor loss;
      const double fwd_ms = time_ms([&] { loss = ops::mse_loss(net->forward(x), y); });
      add_pass(train, "forward", false, fwd_ms);
      const double bwd_ms = time_ms([&] { loss.backward(); });
      add_pass(train, "backward", true, bwd_ms);
      const double opt_ms = time_ms([&] { opt.step(); });
      loss = Tensor();  // the graph is freed inside the step, as in the timed steps
      train_sum += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      train["zero_grad"] += zero_ms;
      train["optimizer step (Adam)"] += opt_ms;
    }
    net->eval();
    for (int64_t i = 0; i < o.steps; ++i) {
      reset_profile();
      const double ms = time_ms([&] {
        NoGradGuard no_grad;
        net->forward(x);
      });
      add_pass(infer, "forward", false, ms);
      infer_sum += ms;
    }
    set_profiling(was_profiling);
    reset_profile();
    r.train_breakdown = finish(train, train_sum, o.steps);
    r.infer_breakdown = finish(infer, infer_sum, o.steps);
  }
  r.train_median_ms = median(r.train_ms);
  r.infer_median_ms = median(r.infer_ms);
  r.train_images_per_s = 1000.0 * static_cast<double>(o.batch) / r.train_median_ms;
  r.infer_images_per_s = 1000.0 * static_cast<double>(o.batch) / r.infer_median_ms;
  r.peak_rss_mib = peak_rss_mib();
  return r;
}

}  // namespace weft::nn
