// Unary ops and where: forward values in both dtypes, hand-derived gradients, bad input.
#include <gtest/gtest.h>

#include <cmath>

#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::expect_error;
using testing::expect_values;
using testing::tol;

class Unary : public ::testing::TestWithParam<DType> {
 protected:
  Tensor t(const Shape& s, std::vector<double> v) { return Tensor::from_data(s, v, GetParam()); }
};

TEST_P(Unary, MathFunctions) {
  const double e = std::exp(1.0);
  const DType d = GetParam();
  expect_values(ops::exp(t({2}, {0, 1})), {1, e}, tol(d));
  expect_values(ops::log(t({2}, {1, e})), {0, 1}, tol(d));
  expect_values(ops::sqrt(t({3}, {0, 4, 2.25})), {0, 2, 1.5}, tol(d));
  expect_values(ops::pow(t({3}, {2, -3, 0.5}), 3), {8, -27, 0.125}, tol(d));
  expect_values(ops::pow(t({2}, {4, 9}), 0.5), {2, 3}, tol(d));
  expect_values(ops::abs(t({3}, {-2, 0, 1.5})), {2, 0, 1.5}, tol(d));
  expect_values(ops::sin(t({2}, {0, M_PI / 2})), {0, 1}, tol(d));
  expect_values(ops::cos(t({2}, {0, M_PI})), {1, -1}, tol(d));
  expect_values(ops::neg(t({2}, {1, -2})), {-1, 2}, tol(d));
}

TEST_P(Unary, ClampAndActivations) {
  const DType d = GetParam();
  expect_values(ops::clamp(t({4}, {-2, -0.5, 0.3, 7}), -1, 0.5), {-1, -0.5, 0.3, 0.5}, tol(d));
  expect_values(ops::relu(t({3}, {-1, 0, 2})), {0, 0, 2}, tol(d));
  expect_values(ops::sigmoid(t({3}, {0, -1000, 1000})), {0.5, 0, 1}, tol(d));
  expect_values(ops::sigmoid(t({1}, {2})), {1 / (1 + std::exp(-2.0))}, tol(d));
  expect_values(ops::tanh(t({2}, {0, 1})), {0, std::tanh(1.0)}, tol(d));
  // softplus: log 2 at 0; exactly x above the threshold; beta scales inside and out.
  expect_values(ops::softplus(t({3}, {0, 30, -30})), {std::log(2.0), 30, std::exp(-30.0)}, tol(d));
  expect_values(ops::softplus(t({2}, {0.25, 0.8}), 2.0, 1.0),
                {std::log1p(std::exp(0.5)) / 2, 0.8}, tol(d));
  for (double v : ops::sigmoid(t({2}, {-1000, 1000})).to_vector()) EXPECT_FALSE(std::isnan(v));
}

TEST_P(Unary, GradientsByHand) {
  Tensor x = t({4}, {-2, -0.25, 0.25, 2});
  x.set_requires_grad();
  Tensor y = ops::add(ops::relu(x), ops::clamp(x, -1, 1));  // relu' + clamp'
  y.backward(Tensor::ones({4}, GetParam()));
  expect_values(x.grad(), {0, 1, 2, 1}, tol(GetParam()));

  Tensor z = t({2}, {0.5, -1});
  z.set_requires_grad();
  ops::tanh(z).backward(Tensor::ones({2}, GetParam()));
  expect_values(z.grad(), {1 - std::pow(std::tanh(0.5), 2), 1 - std::pow(std::tanh(-1.0), 2)},
                tol(GetParam()));

  Tensor w = t({2}, {0.0, 25.0});
  w.set_requires_grad();
  ops::softplus(w).backward(Tensor::ones({2}, GetParam()));
  expect_values(w.grad(), {0.5, 1}, tol(GetParam()));
}

TEST_P(Unary, WhereBroadcastsAllThree) {
  const DType d = GetParam();
  Tensor cond = Tensor::from_indices({2, 1}, {1, 0});
  Tensor a = t({3}, {1, 2, 3});
  Tensor b = t({}, {-1});
  Tensor out = ops::where(cond, a, b);
  EXPECT_EQ(out.shape(), (Shape{2, 3}));
  expect_values(out, {1, 2, 3, -1, -1, -1}, tol(d));
  // A float condition works the same way; gradients split by the mask, none to cond.
  Tensor fc = t({3}, {0, 2.5, 0});
  Tensor fa = t({3}, {1, 2, 3});
  Tensor fb = t({2, 3}, {4, 5, 6, 7, 8, 9});
  fa.set_requires_grad();
  fb.set_requires_grad();
  Tensor y = ops::where(fc, fa, fb);
  expect_values(y, {4, 2, 6, 7, 2, 9}, tol(d));
  y.backward(Tensor::ones({2, 3}, d));
  expect_values(fa.grad(), {0, 2, 0}, tol(d));
  expect_values(fb.grad(), {1, 0, 1, 1, 0, 1}, tol(d));
}

INSTANTIATE_TEST_SUITE_P(Dtypes, Unary, ::testing::Values(DType::F32, DType::F64),
                         testing::dtype_label);

TEST(UnaryErrors, BadInputNamesOpAndShapes) {
  Tensor idx = Tensor::from_indices({2}, {1, 2});
  expect_error([&] { ops::exp(idx); }, {"exp", "int64 [2]"});
  Tensor x = Tensor::ones({2, 3});
  expect_error([&] { ops::clamp(x, 1, -1); }, {"clamp", "float32 [2, 3]"});
  expect_error([&] { ops::softplus(x, 0.0); }, {"softplus", "[2, 3]"});
  expect_error([&] { ops::where(Tensor::ones({2}), x, Tensor::ones({2, 3}, DType::F64)); },
               {"where", "float32 [2, 3]", "float64 [2, 3]"});
  expect_error([&] { ops::where(Tensor::ones({4}), x, x); }, {"where", "[4]", "[2, 3]"});
}

}  // namespace
}  // namespace weft
