// Depth-blocked products (ops/depth_blocked_gemm.h): the same values as a plain product
// across super-block boundaries, Eigen's depth panel capped, and float32 results of the
// ops built on them (conv2d, linear) within PyTorch's error of float64 on deep ResNet
// shapes, where a product summed in one long chain is 2–3× further off.
#include <gtest/gtest.h>

#include <Eigen/Core>

#include "ops/conv_backend.h"
#include "ops/depth_blocked_gemm.h"
#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::rel_l2;
using RowMatD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Depths around the block (64) and super-block (512) edges, and none at all.
class DepthBlockedGemm : public ::testing::TestWithParam<int64_t> {};

TEST_P(DepthBlockedGemm, EqualsPlainProduct) {
  const int64_t k = GetParam(), m = 13, n = 9;
  RowMatD A = RowMatD::Random(m, k), B = RowMatD::Random(k, n), At = RowMatD::Random(k, m);
  const RowMatD start = RowMatD::Random(m, n);
  const double scale = 1e-12 * (1.0 + static_cast<double>(k));

  RowMatD C(m, n);
  gemm_in_depth_blocks(C, A, B, false);
  EXPECT_LE((C - A * B).cwiseAbs().maxCoeff(), scale) << "C = A·B, depth " << k;

  C = start;
  gemm_in_depth_blocks(C, A, B, true);
  EXPECT_LE((C - (start + A * B)).cwiseAbs().maxCoeff(), scale) << "C += A·B, depth " << k;

  // Transposed operands, as conv2d's backward and linear pass them, into a map.
  std::vector<double> storage(m * n);
  Eigen::Map<RowMatD> Cm(storage.data(), m, n);
  gemm_in_depth_blocks(Cm, At.transpose(), B, false);
  EXPECT_LE((Cm - At.transpose() * B).cwiseAbs().maxCoeff(), scale) << "Aᵀ·B, depth " << k;
  RowMatD Bt = B.transpose();
  gemm_in_depth_blocks(Cm, A, Bt.transpose(), false);
  EXPECT_LE((Cm - A * B).cwiseAbs().maxCoeff(), scale) << "A·(Bᵀ)ᵀ, depth " << k;
}

INSTANTIATE_TEST_SUITE_P(Depths, DepthBlockedGemm,
                         ::testing::Values(0, 1, 63, 64, 65, 511, 512, 513, 1100, 1600));

// PyTorch's float32 conv (oneDNN) is ~1.5e-7 off float64 on these shapes
// (docs/BENCHMARKS.md); weft's must not be worse.
constexpr double kConvFloat32Error = 1.5e-7;

// ResNet's deepest 3×3 conv: 512 channels × 9 taps = 4608 terms per output.
TEST(DepthBlockedAccuracy, DeepConvFloat32WithinOneRoundingOfFloat64) {
  // weft's own kernels (the oneDNN backend has its test in conv_backend_test.cpp).
  const ConvBackend saved = conv_backend();
  set_conv_backend(ConvBackend::eigen);
  Generator gen(3);
  const Tensor x32 = ops::relu(Tensor::randn({2, 512, 4, 4}, gen));
  const Tensor w32 = ops::scale(Tensor::randn({512, 512, 3, 3}, gen), 0.02);
  const Tensor gy32 = Tensor::randn({2, 512, 4, 4}, gen);
  const ops::Conv2dOptions same{1, 1, 1, 1, 1, 1};
  auto run = [&](DType d) {
    Tensor x = x32.to(d), w = w32.to(d);
    x.set_requires_grad();
    w.set_requires_grad();
    const Tensor y = ops::conv2d(x, w, Tensor(), same);
    y.backward(gy32.to(d));
    return std::vector<std::vector<double>>{y.to_vector(), x.grad().to_vector(),
                                            w.grad().to_vector()};
  };
  const auto f32 = run(DType::F32), f64 = run(DType::F64);
  EXPECT_LE(rel_l2(f32[0], f64[0]), kConvFloat32Error) << "output";
  EXPECT_LE(rel_l2(f32[1], f64[1]), kConvFloat32Error) << "input gradient";
  EXPECT_LE(rel_l2(f32[2], f64[2]), kConvFloat32Error) << "weight gradient";
  set_conv_backend(saved);
}

TEST(DepthBlockedAccuracy, DeepLinearFloat32WithinOneRoundingOfFloat64) {
  Generator gen(4);
  const Tensor x32 = ops::relu(Tensor::randn({8, 2048}, gen));
  const Tensor w32 = ops::scale(Tensor::randn({64, 2048}, gen), 0.03);
  const Tensor y32 = ops::linear(x32, w32);
  const Tensor y64 = ops::linear(x32.to(DType::F64), w32.to(DType::F64));
  EXPECT_LE(rel_l2(y32.to_vector(), y64.to_vector()), kConvFloat32Error);
}

// Eigen's own depth panel is capped, so a product within one super-block sums at most
// kGemmDepthBlock terms in a register.
TEST(DepthBlockedGemmPanel, EigenDepthPanelIsCapped) {
  const int64_t panel = limit_gemm_depth_panel();
  EXPECT_GT(panel, 0);
  EXPECT_LE(panel, kGemmDepthBlock);
  Eigen::Index k = 4608, m = 256, n = 1024;
  Eigen::internal::computeProductBlockingSizes<float, float>(k, m, n, Eigen::Index(1));
  EXPECT_LE(k, kGemmDepthBlock) << "one thread";
  k = 4608, m = 256, n = 1024;
  Eigen::internal::computeProductBlockingSizes<float, float>(k, m, n, Eigen::Index(2));
  EXPECT_LE(k, kGemmDepthBlock) << "two threads";
}

}  // namespace
}  // namespace weft
