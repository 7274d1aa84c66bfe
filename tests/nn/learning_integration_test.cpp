// "It learns": a small residual network (the ResNet BasicBlock, batch norm, Adam with
// warm-up and cosine decay, gradient clipping) regresses the position and orientation of
// a rendered bar from 32×32 images, and its validation error falls at least tenfold.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numbers>

#include "graph/autograd.h"
#include "nn/optim.h"
#include "nn/resnet.h"
#include "nn/schedule.h"
#include "ops/ops.h"

namespace weft::nn {
namespace {

constexpr int64_t kSize = 32;

// A soft-edged bar (length 14 px, half-width 1.5 px) centred at (cx, cy) px at angle θ;
// targets: centre in [-1, 1] and (cos 2θ, sin 2θ), which is continuous in θ mod π.
void render_batch(Generator& gen, int64_t n, Tensor& images, Tensor& targets) {
  images = Tensor::zeros({n, 1, kSize, kSize});
  targets = Tensor::zeros({n, 4});
  float* img = images.data<float>();
  float* tgt = targets.data<float>();
  for (int64_t i = 0; i < n; ++i) {
    const double cx = gen.uniform(9, 23), cy = gen.uniform(9, 23);
    const double theta = gen.uniform(0, std::numbers::pi);
    const double dx = std::cos(theta), dy = std::sin(theta);
    for (int64_t y = 0; y < kSize; ++y)
      for (int64_t x = 0; x < kSize; ++x) {
        const double px = x + 0.5 - cx, py = y + 0.5 - cy;
        const double along = std::clamp(px * dx + py * dy, -7.0, 7.0);
        const double dist = std::hypot(px - along * dx, py - along * dy);
        img[(i * kSize + y) * kSize + x] = static_cast<float>(std::clamp(2.0 - dist, 0.0, 1.0));
      }
    tgt[i * 4 + 0] = static_cast<float>((cx - 16) / 7);
    tgt[i * 4 + 1] = static_cast<float>((cy - 16) / 7);
    tgt[i * 4 + 2] = static_cast<float>(std::cos(2 * theta));
    tgt[i * 4 + 3] = static_cast<float>(std::sin(2 * theta));
  }
}

class SmallResNet : public Module {
 public:
  explicit SmallResNet(Generator& gen) : Module("SmallResNet") {
    Conv2dSpec stem{.in_channels = 1, .out_channels = 16, .kernel = 3, .stride = 1,
                    .padding = 1, .init = ConvInit::kaiming_normal_fan_out};
    conv1 = register_module("conv1", std::make_shared<Conv2d>(stem, gen));
    bn1 = register_module("bn1", std::make_shared<BatchNorm2d>(16));
    layer1 = register_module("layer1", std::make_shared<BasicBlock>(16, 16, 2, &gen, DType::F32));
    layer2 = register_module("layer2", std::make_shared<BasicBlock>(16, 32, 2, &gen, DType::F32));
    layer3 = register_module("layer3", std::make_shared<BasicBlock>(32, 64, 2, &gen, DType::F32));
    fc = register_module("fc", std::make_shared<Linear>(64, 4, gen));
  }
  Tensor forward(const Tensor& x) override {
    Tensor y = ops::relu(bn1->forward(conv1->forward(x)));
    y = layer3->forward(layer2->forward(layer1->forward(y)));
    return fc->forward(ops::global_avg_pool2d(y));
  }
  std::shared_ptr<Conv2d> conv1;
  std::shared_ptr<BatchNorm2d> bn1;
  std::shared_ptr<BasicBlock> layer1, layer2, layer3;
  std::shared_ptr<Linear> fc;
};

double validation_error(SmallResNet& net, const Tensor& images, const Tensor& targets) {
  NoGradGuard no_grad;
  net.eval();
  const double e = ops::mse_loss(net.forward(images), targets).item();
  net.train();
  return e;
}

TEST(ItLearns, BarPositionAndAngleErrorFallsTenfold) {
  Generator gen(2024);
  SmallResNet net(gen);
  Tensor val_x, val_y;
  render_batch(gen, 128, val_x, val_y);

  constexpr int64_t kMaxSteps = 400, kBatch = 32;
  AdamOptions ao;
  ao.lr = 3e-3;
  Adam opt(net.named_parameters(), ao);
  WarmupLR schedule(std::make_shared<CosineLR>(ao.lr, kMaxSteps - 20, 1e-4), 20, 0.1);

  const double initial = validation_error(net, val_x, val_y);
  double best = initial;
  int64_t steps = 0;
  const auto start = std::chrono::steady_clock::now();
  while (steps < kMaxSteps && best > initial / 10) {
    Tensor x, y;
    render_batch(gen, kBatch, x, y);
    opt.set_lr(schedule.lr(steps));
    opt.zero_grad();
    Tensor loss = ops::mse_loss(net.forward(x), y);
    loss.backward();
    clip_grad_norm(opt.params(), 5.0);
    opt.step();
    ++steps;
    if (steps % 25 == 0) {
      best = std::min(best, validation_error(net, val_x, val_y));
      std::printf("step %3ld  train %.4f  validation %.4f\n", static_cast<long>(steps),
                  loss.item(), best);
    }
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("validation MSE %.4f -> %.4f in %ld steps (%.1f s)\n", initial, best,
              static_cast<long>(steps), seconds);
  EXPECT_GT(initial, 0.2);  // the task is not trivial for an untrained network
  EXPECT_LT(best, initial / 10) << "after " << steps << " steps";
}

}  // namespace
}  // namespace weft::nn
