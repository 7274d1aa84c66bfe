// `weft engine-check`: the autodiff engine alone, in seconds: it trains a small
// multilayer perceptron on a synthetic regression task (y = sin(2x₁)·cos(x₂)) and prints
// the falling loss. A check that a build's engine learns, not a demo of capture (that is
// scripts/demo.sh).
#include <spdlog/spdlog.h>

#include <chrono>
#include <cmath>

#include "apps/commands.h"
#include "graph/autograd.h"
#include "graph/op_registry.h"
#include "ops/ops.h"

namespace weft::apps {
namespace {

struct EngineCheckOptions {
  int steps = 300;
  int hidden = 64;
  int batch = 256;
  double learning_rate = 0.05;
  uint64_t seed = 1;
};

// Targets of the synthetic task for inputs x [N, 2] in [-1, 1]².
Tensor target_of(const Tensor& x) {
  const int64_t n = x.size(0);
  Tensor y = Tensor::empty({n, 1});
  const float* px = x.data<float>();
  float* py = y.data<float>();
  for (int64_t i = 0; i < n; ++i) py[i] = std::sin(2 * px[2 * i]) * std::cos(px[2 * i + 1]);
  return y;
}

void run_engine_check(const EngineCheckOptions& o) {
  spdlog::info("weft engine-check: {} ops registered ({} differentiable); training a 2-{}-{}-1 tanh "
               "MLP on y = sin(2x1)*cos(x2)",
               OpRegistry::instance().all().size(),
               [] {
                 int n = 0;
                 for (auto* op : OpRegistry::instance().all()) n += op->differentiable;
                 return n;
               }(),
               o.hidden, o.hidden);
  Generator gen(o.seed);
  auto param = [&](Shape s, double fan_in) {
    Tensor t = Tensor::randn(s, gen, DType::F32, 0.0, 1.0 / std::sqrt(fan_in));
    t.set_requires_grad();
    return t;
  };
  std::vector<Tensor> params = {param({o.hidden, 2}, 2),         param({o.hidden}, 2),
                                param({o.hidden, o.hidden}, o.hidden), param({o.hidden}, o.hidden),
                                param({1, o.hidden}, o.hidden),  param({1}, o.hidden)};
  auto model = [&](const Tensor& x) {
    Tensor h = ops::tanh(ops::linear(x, params[0], params[1]));
    h = ops::tanh(ops::linear(h, params[2], params[3]));
    return ops::linear(h, params[4], params[5]);
  };
  const Tensor x_val = Tensor::rand({1024, 2}, gen, DType::F32, -1, 1);
  const Tensor y_val = target_of(x_val);
  auto validation_loss = [&] {
    NoGradGuard no_grad;
    return ops::mse_loss(model(x_val), y_val).item();
  };

  // Plain SGD with momentum 0.9, written out: the engine is the point here.
  std::vector<Tensor> velocity;
  for (auto& p : params) velocity.push_back(Tensor::zeros(p.shape()));
  const double first = validation_loss();
  spdlog::info("step {:4d}  validation MSE {:.5f}", 0, first);
  const auto start = std::chrono::steady_clock::now();
  for (int step = 1; step <= o.steps; ++step) {
    const Tensor x = Tensor::rand({o.batch, 2}, gen, DType::F32, -1, 1);
    Tensor loss = ops::mse_loss(model(x), target_of(x));
    for (auto& p : params) p.zero_grad();
    loss.backward();
    NoGradGuard no_grad;
    for (size_t i = 0; i < params.size(); ++i) {
      float* v = velocity[i].data<float>();
      float* w = params[i].data<float>();
      const float* g = params[i].grad().data<float>();
      for (int64_t k = 0; k < params[i].numel(); ++k) {
        v[k] = 0.9f * v[k] + g[k];
        w[k] -= static_cast<float>(o.learning_rate) * v[k];
      }
    }
    if (step % (o.steps / 10) == 0)
      spdlog::info("step {:4d}  training MSE {:.5f}  validation MSE {:.5f}", step, loss.item(),
                   validation_loss());
  }
  const double ms = std::chrono::duration<double, std::milli>(
                        std::chrono::steady_clock::now() - start).count();
  const double last = validation_loss();
  spdlog::info("done: validation MSE {:.5f} -> {:.5f} ({:.0f}x lower) in {} steps, {:.2f} ms/step",
               first, last, first / last, o.steps, ms / o.steps);
}

}  // namespace

void add_engine_check_command(CLI::App& app) {
  static EngineCheckOptions o;
  auto* cmd = app.add_subcommand(
      "engine-check",
      "Check the autodiff engine in seconds: train a small MLP on a synthetic regression task\n"
      "(y = sin(2 x1) cos(x2)) and print the falling loss. The capture demo is scripts/demo.sh.");
  cmd->add_option("--steps", o.steps, "Training steps")->check(CLI::Range(10, 100000));
  cmd->add_option("--hidden", o.hidden, "Hidden units per layer")->check(CLI::Range(1, 4096));
  cmd->add_option("--batch", o.batch, "Batch size")->check(CLI::Range(1, 65536));
  cmd->add_option("--lr", o.learning_rate, "SGD learning rate (momentum 0.9)");
  cmd->add_option("--seed", o.seed, "Random seed");
  cmd->callback([] { run_engine_check(o); });
}

}  // namespace weft::apps
