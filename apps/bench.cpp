// `weft bench resnet`: training-step and inference timings of a ResNet, and peak memory
// (see nn/resnet_benchmark.h; bench/resnet_compare.py runs it beside PyTorch).
#include <cstdio>

#include "apps/commands.h"
#include "nn/resnet_benchmark.h"

namespace weft::apps {

void add_bench_command(CLI::App& app) {
  auto* bench = app.add_subcommand("bench", "Benchmarks");
  bench->require_subcommand(1);
  auto* resnet = bench->add_subcommand(
      "resnet", "Time a ResNet training step (forward, backward, Adam) and inference");
  auto o = std::make_shared<nn::ResNetBenchmarkOptions>();
  resnet->add_option("--arch", o->arch, "resnet18, resnet34 or resnet50")
      ->check(CLI::IsMember({"resnet18", "resnet34", "resnet50"}))
      ->capture_default_str();
  resnet->add_option("--batch", o->batch, "Images per step")->capture_default_str();
  resnet->add_option("--size", o->size, "Image height and width, pixels")->capture_default_str();
  resnet->add_option("--outputs", o->outputs, "Size of the linear head")->capture_default_str();
  resnet->add_option("--steps", o->steps, "Timed steps per phase")->capture_default_str();
  resnet->add_option("--warmup", o->warmup, "Untimed steps first")->capture_default_str();
  resnet->add_flag("--breakdown", o->breakdown,
                   "Then where the time goes: each phase again with the ops profiled, the "
                   "mean milliseconds per step of every part, and how much of the step "
                   "they account for");
  resnet->callback([o] {
    const nn::ResNetBenchmarkResult r = nn::benchmark_resnet(*o);
    std::printf("%s, batch %ld, %ldx%ld, %ld parameters, median of %ld steps\n",
                o->arch.c_str(), static_cast<long>(o->batch), static_cast<long>(o->size),
                static_cast<long>(o->size), static_cast<long>(r.parameters),
                static_cast<long>(o->steps));
    std::printf("train step: %.1f ms  (%.1f images/s)\n", r.train_median_ms,
                r.train_images_per_s);
    std::printf("inference:  %.1f ms  (%.1f images/s)\n", r.infer_median_ms,
                r.infer_images_per_s);
    std::printf("peak memory: %.0f MiB  (resident after first/last timed train step: "
                "%.0f / %.0f MiB)\n",
                r.peak_rss_mib, r.rss_first_step_mib, r.rss_last_step_mib);
    if (!o->breakdown) return;
    auto print = [&](const char* phase, const nn::StepBreakdown& b, double median_ms) {
      std::printf("\n%s breakdown, mean ms per step over %ld profiled steps:\n", phase,
                  static_cast<long>(o->steps));
      for (const nn::StepPart& p : b.parts)
        std::printf("  %-38s %8.1f  %5.1f%%\n", p.name.c_str(), p.ms, 100.0 * p.ms / b.step_ms);
      std::printf("  %-38s %8.1f  (the profiled steps timed whole: %.1f ms, %.1f%% accounted; "
                  "the median step above: %.1f ms, %.1f%%)\n",
                  "sum of the parts", b.parts_ms, b.step_ms, 100.0 * b.parts_ms / b.step_ms,
                  median_ms, 100.0 * b.parts_ms / median_ms);
    };
    print("train step", r.train_breakdown, r.train_median_ms);
    print("inference", r.infer_breakdown, r.infer_median_ms);
  });
}

}  // namespace weft::apps
