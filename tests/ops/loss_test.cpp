// Losses: values by hand in both dtypes, gradients, exact-shape requirement.
#include <gtest/gtest.h>

#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::expect_error;
using testing::expect_values;
using testing::tol;

class Loss : public ::testing::TestWithParam<DType> {};

TEST_P(Loss, ValuesByHand) {
  const DType d = GetParam();
  // d = pred − target = [0.5, -2, 0, 3]
  Tensor p = Tensor::from_data({2, 2}, {1.5, -1, 2, 4}, d);
  Tensor t = Tensor::from_data({2, 2}, {1, 1, 2, 1}, d);
  expect_values(ops::mse_loss(p, t), {(0.25 + 4 + 0 + 9) / 4}, tol(d));
  expect_values(ops::l1_loss(p, t), {(0.5 + 2 + 0 + 3) / 4}, tol(d));
  // beta 1: 0.5·0.25, 2 − 0.5, 0, 3 − 0.5
  expect_values(ops::smooth_l1_loss(p, t), {(0.125 + 1.5 + 0 + 2.5) / 4}, tol(d));
  // beta 2: 0.5·0.25/2, 2 − 1 (|d| = beta is the linear branch), 0, 3 − 1
  expect_values(ops::smooth_l1_loss(p, t, 2.0), {(0.0625 + 1 + 0 + 2) / 4}, tol(d));
  // beta 0 is the L1 loss.
  expect_values(ops::smooth_l1_loss(p, t, 0.0), ops::l1_loss(p, t).to_vector(), tol(d));
  EXPECT_EQ(ops::mse_loss(p, t).dim(), 0);
}

TEST_P(Loss, GradientsByHand) {
  const DType d = GetParam();
  Tensor p = Tensor::from_data({4}, {1.5, -1, 2, 4}, d);
  Tensor t = Tensor::from_data({4}, {1, 1, 2.5, 1}, d);
  p.set_requires_grad();
  t.set_requires_grad();
  ops::mse_loss(p, t).backward();  // 2d/n
  expect_values(p.grad(), {0.25, -1, -0.25, 1.5}, tol(d));
  expect_values(t.grad(), {-0.25, 1, 0.25, -1.5}, tol(d));
  p.zero_grad();
  ops::smooth_l1_loss(p, t).backward();  // d/beta inside, sign(d) outside, over n
  expect_values(p.grad(), {0.125, -0.25, -0.125, 0.25}, tol(d));
  p.zero_grad();
  ops::l1_loss(p, t).backward();
  expect_values(p.grad(), {0.25, -0.25, -0.25, 0.25}, tol(d));
}

INSTANTIATE_TEST_SUITE_P(Dtypes, Loss, ::testing::Values(DType::F32, DType::F64),
                         testing::dtype_label);

TEST(LossErrors, ShapesMustMatchExactly) {
  Tensor p = Tensor::ones({2, 3});
  // Broadcastable is not enough: a loss of mismatched shapes is almost always a bug.
  expect_error([&] { ops::mse_loss(p, Tensor::ones({3})); }, {"mse_loss", "[2, 3]", "[3]"});
  expect_error([&] { ops::l1_loss(p, Tensor::ones({3, 2})); }, {"l1_loss", "[2, 3]", "[3, 2]"});
  expect_error([&] { ops::smooth_l1_loss(p, Tensor::ones({2, 3}, DType::F64)); },
               {"smooth_l1_loss", "float32 [2, 3]", "float64 [2, 3]"});
  expect_error([&] { ops::smooth_l1_loss(p, p, -1.0); }, {"smooth_l1_loss", "beta", "[2, 3]"});
}

}  // namespace
}  // namespace weft
