#include <gtest/gtest.h>

#include "graph/autograd.h"
#include "ops/ops.h"

namespace weft {
namespace {

TEST(Autograd, GradientsAccumulateAcrossBackwardCalls) {
  Tensor x = Tensor::from_data({3}, std::vector<double>{1, 2, 3}, DType::F64);
  x.set_requires_grad();
  for (int k = 0; k < 2; ++k) {
    Tensor y = ops::mul(x, x);  // dy/dx = 2x
    y.backward(Tensor::ones({3}, DType::F64));
  }
  EXPECT_EQ(x.grad().to_vector(), (std::vector<double>{4, 8, 12}));
}

// clear_grad: the gradient reads as zero, the next backward replaces it (not added to),
// the one after adds again; a view of the old buffer keeps the copy path correct.
TEST(Autograd, ClearedGradientIsReplacedByTheNextBackward) {
  Tensor x = Tensor::from_data({3}, std::vector<double>{1, 2, 3}, DType::F64);
  x.set_requires_grad();
  auto square_backward = [&] { ops::mul(x, x).backward(Tensor::ones({3}, DType::F64)); };
  square_backward();
  const Tensor g = x.grad();
  x.clear_grad();
  EXPECT_EQ(x.grad().to_vector(), (std::vector<double>{0, 0, 0}));
  EXPECT_EQ(g.to_vector(), (std::vector<double>{0, 0, 0}));  // the same tensor, zeroed
  x.clear_grad();
  square_backward();
  EXPECT_EQ(x.grad().to_vector(), (std::vector<double>{2, 4, 6}));
  EXPECT_EQ(g.to_vector(), (std::vector<double>{2, 4, 6}));  // still x's gradient tensor
  square_backward();
  EXPECT_EQ(x.grad().to_vector(), (std::vector<double>{4, 8, 12}));
  const Tensor view = x.grad().slice_view(0, 1, 3);  // shares the buffer: copied into, not swapped
  x.clear_grad();
  square_backward();
  EXPECT_EQ(x.grad().to_vector(), (std::vector<double>{2, 4, 6}));
  EXPECT_EQ(view.to_vector(), (std::vector<double>{4, 6}));
}

// A leaf takes a fresh op output as its gradient without copying, but never a tensor
// someone else holds: the output gradient the caller passed, or one shared by two inputs.
TEST(Autograd, LeafGradientNeverAliasesTheCallersTensors) {
  Tensor x = Tensor::from_data({3}, std::vector<double>{1, 2, 3}, DType::F64);
  x.set_requires_grad();
  Tensor gy = Tensor::from_data({3}, std::vector<double>{1, 1, 1}, DType::F64);
  ops::reshape(x, {3}).backward(gy);  // reshape's backward hands gy back
  EXPECT_FALSE(x.grad().shares_storage(gy));
  ops::reshape(x, {3}).backward(gy);  // accumulates into x.grad, not into gy
  EXPECT_EQ(gy.to_vector(), (std::vector<double>{1, 1, 1}));
  EXPECT_EQ(x.grad().to_vector(), (std::vector<double>{2, 2, 2}));

  Tensor a = Tensor::ones({2}, DType::F64), b = Tensor::ones({2}, DType::F64);
  a.set_requires_grad();
  b.set_requires_grad();
  ops::add(a, b).backward(Tensor::ones({2}, DType::F64));  // both receive the same gradient
  EXPECT_FALSE(a.grad().shares_storage(b.grad()));
  ops::mul(a, a).backward(Tensor::ones({2}, DType::F64));
  EXPECT_EQ(a.grad().to_vector(), (std::vector<double>{3, 3}));
  EXPECT_EQ(b.grad().to_vector(), (std::vector<double>{1, 1}));
}

TEST(Autograd, SharedSubexpressionGetsSummedGradient) {
  Tensor x = Tensor::scalar(3.0, DType::F64);
  x.set_requires_grad();
  Tensor y = ops::mul(x, x);
  Tensor z = ops::add(y, ops::mul(y, x));  // x² + x³ → 2x + 3x² = 33
  z.backward();
  EXPECT_DOUBLE_EQ(x.grad().item(), 33.0);
}

TEST(Autograd, NoGradRecordsNothing) {
  Tensor x = Tensor::ones({2}, DType::F64);
  x.set_requires_grad();
  NoGradGuard guard;
  Tensor y = ops::mul(x, x);
  EXPECT_FALSE(y.requires_grad());
  EXPECT_EQ(y.grad_fn(), nullptr);
}

TEST(Autograd, DetachAndStopGradientBlockTheGradient) {
  Tensor x = Tensor::scalar(2.0, DType::F64);
  x.set_requires_grad();
  Tensor y = ops::add(ops::mul(x, x.detach()), x);  // d/dx = x.detach() + 1 = 3
  y.backward();
  EXPECT_DOUBLE_EQ(x.grad().item(), 3.0);
}

TEST(Autograd, OpaqueNodeComputesButPassesNoGradient) {
  Tensor x = Tensor::scalar(2.0, DType::F64);
  x.set_requires_grad();
  Tensor y = apply_opaque("square_outside_graph", {x}, [](const std::vector<Tensor>& in) {
    Tensor out = in[0].clone();
    out.data<double>()[0] *= out.data<double>()[0];
    return out;
  });
  EXPECT_DOUBLE_EQ(y.item(), 4.0);
  EXPECT_FALSE(y.requires_grad());
  Tensor z = ops::mul(x, y);  // dz/dx = y = 4 (nothing through y)
  z.backward();
  EXPECT_DOUBLE_EQ(x.grad().item(), 4.0);
}

TEST(Autograd, BackwardFreesTheGraphUnlessRetained) {
  Tensor x = Tensor::scalar(2.0, DType::F64);
  x.set_requires_grad();
  Tensor y = ops::mul(x, x);
  y.backward(/*retain_graph=*/true);
  EXPECT_FALSE(y.grad_fn()->released);
  y.backward();
  EXPECT_TRUE(y.grad_fn()->released);
  EXPECT_TRUE(y.grad_fn()->inputs.empty());
  EXPECT_DOUBLE_EQ(x.grad().item(), 8.0);
  EXPECT_THROW(y.backward(), Error);
}

TEST(Autograd, BackwardFromNonScalarNeedsAnExplicitGradient) {
  Tensor x = Tensor::ones({2, 2}, DType::F64);
  x.set_requires_grad();
  Tensor y = ops::mul(x, x);
  EXPECT_THROW(y.backward(), Error);
  EXPECT_THROW(y.backward(Tensor::ones({3}, DType::F64)), Error);
}

TEST(Autograd, BroadcastGradientIsSummedToTheInputShape) {
  Tensor a = Tensor::ones({3, 1}, DType::F64);
  Tensor b = Tensor::ones({4}, DType::F64);
  a.set_requires_grad();
  b.set_requires_grad();
  ops::add(a, b).backward(Tensor::ones({3, 4}, DType::F64));
  EXPECT_EQ(a.grad().shape(), (Shape{3, 1}));
  EXPECT_EQ(a.grad().to_vector(), (std::vector<double>{4, 4, 4}));
  EXPECT_EQ(b.grad().to_vector(), (std::vector<double>{3, 3, 3, 3}));
}

TEST(Autograd, ErrorsNameTheOpAndBothShapes) {
  Tensor a = Tensor::ones({2, 3});
  Tensor b = Tensor::ones({4});
  try {
    ops::add(a, b);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "add: shapes [2, 3] and [4] cannot be broadcast");
  }
  try {
    ops::mul(a, Tensor::ones({2, 3}, DType::F64));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "mul: dtype mismatch: float32 [2, 3] vs float64 [2, 3]");
  }
  EXPECT_THROW(ops::add(Tensor::zeros({0, 3}), Tensor::zeros({0, 3})), Error);
  EXPECT_THROW(ops::add(Tensor(), a), Error);
}

}  // namespace
}  // namespace weft
