#include "nn/optim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "graph/error.h"
#include "nn/schedule.h"

namespace weft::nn {
namespace {

// Three steps on p = [1, -2, 0.5] (float64) with fixed gradients; `expected` was printed
// by torch 1.13's torch.optim on the same inputs.
void check_three_steps(const std::function<std::unique_ptr<Optimizer>(std::vector<NamedTensor>)>& make,
                       const std::vector<double>& expected) {
  Tensor p = Tensor::from_data({3}, std::vector<double>{1.0, -2.0, 0.5}, DType::F64);
  p.set_requires_grad();
  auto opt = make({{"p", p}});
  const std::vector<std::vector<double>> grads{{0.5, -0.25, 2.0}, {0.1, 0.3, -1.0}, {-0.7, 0.0, 0.4}};
  for (const auto& g : grads) {
    p.set_grad(Tensor::from_data({3}, g, DType::F64));
    opt->step();
  }
  const std::vector<double> got = p.to_vector();
  for (size_t i = 0; i < 3; ++i) EXPECT_NEAR(got[i], expected[i], 1e-14) << i;
  EXPECT_EQ(opt->state().at("p.step").item(), 3.0);
}

TEST(Optim, SGDMatchesTorch) {
  auto sgd = [](SGDOptions o) {
    return [o](std::vector<NamedTensor> ps) { return std::make_unique<SGD>(ps, o); };
  };
  SGDOptions o;
  o.lr = 0.1;
  check_three_steps(sgd(o), {1.01, -2.005, 0.36000000000000004});
  o.momentum = 0.9;
  o.weight_decay = 0.1;
  check_three_steps(sgd(o), {0.8618739999999999, -1.8786555000000003, 0.08676949999999997});
  o.nesterov = true;
  check_three_steps(sgd(o), {0.860319646, -1.8385872345, -0.015504209500000013});
  o.nesterov = false;
  o.weight_decay = 0;
  o.dampening = 0.5;
  check_three_steps(sgd(o), {0.8899999999999999, -1.96075, 0.03299999999999997});
  o.nesterov = true;
  EXPECT_THROW(sgd(o)({}), Error);  // Nesterov needs zero dampening
}

TEST(Optim, AdamAndAdamWMatchTorch) {
  AdamOptions a;
  a.lr = 0.1;
  auto adam = [](AdamOptions o) {
    return [o](std::vector<NamedTensor> ps) { return std::make_unique<Adam>(ps, o); };
  };
  check_three_steps(adam(a), {0.8348226348691605, -1.9253441451669422, 0.34184194029891996});
  a.weight_decay = 0.1;
  a.beta1 = 0.8;
  a.beta2 = 0.99;
  a.eps = 1e-3;
  check_three_steps(adam(a), {0.8231508344313706, -1.8029860677992096, 0.3461075719267839});

  auto adamw = [](AdamWOptions o) {
    return [o](std::vector<NamedTensor> ps) { return std::make_unique<AdamW>(ps, o); };
  };
  AdamWOptions w;
  w.lr = 0.1;
  EXPECT_EQ(w.weight_decay, 0.01);  // PyTorch's default
  check_three_steps(adamw(w), {0.8321058379607779, -1.9195357486863984, 0.340569973501718});
  w.weight_decay = 0.5;
  w.eps = 1e-3;
  check_three_steps(adamw(w), {0.7063238380142086, -1.6493911793617608, 0.28169624944493615});
  a.beta2 = 1.0;
  EXPECT_THROW(adam(a)({}), Error);
}

TEST(Optim, StepsInPlaceWithoutAllocatingAndSkipsMissingGradients) {
  Tensor p = Tensor::ones({1000});
  p.set_requires_grad();
  Tensor q = Tensor::ones({2});
  q.set_requires_grad();
  AdamW opt({{"p", p}, {"q", q}}, {});
  const TensorMap state = opt.state();
  p.set_grad(Tensor::full({1000}, 0.5));
  const void* p_data = p.raw_data();
  const void* g_data = p.grad().raw_data();
  const void* m_data = state.at("p.exp_avg").raw_data();
  for (int k = 0; k < 3; ++k) {
    opt.zero_grad();
    p.grad().fill(0.5);
    opt.step();
  }
  EXPECT_EQ(p.raw_data(), p_data);
  EXPECT_EQ(p.grad().raw_data(), g_data);  // zero_grad zeroes in place
  EXPECT_EQ(opt.state().at("p.exp_avg").raw_data(), m_data);
  EXPECT_LT(p.at({0}), 1.0);
  EXPECT_EQ(q.to_vector(), (std::vector<double>{1, 1}));  // no gradient: untouched
  EXPECT_EQ(opt.state().at("q.step").item(), 0.0);
  EXPECT_EQ(opt.state().at("p.step").item(), 3.0);
  opt.zero_grad(/*set_to_none=*/true);
  EXPECT_FALSE(p.grad().defined());

  Tensor not_leaf_grad = Tensor::ones({2});
  EXPECT_THROW(SGD({{"x", not_leaf_grad}}, {}), Error);  // does not require grad
  EXPECT_THROW(SGD({{"p", p}, {"p", p}}, {}), Error);
  EXPECT_THROW(opt.set_lr(-1), Error);
}

TEST(Optim, LoadStateChecksBeforeCopying) {
  Tensor p = Tensor::ones({3});
  p.set_requires_grad();
  Adam opt({{"w", p}}, {});
  TensorMap good;
  for (const auto& [k, t] : opt.state()) good[k] = Tensor::full(t.shape(), 2.0, t.dtype());
  TensorMap bad = good;
  bad["w.exp_avg_sq"] = Tensor::zeros({4});
  EXPECT_THROW(opt.load_state(bad, "ckpt"), Error);
  EXPECT_EQ(opt.state().at("w.exp_avg").to_vector(), (std::vector<double>{0, 0, 0}));
  bad = good;
  bad.erase("w.step");
  EXPECT_THROW(opt.load_state(bad, "ckpt"), Error);
  opt.load_state(good, "ckpt");
  EXPECT_EQ(opt.state().at("w.exp_avg").to_vector(), (std::vector<double>{2, 2, 2}));
}

TEST(Optim, ClipGradNormScalesAllGradientsTogether) {
  Tensor a = Tensor::zeros({2}, DType::F64), b = Tensor::zeros({1}, DType::F64);
  a.set_requires_grad();
  b.set_requires_grad();
  a.set_grad(Tensor::from_data({2}, std::vector<double>{3, 4}, DType::F64));
  b.set_grad(Tensor::from_data({1}, std::vector<double>{12}, DType::F64));
  const std::vector<NamedTensor> ps{{"a", a}, {"b", b}};
  EXPECT_DOUBLE_EQ(clip_grad_norm(ps, 100.0), 13.0);
  EXPECT_EQ(b.grad().item(), 12.0);  // below the limit: unchanged
  EXPECT_DOUBLE_EQ(clip_grad_norm(ps, 6.5), 13.0);
  const double c = 6.5 / (13.0 + 1e-6);
  EXPECT_DOUBLE_EQ(a.grad().at({1}), 4.0 * c);
  EXPECT_DOUBLE_EQ(b.grad().item(), 12.0 * c);
  EXPECT_THROW(clip_grad_norm(ps, 0.0), Error);
}

TEST(Schedule, StepCosineAndWarmup) {
  StepLR step(0.1, 3, 0.5);
  EXPECT_DOUBLE_EQ(step.lr(0), 0.1);
  EXPECT_DOUBLE_EQ(step.lr(2), 0.1);
  EXPECT_DOUBLE_EQ(step.lr(3), 0.05);
  EXPECT_DOUBLE_EQ(step.lr(7), 0.025);
  auto cosine = std::make_shared<CosineLR>(1.0, 10, 0.1);
  EXPECT_DOUBLE_EQ(cosine->lr(0), 1.0);
  EXPECT_DOUBLE_EQ(cosine->lr(5), 0.55);
  EXPECT_DOUBLE_EQ(cosine->lr(10), 0.1);
  EXPECT_DOUBLE_EQ(cosine->lr(25), 0.1);
  WarmupLR warm(cosine, 4, 0.25);
  EXPECT_DOUBLE_EQ(warm.lr(0), 0.25);
  EXPECT_DOUBLE_EQ(warm.lr(2), 0.625);
  EXPECT_DOUBLE_EQ(warm.lr(4), 1.0);
  EXPECT_DOUBLE_EQ(warm.lr(9), 0.55);
  EXPECT_DOUBLE_EQ(ConstantLR(0.3).lr(100), 0.3);
  EXPECT_THROW(step.lr(-1), Error);
  EXPECT_THROW(StepLR(0.1, 0), Error);
  EXPECT_THROW(WarmupLR(nullptr, 3), Error);
}

}  // namespace
}  // namespace weft::nn
