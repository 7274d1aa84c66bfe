// matmul and linear: hand-computed products in both dtypes, parity with a naive loop on
// larger and many-small shapes (both threading paths), gradients, bad shapes.
#include <gtest/gtest.h>

#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::expect_error;
using testing::expect_values;
using testing::tol;

// Reference: [B,n,k]@[B,k,m] (B = 1 for 2-D) by three loops in double.
std::vector<double> naive_matmul(const Tensor& a, const Tensor& b, int64_t batch, int64_t n,
                                 int64_t k, int64_t m, bool shared_b) {
  const std::vector<double> va = a.to_vector(), vb = b.to_vector();
  std::vector<double> out(static_cast<size_t>(batch * n * m), 0.0);
  for (int64_t s = 0; s < batch; ++s)
    for (int64_t i = 0; i < n; ++i)
      for (int64_t j = 0; j < m; ++j) {
        double acc = 0;
        for (int64_t r = 0; r < k; ++r)
          acc += va[(s * n + i) * k + r] * vb[(shared_b ? 0 : s * k * m) + r * m + j];
        out[(s * n + i) * m + j] = acc;
      }
  return out;
}

class Matmul : public ::testing::TestWithParam<DType> {};

TEST_P(Matmul, SmallProductsByHand) {
  const DType d = GetParam();
  Tensor a = Tensor::from_data({2, 3}, {1, 2, 3, 4, 5, 6}, d);
  Tensor b = Tensor::from_data({3, 2}, {7, 8, 9, 10, 11, 12}, d);
  expect_values(ops::matmul(a, b), {58, 64, 139, 154}, tol(d));
  Tensor ab = Tensor::from_data({2, 1, 2}, {1, 2, 3, 4}, d);
  Tensor bb = Tensor::from_data({2, 2, 1}, {5, 6, 7, 8}, d);
  Tensor c = ops::matmul(ab, bb);
  EXPECT_EQ(c.shape(), (Shape{2, 1, 1}));
  expect_values(c, {17, 53}, tol(d));
  Tensor shared = ops::matmul(ab, Tensor::from_data({2, 2}, {1, 0, 0, 2}, d));
  EXPECT_EQ(shared.shape(), (Shape{2, 1, 2}));
  expect_values(shared, {1, 4, 3, 8}, tol(d));
}

TEST_P(Matmul, MatchesNaiveLoops) {
  const DType d = GetParam();
  Generator g(7);
  const double t = d == DType::F32 ? 1e-5 : 1e-12;
  Tensor a = Tensor::randn({37, 53}, g, d), b = Tensor::randn({53, 29}, g, d);
  expect_values(ops::matmul(a, b), naive_matmul(a, b, 1, 37, 53, 29, false), t);
  // Many tiny products take the split-over-threads path; a few big ones use Eigen's.
  Tensor sa = Tensor::randn({600, 4, 5}, g, d), sb = Tensor::randn({600, 5, 3}, g, d);
  expect_values(ops::matmul(sa, sb), naive_matmul(sa, sb, 600, 4, 5, 3, false), t);
  Tensor la = Tensor::randn({2, 40, 50}, g, d), lb = Tensor::randn({2, 50, 33}, g, d);
  expect_values(ops::matmul(la, lb), naive_matmul(la, lb, 2, 40, 50, 33, false), t);
  Tensor wb = Tensor::randn({50, 7}, g, d);
  expect_values(ops::matmul(la, wb), naive_matmul(la, wb, 2, 40, 50, 7, true), t);
}

TEST_P(Matmul, GradientsByHand) {
  const DType d = GetParam();
  Tensor a = Tensor::from_data({1, 2}, {1, 2}, d);
  Tensor b = Tensor::from_data({2, 2}, {3, 4, 5, 6}, d);
  a.set_requires_grad();
  b.set_requires_grad();
  ops::matmul(a, b).backward(Tensor::from_data({1, 2}, {1, -1}, d));
  expect_values(a.grad(), {3 - 4, 5 - 6}, tol(d));   // g·bᵀ
  expect_values(b.grad(), {1, -1, 2, -2}, tol(d));   // aᵀ·g
}

TEST_P(Matmul, LinearWithAndWithoutBias) {
  const DType d = GetParam();
  Tensor x = Tensor::from_data({2, 1, 2}, {1, 2, 3, 4}, d);
  Tensor w = Tensor::from_data({3, 2}, {1, 0, 0, 1, 1, 1}, d);
  Tensor b = Tensor::from_data({3}, {10, 20, 30}, d);
  Tensor y = ops::linear(x, w, b);
  EXPECT_EQ(y.shape(), (Shape{2, 1, 3}));
  expect_values(y, {11, 22, 33, 13, 24, 37}, tol(d));
  expect_values(ops::linear(Tensor::from_data({2}, {1, 2}, d), w), {1, 2, 3}, tol(d));
  // dX = G·W, dW = Gᵀ·X, db = Σ rows of G.
  x.set_requires_grad();
  w.set_requires_grad();
  b.set_requires_grad();
  ops::linear(x, w, b).backward(Tensor::from_data({2, 1, 3}, {1, 0, 1, 0, 1, 0}, d));
  expect_values(x.grad(), {2, 1, 0, 1}, tol(d));
  expect_values(w.grad(), {1, 2, 3, 4, 1, 2}, tol(d));
  expect_values(b.grad(), {1, 1, 1}, tol(d));
}

INSTANTIATE_TEST_SUITE_P(Dtypes, Matmul, ::testing::Values(DType::F32, DType::F64),
                         testing::dtype_label);

TEST(MatmulErrors, BadShapesNameOpAndBothShapes) {
  Tensor a = Tensor::ones({2, 3});
  expect_error([&] { ops::matmul(a, a); }, {"matmul", "[2, 3]", "inner"});
  expect_error([&] { ops::matmul(Tensor::ones({2, 2, 3}), Tensor::ones({3, 3, 2})); },
               {"matmul", "[2, 2, 3]", "[3, 3, 2]", "batch"});
  expect_error([&] { ops::matmul(a, Tensor::ones({3})); }, {"matmul", "[2, 3]", "[3]"});
  expect_error([&] { ops::matmul(a, Tensor::ones({3, 2}, DType::F64)); },
               {"matmul", "float32 [2, 3]", "float64 [3, 2]"});
  expect_error([&] { ops::linear(a, Tensor::ones({4, 2})); }, {"linear", "[2, 3]", "[4, 2]"});
  expect_error([&] { ops::linear(a, Tensor::ones({4, 3}), Tensor::ones({3})); },
               {"linear", "bias [3]", "[4, 3]"});
  expect_error([&] { ops::linear(a, Tensor::ones({4, 3}, DType::F64)); },
               {"linear", "float32 [2, 3]", "float64 [4, 3]"});
}

}  // namespace
}  // namespace weft
