#include <gtest/gtest.h>

#include "graph/tensor.h"

namespace weft {
namespace {

TEST(Tensor, CreationFillsAsAsked) {
  EXPECT_EQ(Tensor::zeros({2, 3}).to_vector(), std::vector<double>(6, 0.0));
  EXPECT_EQ(Tensor::full({2}, 2.5, DType::F64).to_vector(), (std::vector<double>{2.5, 2.5}));
  EXPECT_EQ(Tensor::arange(0, 5, 2).to_vector(), (std::vector<double>{0, 2, 4}));
  EXPECT_EQ(Tensor::scalar(3).shape(), Shape{});
  EXPECT_EQ(Tensor::scalar(3).item(), 3.0);
}

TEST(Tensor, SeededRandomIsReproducible) {
  Generator g1(7), g2(7), g3(8);
  EXPECT_EQ(Tensor::randn({5}, g1).to_vector(), Tensor::randn({5}, g2).to_vector());
  EXPECT_NE(Tensor::randn({5}, g1).to_vector(), Tensor::randn({5}, g3).to_vector());
  Generator g4(9);
  const std::string state = g4.state();
  const double first = g4.normal();
  g4.set_state(state);
  EXPECT_EQ(g4.normal(), first);
}

TEST(Tensor, ElementAccessIsRowMajorAndChecked) {
  Tensor t = Tensor::arange(0, 6).view({2, 3});
  EXPECT_EQ(t.at({1, 2}), 5.0);
  t.set({0, 1}, 10);
  EXPECT_EQ(t.at({0, 1}), 10.0);
  EXPECT_THROW(t.at({2, 0}), Error);
  EXPECT_THROW(t.at({0}), Error);
  EXPECT_THROW(t.item(), Error);
}

TEST(Tensor, ViewsShareStorageAndClonesDoNot) {
  Tensor t = Tensor::arange(0, 12).view({3, 4});
  Tensor v = t.view({4, -1});
  EXPECT_EQ(v.shape(), (Shape{4, 3}));
  EXPECT_TRUE(v.shares_storage(t));
  Tensor rows = t.slice_view(0, 1, 3);
  EXPECT_TRUE(rows.shares_storage(t));
  EXPECT_EQ(rows.at({0, 0}), 4.0);
  rows.set({0, 0}, -1);
  EXPECT_EQ(t.at({1, 0}), -1.0);
  EXPECT_THROW(t.slice_view(1, 0, 2), Error);  // columns are not contiguous
  Tensor c = t.clone();
  EXPECT_FALSE(c.shares_storage(t));
  EXPECT_THROW(t.view({5, -1}), Error);
}

TEST(Tensor, ConversionAndPrinting) {
  Tensor t = Tensor::from_data({2, 2}, std::vector<double>{1, 2, 3, 4}, DType::F64);
  Tensor f = t.to(DType::F32);
  EXPECT_EQ(f.dtype(), DType::F32);
  EXPECT_EQ(f.to_vector(), t.to_vector());
  EXPECT_EQ(f.to_string(), "tensor([[1, 2], [3, 4]], dtype=float32, shape=[2, 2])");
  EXPECT_EQ(Tensor::scalar(1.5).to_string(), "tensor(1.5, dtype=float32, shape=[])");
  EXPECT_THROW(f.data<double>(), Error);
  EXPECT_THROW(Tensor::from_data({3}, std::vector<double>{1, 2}), Error);
}

}  // namespace
}  // namespace weft
