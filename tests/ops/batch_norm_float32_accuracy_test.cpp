// batch_norm in float32 within about one rounding of float64 on channels whose mean is
// far from 0, where y = x·a + b' rounded in float32 (a, b', then x·a against b'
// cancelling) was several times further off.
#include <gtest/gtest.h>

#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::rel_l2;

// |μ| = 20σ per channel: y = (x − μ)·w/σ + b is computed in double and rounded once.
TEST(BatchNormFloat32Accuracy, OffsetChannelsWithinOneRoundingOfFloat64) {
  Generator gen(5);
  const int64_t C = 16;
  const Tensor offset = ops::scale(Tensor::randn({1, C, 1, 1}, gen), 20.0);
  const Tensor x32 = ops::add(Tensor::randn({4, C, 8, 8}, gen), offset);
  const Tensor w32 = ops::add_scalar(Tensor::rand({C}, gen), 0.5);
  const Tensor b32 = ops::scale(Tensor::randn({C}, gen), 0.2);
  const Tensor gy32 = Tensor::randn(x32.shape(), gen);
  auto run = [&](DType d) {
    Tensor x = x32.to(d);
    x.set_requires_grad();
    const Tensor y = ops::batch_norm(x, w32.to(d), b32.to(d), Tensor::zeros({C}, d),
                                     Tensor::ones({C}, d), true, 0.1, 1e-5);
    y.backward(gy32.to(d));
    return std::vector<std::vector<double>>{y.to_vector(), x.grad().to_vector()};
  };
  const auto f32 = run(DType::F32), f64 = run(DType::F64);
  // One float32 rounding of a normal value is ~2.5e-8 relative L2 (the three roundings
  // before: 3.9e-7 for y).
  EXPECT_LE(rel_l2(f32[0], f64[0]), 4e-8) << "output";
  EXPECT_LE(rel_l2(f32[1], f64[1]), 4e-8) << "input gradient";
}

}  // namespace
}  // namespace weft
