// batch_norm in float32 against direct loops in double: forward, backward, running stats.
#include <gtest/gtest.h>

#include <cmath>

#include "graph/error.h"
#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::rel_l2;

struct BnRef {
  std::vector<double> y, gx, gw, gb, mean, var;  // var: biased
};

// x as [N, C, S]. Training: batch statistics and the full chain rule through them,
// written as the plain sum over the channel's M values (no closed form borrowed from the
// implementation): dx_i = Σ_j dy_j ∂y_j/∂x_i.
BnRef reference(const std::vector<double>& x, const std::vector<double>& w,
                const std::vector<double>& b, const std::vector<double>& rm,
                const std::vector<double>& rv, const std::vector<double>& gy, int64_t N,
                int64_t C, int64_t S, bool training, double eps) {
  BnRef r;
  r.y.resize(x.size());
  r.gx.resize(x.size());
  r.gw.assign(C, 0);
  r.gb.assign(C, 0);
  const double M = double(N * S);
  auto idx = [&](int64_t n, int64_t c, int64_t s) { return (n * C + c) * S + s; };
  for (int64_t c = 0; c < C; ++c) {
    double mu = 0, var = 0;
    for (int64_t n = 0; n < N; ++n)
      for (int64_t s = 0; s < S; ++s) mu += x[idx(n, c, s)] / M;
    for (int64_t n = 0; n < N; ++n)
      for (int64_t s = 0; s < S; ++s) var += (x[idx(n, c, s)] - mu) * (x[idx(n, c, s)] - mu) / M;
    r.mean.push_back(mu);
    r.var.push_back(var);
    const double m = training ? mu : rm[c], v = training ? var : rv[c];
    const double sd = std::sqrt(v + eps);
    for (int64_t n = 0; n < N; ++n)
      for (int64_t s = 0; s < S; ++s) {
        const int64_t i = idx(n, c, s);
        const double xh = (x[i] - m) / sd;
        r.y[i] = xh * w[c] + b[c];
        r.gw[c] += gy[i] * xh;
        r.gb[c] += gy[i];
      }
    // ∂y_j/∂x_i = w/sd · (δ_ij − 1/M − xh_i xh_j / M) in training, w/sd · δ_ij in eval.
    for (int64_t n = 0; n < N; ++n)
      for (int64_t s = 0; s < S; ++s) {
        const int64_t i = idx(n, c, s);
        if (!training) {
          r.gx[i] = gy[i] * w[c] / sd;
          continue;
        }
        const double xhi = (x[i] - m) / sd;
        double acc = 0;
        for (int64_t n2 = 0; n2 < N; ++n2)
          for (int64_t s2 = 0; s2 < S; ++s2) {
            const int64_t j = idx(n2, c, s2);
            const double xhj = (x[j] - m) / sd;
            acc += gy[j] * ((i == j ? 1.0 : 0.0) - 1.0 / M - xhi * xhj / M);
          }
        r.gx[i] = acc * w[c] / sd;
      }
  }
  return r;
}

void check(const Shape& shape, bool training) {
  Generator g(11);
  const int64_t N = shape[0], C = shape[1], S = shape_numel(shape) / (N * C);
  Tensor x = Tensor::randn(shape, g, DType::F32, 0.5, 2.0);
  Tensor w = Tensor::rand({C}, g, DType::F32, 0.5, 1.5);
  Tensor b = Tensor::randn({C}, g);
  Tensor rm = Tensor::randn({C}, g, DType::F32, 0.0, 0.3);
  Tensor rv = Tensor::rand({C}, g, DType::F32, 0.5, 2.0);
  const auto rm0 = rm.to_vector(), rv0 = rv.to_vector();
  x.set_requires_grad();
  w.set_requires_grad();
  b.set_requires_grad();
  Tensor y = ops::batch_norm(x, w, b, rm, rv, training, 0.1, 1e-5);
  Tensor gy = Tensor::randn(y.shape(), g);
  y.backward(gy);
  const BnRef r = reference(x.to_vector(), w.to_vector(), b.to_vector(), rm0, rv0,
                            gy.to_vector(), N, C, S, training, 1e-5);
  EXPECT_LE(rel_l2(y.to_vector(), r.y), 1e-5);
  EXPECT_LE(rel_l2(x.grad().to_vector(), r.gx), 1e-5);
  EXPECT_LE(rel_l2(w.grad().to_vector(), r.gw), 1e-5);
  EXPECT_LE(rel_l2(b.grad().to_vector(), r.gb), 1e-5);
  // Running statistics: updated by one training step, untouched in eval.
  const double M = double(N * S);
  for (int64_t c = 0; c < C; ++c) {
    const double want_m = training ? 0.9 * rm0[c] + 0.1 * r.mean[c] : rm0[c];
    const double want_v = training ? 0.9 * rv0[c] + 0.1 * r.var[c] * M / (M - 1) : rv0[c];
    EXPECT_NEAR(rm.at({c}), want_m, 1e-5 * (1 + std::abs(want_m))) << "channel " << c;
    EXPECT_NEAR(rv.at({c}), want_v, 1e-5 * (1 + std::abs(want_v))) << "channel " << c;
  }
}

