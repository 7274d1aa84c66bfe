// Shape ops: values in both dtypes, which results share storage, gradients, bad input.
#include <gtest/gtest.h>

#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::expect_error;
using testing::expect_values;
using testing::tol;

class ShapeOps : public ::testing::TestWithParam<DType> {
 protected:
  Tensor iota(const Shape& s) {
    return Tensor::arange(0, static_cast<double>(shape_numel(s)), 1, GetParam()).view(s);
  }
};

TEST_P(ShapeOps, ReshapeSharesStorage) {
  Tensor x = iota({2, 3});
  Tensor y = ops::reshape(x, {3, -1});
  EXPECT_EQ(y.shape(), (Shape{3, 2}));
  EXPECT_TRUE(y.shares_storage(x));
  expect_values(y, {0, 1, 2, 3, 4, 5}, 0);
  // Also when recorded for backward; the gradient comes back in the input's shape.
  Tensor leaf = iota({2, 3});
  leaf.set_requires_grad();
  Tensor r = ops::reshape(leaf, {6});
  EXPECT_TRUE(r.shares_storage(leaf));
  ops::sum(ops::mul(r, r)).backward();
  EXPECT_EQ(leaf.grad().shape(), (Shape{2, 3}));
  expect_values(leaf.grad(), {0, 2, 4, 6, 8, 10}, tol(GetParam()));
}

TEST_P(ShapeOps, SliceSharesOnlyContiguousBlocks) {
  Tensor x = iota({4, 3});
  Tensor rows = ops::slice(x, 0, 1, 3);
  EXPECT_TRUE(rows.shares_storage(x));
  expect_values(rows, {3, 4, 5, 6, 7, 8}, 0);
  Tensor cols = ops::slice(x, 1, 1, 3);
  EXPECT_FALSE(cols.shares_storage(x));
  expect_values(cols, {1, 2, 4, 5, 7, 8, 10, 11}, 0);
  Tensor stepped = ops::slice(x, 0, 0, 4, 2);
  EXPECT_FALSE(stepped.shares_storage(x));
  expect_values(stepped, {0, 1, 2, 6, 7, 8}, 0);
  // Earlier axes of size 1 keep the block contiguous.
  Tensor y = iota({1, 5, 2});
  Tensor inner = ops::slice(y, 1, 2, 4);
  EXPECT_TRUE(inner.shares_storage(y));
  expect_values(inner, {4, 5, 6, 7}, 0);
  // Negative bounds count from the end.
  expect_values(ops::slice(x, 1, -2, -1), {1, 4, 7, 10}, 0);
  expect_values(ops::slice(x, 1, 0, 3, 2), {0, 2, 3, 5, 6, 8, 9, 11}, 0);
}

TEST_P(ShapeOps, SliceBackwardScattersIntoZeros) {
  Tensor x = iota({2, 5});
  x.set_requires_grad();
  ops::slice(x, 1, 1, 5, 2).backward(Tensor::from_data({2, 2}, {1, 2, 3, 4}, GetParam()));
  expect_values(x.grad(), {0, 1, 0, 2, 0, 0, 3, 0, 4, 0}, 0);
}

TEST_P(ShapeOps, PermuteAndTransposeCopy) {
  Tensor x = iota({2, 3, 2});
  Tensor p = ops::permute(x, {2, 0, 1});
  EXPECT_EQ(p.shape(), (Shape{2, 2, 3}));
  EXPECT_FALSE(p.shares_storage(x));
  // p[k][i][j] = x[i][j][k] = 6i + 2j + k
  expect_values(p, {0, 2, 4, 6, 8, 10, 1, 3, 5, 7, 9, 11}, 0);
  Tensor t = ops::transpose(iota({2, 3}), 0, -1);
  EXPECT_EQ(t.shape(), (Shape{3, 2}));
  expect_values(t, {0, 3, 1, 4, 2, 5}, 0);
  Tensor leaf = iota({2, 3});
  leaf.set_requires_grad();
  ops::transpose(leaf, 0, 1).backward(Tensor::from_data({3, 2}, {1, 2, 3, 4, 5, 6}, GetParam()));
  expect_values(leaf.grad(), {1, 3, 5, 2, 4, 6}, 0);
}

