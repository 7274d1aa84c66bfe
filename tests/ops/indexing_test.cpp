// index_select, gather, scatter_add: values in both dtypes, accumulation of repeated
// indices, gradients, and out-of-range indices caught before any read.
#include <gtest/gtest.h>

#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::expect_error;
using testing::expect_values;
using testing::tol;

class Indexing : public ::testing::TestWithParam<DType> {
 protected:
  Tensor iota(const Shape& s) {
    return Tensor::arange(0, static_cast<double>(shape_numel(s)), 1, GetParam()).view(s);
  }
};

TEST_P(Indexing, IndexSelect) {
  Tensor x = iota({3, 2});
  expect_values(ops::index_select(x, 0, Tensor::from_indices({3}, {2, 0, 2})), {4, 5, 0, 1, 4, 5}, 0);
  Tensor y = ops::index_select(iota({2, 3}), -1, Tensor::from_indices({2}, {1, 1}));
  EXPECT_EQ(y.shape(), (Shape{2, 2}));
  expect_values(y, {1, 1, 4, 4}, 0);
  // Repeated indices accumulate their gradients.
  Tensor leaf = iota({3, 2});
  leaf.set_requires_grad();
  ops::sum(ops::index_select(leaf, 0, Tensor::from_indices({3}, {2, 0, 2}))).backward();
  expect_values(leaf.grad(), {1, 1, 0, 0, 2, 2}, 0);
}

TEST_P(Indexing, GatherLikePyTorch) {
  // out[i][j] = x[index[i][j]][j] on axis 0; out[i][j] = x[i][index[i][j]] on axis 1.
  Tensor x = iota({3, 3});
  expect_values(ops::gather(x, 0, Tensor::from_indices({2, 3}, {2, 0, 1, 0, 0, 2})),
                {6, 1, 5, 0, 1, 8}, 0);
  Tensor g1 = ops::gather(x, 1, Tensor::from_indices({3, 2}, {0, 0, 2, 1, 1, 2}));
  EXPECT_EQ(g1.shape(), (Shape{3, 2}));
  expect_values(g1, {0, 0, 5, 4, 7, 8}, 0);
  Tensor leaf = iota({3, 3});
  leaf.set_requires_grad();
  ops::sum(ops::gather(leaf, 1, Tensor::from_indices({3, 2}, {0, 0, 2, 1, 1, 2}))).backward();
  expect_values(leaf.grad(), {2, 0, 0, 0, 1, 1, 0, 1, 1}, 0);
}

TEST_P(Indexing, ScatterAddAccumulates) {
  const DType d = GetParam();
  Tensor x = Tensor::zeros({3, 2}, d);
  Tensor src = Tensor::from_data({3, 2}, {1, 2, 3, 4, 5, 6}, d);
  Tensor index = Tensor::from_indices({3, 2}, {0, 2, 0, 1, 2, 2});
  // out[index[i][j]][j] += src[i][j]
  expect_values(ops::scatter_add(x, 0, index, src), {4, 0, 0, 4, 5, 8}, tol(d));
  // Gradients: x gets g; src gets g gathered at the same positions.
  Tensor lx = Tensor::ones({3, 2}, d), ls = src.clone();
  lx.set_requires_grad();
  ls.set_requires_grad();
  Tensor g = Tensor::from_data({3, 2}, {10, 20, 30, 40, 50, 60}, d);
  ops::scatter_add(lx, 0, index, ls).backward(g);
  expect_values(lx.grad(), {10, 20, 30, 40, 50, 60}, tol(d));
  expect_values(ls.grad(), {10, 60, 10, 40, 50, 60}, tol(d));
}

INSTANTIATE_TEST_SUITE_P(Dtypes, Indexing, ::testing::Values(DType::F32, DType::F64),
                         testing::dtype_label);

TEST(IndexingErrors, OutOfRangeIndexNamesOpValueAndShape) {
  Tensor x = Tensor::ones({3, 2});
  expect_error([&] { ops::index_select(x, 0, Tensor::from_indices({2}, {1, 3})); },
               {"index_select", "index 3", "[3, 2]"});
  expect_error([&] { ops::index_select(x, 1, Tensor::from_indices({1}, {-1})); },
               {"index_select", "index -1", "[3, 2]"});
  expect_error([&] { ops::index_select(x, 2, Tensor::from_indices({1}, {0})); },
               {"index_select", "axis 2", "[3, 2]"});
  expect_error([&] { ops::index_select(x, 0, Tensor::ones({2})); },
               {"index_select", "int64", "float32 [2]"});
  expect_error([&] { ops::index_select(x, 0, Tensor::from_indices({1, 1}, {0})); },
               {"index_select", "1-D", "[1, 1]", "[3, 2]"});
  expect_error([&] { ops::gather(x, 0, Tensor::from_indices({1, 2}, {0, 7})); },
               {"gather", "index 7", "[3, 2]"});
  expect_error([&] { ops::gather(x, 0, Tensor::from_indices({2}, {0, 1})); },
               {"gather", "[2]", "[3, 2]"});
  expect_error([&] { ops::gather(x, 0, Tensor::from_indices({1, 3}, {0, 0, 0})); },
               {"gather", "[1, 3]", "[3, 2]"});
  expect_error(
      [&] { ops::scatter_add(x, 1, Tensor::from_indices({1, 1}, {2}), Tensor::ones({1, 1})); },
      {"scatter_add", "index 2", "[3, 2]"});
  expect_error(
      [&] { ops::scatter_add(x, 0, Tensor::from_indices({2, 2}, {0, 0, 0, 0}), Tensor::ones({1, 2})); },
      {"scatter_add", "[2, 2]", "[1, 2]"});
  expect_error(
      [&] { ops::scatter_add(x, 0, Tensor::from_indices({1, 1}, {0}), Tensor::ones({1, 1}, DType::F64)); },
      {"scatter_add", "float64 [1, 1]", "float32 [3, 2]"});
}

}  // namespace
}  // namespace weft