TEST(BatchNormReference, TrainingNCHW) { check({4, 3, 5, 6}, true); }
TEST(BatchNormReference, TrainingRank2) { check({16, 5}, true); }
TEST(BatchNormReference, TrainingLarge) { check({8, 16, 12, 12}, true); }  // threaded
TEST(BatchNormReference, EvalNCHW) { check({4, 3, 5, 6}, false); }
TEST(BatchNormReference, EvalLarge) { check({8, 16, 12, 12}, false); }

TEST(BatchNormReference, RunningStatsByHand) {
  // One channel, values 1, 2, 3, 6: mean 3, biased var 3.5, unbiased 14/3.
  Tensor x = Tensor::from_data({2, 1, 2}, std::vector<double>{1, 2, 3, 6});
  Tensor rm = Tensor::from_data({1}, std::vector<double>{1.0});
  Tensor rv = Tensor::from_data({1}, std::vector<double>{2.0});
  Tensor y = ops::batch_norm(x, Tensor(), Tensor(), rm, rv, true);
  EXPECT_NEAR(rm.item(), 0.9 * 1.0 + 0.1 * 3.0, 1e-6);
  EXPECT_NEAR(rv.item(), 0.9 * 2.0 + 0.1 * 14.0 / 3.0, 1e-6);
  EXPECT_NEAR(y.at({0, 0, 0}), (1 - 3) / std::sqrt(3.5 + 1e-5), 1e-6);
  // A second step moves them again, from the updated values.
  ops::batch_norm(x, Tensor(), Tensor(), rm, rv, true, 0.5);
  EXPECT_NEAR(rm.item(), 0.5 * 1.2 + 0.5 * 3.0, 1e-6);
  EXPECT_NEAR(rv.item(), 0.5 * (1.8 + 1.4 / 3.0) + 0.5 * 14.0 / 3.0, 1e-5);
}

void expect_error(const std::function<void()>& f, const std::string& what,
                  const std::vector<Shape>& shapes) {
  try {
    f();
    ADD_FAILURE() << "no error for " << what;
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("batch_norm"), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
    for (const Shape& s : shapes) EXPECT_NE(m.find(shape_str(s)), std::string::npos) << m;
  }
}

TEST(BatchNormBadInput, ClearErrors) {
  const Tensor x = Tensor::zeros({2, 3, 4, 4});
  const Tensor c3 = Tensor::ones({3}), c4 = Tensor::ones({4});
  expect_error([&] { ops::batch_norm(x, c4, c3, c3.clone(), c3.clone(), true); },
               "weight must be [3]", {{4}, x.shape()});
  expect_error([&] { ops::batch_norm(x, c3, c3, c3.clone(), c4.clone(), false); },
               "running_var must be [3]", {{4}, x.shape()});
  expect_error(
      [&] { ops::batch_norm(x, c3.to(DType::F64), c3, c3.clone(), c3.clone(), true); },
      "dtype mismatch", {{3}, x.shape()});
  const Tensor one = Tensor::zeros({1, 3, 1, 1});
  expect_error([&] { ops::batch_norm(one, c3, c3, c3.clone(), c3.clone(), true); },
               "more than one value per channel", {one.shape()});
  const Tensor r1 = Tensor::zeros({5});
  expect_error([&] { ops::batch_norm(r1, Tensor(), Tensor(), Tensor(), Tensor(), true); },
               "rank >= 2", {r1.shape()});
}

}  // namespace
}  // namespace weft