TEST_P(ShapeOps, ConcatAndStack) {
  Tensor a = iota({2, 2});
  Tensor b = Tensor::full({2, 1}, 9, GetParam());
  Tensor c = ops::concat({a, b}, 1);
  EXPECT_EQ(c.shape(), (Shape{2, 3}));
  expect_values(c, {0, 1, 9, 2, 3, 9}, 0);
  expect_values(ops::concat({a, iota({1, 2})}, 0), {0, 1, 2, 3, 0, 1}, 0);
  Tensor s = ops::stack({a, a}, 1);
  EXPECT_EQ(s.shape(), (Shape{2, 2, 2}));
  expect_values(s, {0, 1, 0, 1, 2, 3, 2, 3}, 0);
  Tensor last = ops::stack({a, ops::neg(a)}, -1);
  EXPECT_EQ(last.shape(), (Shape{2, 2, 2}));
  expect_values(last, {0, 0, 1, -1, 2, -2, 3, -3}, 0);
  // Gradients split back into the pieces.
  Tensor la = iota({2, 2}), lb = iota({2, 1});
  la.set_requires_grad();
  lb.set_requires_grad();
  ops::concat({la, lb}, 1).backward(Tensor::from_data({2, 3}, {1, 2, 3, 4, 5, 6}, GetParam()));
  expect_values(la.grad(), {1, 2, 4, 5}, 0);
  expect_values(lb.grad(), {3, 6}, 0);
}

TEST_P(ShapeOps, StopGradientAliasesAndBlocks) {
  Tensor x = iota({3});
  x.set_requires_grad();
  Tensor s = ops::stop_gradient(x);
  EXPECT_TRUE(s.shares_storage(x));
  EXPECT_FALSE(s.requires_grad());
  ops::sum(ops::mul(x, s)).backward();  // d/dx (x · const x) = const x
  expect_values(x.grad(), {0, 1, 2}, 0);
}

INSTANTIATE_TEST_SUITE_P(Dtypes, ShapeOps, ::testing::Values(DType::F32, DType::F64),
                         testing::dtype_label);

TEST(ShapeLarge, ThreadedPermuteAndSliceMatchNaiveLoops) {
  // Large enough for the copies to split over threads.
  const int64_t A = 6, B = 70, C = 300;
  Tensor x = Tensor::arange(0, static_cast<double>(A * B * C), 1, DType::F64).view({A, B, C});
  x.set_requires_grad();
  Tensor p = ops::permute(x, {2, 0, 1});
  const std::vector<double> pv = p.to_vector();
  bool ok = true;
  for (int64_t c = 0; c < C; ++c)
    for (int64_t a = 0; a < A; ++a)
      for (int64_t b = 0; b < B; ++b) ok &= pv[(c * A + a) * B + b] == double((a * B + b) * C + c);
  EXPECT_TRUE(ok);
  Tensor s = ops::slice(x, 2, 1, C, 3);  // 100 of 300 columns
  const std::vector<double> sv = s.to_vector();
  for (int64_t a = 0; a < A && ok; ++a)
    for (int64_t b = 0; b < B; ++b)
      for (int64_t k = 0; k < 100; ++k) ok &= sv[(a * B + b) * 100 + k] == double((a * B + b) * C + 1 + 3 * k);
  EXPECT_TRUE(ok);
  ops::sum(s).backward();
  const std::vector<double> gv = x.grad().to_vector();
  double total = 0;
  for (int64_t i = 0; i < A * B * C; ++i) {
    total += gv[i];
    ok &= gv[i] == ((i % C) % 3 == 1 ? 1.0 : 0.0);
  }
  EXPECT_TRUE(ok);
  EXPECT_EQ(total, double(A * B * 100));
}

TEST(ShapeErrors, BadInputNamesOpAndShapes) {
  Tensor x = Tensor::ones({2, 3});
  expect_error([&] { ops::reshape(x, {4}); }, {"reshape", "[2, 3]", "[4]"});
  expect_error([&] { ops::permute(x, {0, 0}); }, {"permute", "[2, 3]"});
  expect_error([&] { ops::permute(x, {0}); }, {"permute", "[2, 3]"});
  expect_error([&] { ops::transpose(x, 0, 2); }, {"transpose", "axis 2", "[2, 3]"});
  expect_error([&] { ops::slice(x, 1, 0, 4); }, {"slice", "out of bounds", "[2, 3]"});
  expect_error([&] { ops::slice(x, 2, 0, 1); }, {"slice", "axis 2", "[2, 3]"});
  expect_error([&] { ops::slice(x, 0, 0, 2, 0); }, {"slice", "step 0", "[2, 3]"});
  expect_error([&] { ops::concat({x, Tensor::ones({3, 3})}, 1); }, {"concat", "[2, 3]", "[3, 3]"});
  expect_error([&] { ops::concat({x, Tensor::ones({2, 3}, DType::F64)}, 0); },
               {"concat", "float32 [2, 3]", "float64 [2, 3]"});
  expect_error([&] { ops::concat({x, x}, 5); }, {"concat", "axis 5", "[2, 3]"});
  expect_error([&] { ops::stack({x, Tensor::ones({3, 2})}, 0); }, {"stack", "[2, 3]", "[3, 2]"});
  expect_error([&] { ops::stack({x, x}, 3); }, {"stack", "axis 3", "[2, 3]"});
}

}  // namespace
}  // namespace weft
