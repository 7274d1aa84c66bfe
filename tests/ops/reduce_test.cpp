// Reductions: values in both dtypes over axis sets, keepdim, gradients, bad axes.
#include <gtest/gtest.h>

#include <algorithm>

#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::expect_error;
using testing::expect_values;
using testing::tol;

class Reduce : public ::testing::TestWithParam<DType> {
 protected:
  // x[i][j][k] = 12i + 4j + k for shape [2,3,4].
  Tensor iota234() { return Tensor::arange(0, 24, 1, GetParam()).view({2, 3, 4}); }
};

TEST_P(Reduce, SumOverAxes) {
  const DType d = GetParam();
  const Tensor x = iota234();
  expect_values(ops::sum(x), {276}, tol(d));
  Tensor s1 = ops::sum(x, {1});  // 36i + 12 + 3k
  EXPECT_EQ(s1.shape(), (Shape{2, 4}));
  expect_values(s1, {12, 15, 18, 21, 48, 51, 54, 57}, tol(d));
  Tensor s02 = ops::sum(x, {0, 2}, true);  // Σ_i Σ_k = 2·(4·4j + 6) + 4·12 = 32j + 60
  EXPECT_EQ(s02.shape(), (Shape{1, 3, 1}));
  expect_values(s02, {60, 92, 124}, tol(d));
  expect_values(ops::sum(x, {-1}), {6, 22, 38, 54, 70, 86}, tol(d));
}

TEST_P(Reduce, MeanMaxNorm) {
  const DType d = GetParam();
  const Tensor x = iota234();
  expect_values(ops::mean(x), {11.5}, tol(d));
  expect_values(ops::mean(x, {0, 1}), {10, 11, 12, 13}, tol(d));
  Tensor m = ops::max(x, {1}, true);
  EXPECT_EQ(m.shape(), (Shape{2, 1, 4}));
  expect_values(m, {8, 9, 10, 11, 20, 21, 22, 23}, tol(d));
  expect_values(ops::max(x, {0, 2}), {15, 19, 23}, tol(d));
  Tensor v = Tensor::from_data({2, 2}, {3, 4, 0, 0}, d);
  expect_values(ops::norm(v, {1}), {5, 0}, tol(d));
  expect_values(ops::norm(v), {5}, tol(d));
}

TEST_P(Reduce, MaxGradientGoesToFirstTie) {
  const DType d = GetParam();
  Tensor x = Tensor::from_data({2, 3}, {1, 5, 5, 7, 2, 7}, d);
  x.set_requires_grad();
  ops::max(x, {1}).backward(Tensor::from_data({2}, {10, 20}, d));
  expect_values(x.grad(), {0, 10, 0, 20, 0, 0}, tol(d));
  Tensor y = Tensor::from_data({2, 2}, {4, 4, 4, 4}, d);
  y.set_requires_grad();
  ops::max(y).backward();
  expect_values(y.grad(), {1, 0, 0, 0}, tol(d));
}

TEST_P(Reduce, GradientsByHand) {
  const DType d = GetParam();
  Tensor x = Tensor::from_data({2, 2}, {3, 4, 0, 0}, d);
  x.set_requires_grad();
  // norm' = x/‖x‖ (0 for a zero row); mean' = 1/count.
  Tensor y = ops::add(ops::sum(ops::norm(x, {1})), ops::mean(x));
  y.backward();
  expect_values(x.grad(), {0.6 + 0.25, 0.8 + 0.25, 0.25, 0.25}, tol(d));
}

INSTANTIATE_TEST_SUITE_P(Dtypes, Reduce, ::testing::Values(DType::F32, DType::F64),
                         testing::dtype_label);

TEST(ReduceFloat32, LongSumsKeepPrecision) {
  const int64_t n = 1 << 20;
  Tensor x = Tensor::full({n}, 0.1, DType::F32);
  EXPECT_NEAR(ops::sum(x).item(), 0.1f * n, 1e-2);
  EXPECT_NEAR(ops::mean(x.view({1024, 1024}), {0}).at({7}), 0.1f, 1e-7);
}

TEST(ReduceFloat64, SeveralAxisRunsMatchNaiveLoop) {
  // Axes 0, 2, 3 of an NCHW batch (two separate runs), large enough to run threaded.
  Generator g(3);
  const int64_t N = 4, C = 5, H = 40, W = 50;
  Tensor x = Tensor::randn({N, C, H, W}, g, DType::F64);
  std::vector<double> want(C, 0.0), want_max(C, -1e300);
  const std::vector<double> v = x.to_vector();
  for (int64_t n = 0; n < N; ++n)
    for (int64_t c = 0; c < C; ++c)
      for (int64_t k = 0; k < H * W; ++k) {
        const double e = v[(n * C + c) * H * W + k];
        want[c] += e;
        want_max[c] = std::max(want_max[c], e);
      }
  expect_values(ops::sum(x, {0, 2, 3}), want, 1e-12);
  expect_values(ops::max(x, {0, 2, 3}), want_max, 0);
  Tensor m = ops::mean(x, {0, -1, 2}, true);
  EXPECT_EQ(m.shape(), (Shape{1, C, 1, 1}));
  for (double& w : want) w /= static_cast<double>(N * H * W);
  expect_values(m, want, 1e-12);
}

TEST(ReduceErrors, BadAxesNameOpAndShape) {
  Tensor x = Tensor::ones({2, 3});
  expect_error([&] { ops::sum(x, {2}); }, {"sum", "axis 2", "[2, 3]"});
  expect_error([&] { ops::max(x, {-3}); }, {"max", "axis -3", "[2, 3]"});
  expect_error([&] { ops::mean(x, {1, -1}); }, {"mean", "repeated", "[2, 3]"});
  expect_error([&] { ops::norm(Tensor::from_indices({2}, {1, 2})); }, {"norm", "int64 [2]"});
}

}  // namespace
}  // namespace weft
