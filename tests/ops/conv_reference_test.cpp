// conv2d in float32 against direct loops in double: forward and all three gradients.
#include <gtest/gtest.h>

#include <cmath>

#include "graph/error.h"
#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::rel_l2;

struct ConvCase {
  int64_t N, C, H, W, O, kh, kw;
  ops::Conv2dOptions o;
  bool bias;
};

void PrintTo(const ConvCase& k, std::ostream* os) {
  *os << "x [" << k.N << "," << k.C << "," << k.H << "," << k.W << "] w [" << k.O << ","
      << k.C << "," << k.kh << "," << k.kw << "] stride " << k.o.stride_h << "," << k.o.stride_w
      << " pad " << k.o.pad_h << "," << k.o.pad_w << " dil " << k.o.dilation_h << ","
      << k.o.dilation_w << (k.bias ? " bias" : "");
}

struct Naive {
  std::vector<double> y, gx, gw, gb;
};

// Direct definition: y[n,o,i,j] = b[o] + Σ x[n,c,i·sh−ph+ki·dh, j·sw−pw+kj·dw] w[o,c,ki,kj],
// and the gradients by the chain rule through the same index map.
Naive naive_conv(const ConvCase& k, const std::vector<double>& x, const std::vector<double>& w,
                 const std::vector<double>& b, const std::vector<double>& gy, int64_t Ho,
                 int64_t Wo) {
  Naive r;
  r.y.assign(k.N * k.O * Ho * Wo, 0.0);
  r.gx.assign(x.size(), 0.0);
  r.gw.assign(w.size(), 0.0);
  r.gb.assign(k.O, 0.0);
  const auto& o = k.o;
  for (int64_t n = 0; n < k.N; ++n)
    for (int64_t oc = 0; oc < k.O; ++oc)
      for (int64_t i = 0; i < Ho; ++i)
        for (int64_t j = 0; j < Wo; ++j) {
          const int64_t yi = ((n * k.O + oc) * Ho + i) * Wo + j;
          double acc = k.bias ? b[oc] : 0.0;
          r.gb[oc] += gy[yi];
          for (int64_t c = 0; c < k.C; ++c)
            for (int64_t ki = 0; ki < k.kh; ++ki)
              for (int64_t kj = 0; kj < k.kw; ++kj) {
                const int64_t ih = i * o.stride_h - o.pad_h + ki * o.dilation_h;
                const int64_t iw = j * o.stride_w - o.pad_w + kj * o.dilation_w;
                if (ih < 0 || ih >= k.H || iw < 0 || iw >= k.W) continue;
                const int64_t xi = ((n * k.C + c) * k.H + ih) * k.W + iw;
                const int64_t wi = ((oc * k.C + c) * k.kh + ki) * k.kw + kj;
                acc += x[xi] * w[wi];
                r.gx[xi] += gy[yi] * w[wi];
                r.gw[wi] += gy[yi] * x[xi];
              }
          r.y[yi] = acc;
        }
  return r;
}

class ConvReference : public ::testing::TestWithParam<ConvCase> {};

TEST_P(ConvReference, ForwardAndBackwardMatchDirectLoops) {
  const ConvCase k = GetParam();
  Generator gen(42);
  Tensor x = Tensor::randn({k.N, k.C, k.H, k.W}, gen);
  Tensor w = Tensor::randn({k.O, k.C, k.kh, k.kw}, gen);
  Tensor b = k.bias ? Tensor::randn({k.O}, gen) : Tensor();
  x.set_requires_grad();
  w.set_requires_grad();
  if (k.bias) b.set_requires_grad();

  Tensor y = ops::conv2d(x, w, b, k.o);
  const int64_t Ho = y.size(2), Wo = y.size(3);
  const auto& o = k.o;
  EXPECT_EQ(Ho, (k.H + 2 * o.pad_h - o.dilation_h * (k.kh - 1) - 1) / o.stride_h + 1);
  EXPECT_EQ(Wo, (k.W + 2 * o.pad_w - o.dilation_w * (k.kw - 1) - 1) / o.stride_w + 1);
  Tensor gy = Tensor::randn(y.shape(), gen);
  y.backward(gy);

  const Naive r = naive_conv(k, x.to_vector(), w.to_vector(),
                             k.bias ? b.to_vector() : std::vector<double>{}, gy.to_vector(), Ho,
                             Wo);
  EXPECT_LE(rel_l2(y.to_vector(), r.y), 1e-5);
  EXPECT_LE(rel_l2(x.grad().to_vector(), r.gx), 1e-5);
  EXPECT_LE(rel_l2(w.grad().to_vector(), r.gw), 1e-5);
  if (k.bias) EXPECT_LE(rel_l2(b.grad().to_vector(), r.gb), 1e-5);
}

ops::Conv2dOptions opts(int64_t sh, int64_t sw, int64_t ph, int64_t pw, int64_t dh = 1,
                        int64_t dw = 1) {
  return {sh, sw, ph, pw, dh, dw};
}

INSTANTIATE_TEST_SUITE_P(
    Shapes, ConvReference,
    ::testing::Values(
        ConvCase{2, 3, 9, 9, 4, 3, 3, opts(1, 1, 1, 1), true},         // 3x3 same
        ConvCase{3, 4, 11, 10, 5, 3, 3, opts(2, 2, 1, 1), true},       // stride 2
        ConvCase{2, 3, 13, 12, 4, 7, 7, opts(2, 2, 3, 3), false},      // stem-like 7x7/2
        ConvCase{2, 16, 6, 5, 8, 1, 1, opts(1, 1, 0, 0), true},        // 1x1 fast path
        ConvCase{3, 8, 7, 9, 6, 1, 1, opts(2, 2, 0, 0), false},        // 1x1 stride 2
        ConvCase{2, 3, 10, 11, 4, 3, 3, opts(1, 1, 2, 2, 2, 2), true}, // dilation 2
        ConvCase{2, 2, 8, 9, 3, 2, 5, opts(1, 2, 0, 2), true},         // non-square kernel
        ConvCase{1, 5, 6, 7, 2, 3, 1, opts(3, 1, 1, 0, 1, 3), false},  // mixed
        ConvCase{4, 3, 5, 5, 2, 5, 5, opts(1, 1, 0, 0), true},         // kernel = input
        ConvCase{8, 4, 6, 6, 3, 3, 3, opts(1, 1, 1, 1), true},         // batch >= threads
        ConvCase{5, 3, 6, 6, 4, 3, 3, opts(2, 2, 1, 1), true},         // uneven image groups
        ConvCase{7, 6, 4, 4, 5, 1, 1, opts(1, 1, 0, 0), true}));       // grouped 1x1

TEST(ConvReference, Float64MatchesFloat32) {
  Generator gen(7);
  Tensor x = Tensor::randn({2, 3, 8, 8}, gen);
  Tensor w = Tensor::randn({4, 3, 3, 3}, gen);
  const Tensor y32 = ops::conv2d(x, w, Tensor(), opts(2, 2, 1, 1));
  const Tensor y64 = ops::conv2d(x.to(DType::F64), w.to(DType::F64), Tensor(), opts(2, 2, 1, 1));
  EXPECT_LE(rel_l2(y32.to_vector(), y64.to_vector()), 1e-6);
}

// The error names the op and both shapes.
void expect_conv_error(const Tensor& x, const Tensor& w, const Tensor& b,
                       const ops::Conv2dOptions& o, const std::string& what) {
  try {
    ops::conv2d(x, w, b, o);
    ADD_FAILURE() << "no error for " << what;
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("conv2d"), std::string::npos) << m;
    EXPECT_NE(m.find(shape_str(x.shape())), std::string::npos) << m;
    EXPECT_NE(m.find(shape_str(w.shape())), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
  }
}

TEST(ConvBadInput, ChannelMismatch) {
  expect_conv_error(Tensor::zeros({1, 3, 8, 8}), Tensor::zeros({4, 2, 3, 3}), Tensor(), {},
                    "input channels");
}
TEST(ConvBadInput, KernelLargerThanPaddedInput) {
  expect_conv_error(Tensor::zeros({1, 2, 4, 4}), Tensor::zeros({4, 2, 5, 5}), Tensor(),
                    opts(1, 1, 0, 0), "larger than the padded input");
  // dilation makes a 3x3 kernel span 5 pixels
  expect_conv_error(Tensor::zeros({1, 2, 4, 8}), Tensor::zeros({4, 2, 3, 3}), Tensor(),
                    opts(1, 1, 0, 0, 2, 2), "larger than the padded input");
}
TEST(ConvBadInput, NonPositiveStride) {
  expect_conv_error(Tensor::zeros({1, 2, 4, 4}), Tensor::zeros({4, 2, 3, 3}), Tensor(),
                    opts(0, 1, 0, 0), "must be positive");
  expect_conv_error(Tensor::zeros({1, 2, 4, 4}), Tensor::zeros({4, 2, 3, 3}), Tensor(),
                    opts(1, -2, 0, 0), "must be positive");
  expect_conv_error(Tensor::zeros({1, 2, 4, 4}), Tensor::zeros({4, 2, 3, 3}), Tensor(),
                    opts(1, 1, -1, 0), "non-negative");
}
TEST(ConvBadInput, WrongRank) {
  expect_conv_error(Tensor::zeros({2, 4, 4}), Tensor::zeros({4, 2, 3, 3}), Tensor(), {},
                    "4-D");
  expect_conv_error(Tensor::zeros({1, 2, 4, 4}), Tensor::zeros({4, 18}), Tensor(), {}, "4-D");
}
TEST(ConvBadInput, DtypeMismatch) {
  expect_conv_error(Tensor::zeros({1, 2, 4, 4}), Tensor::zeros({4, 2, 3, 3}, DType::F64),
                    Tensor(), {}, "dtype");
}
TEST(ConvBadInput, BiasShape) {
  expect_conv_error(Tensor::zeros({1, 2, 4, 4}), Tensor::zeros({4, 2, 3, 3}),
                    Tensor::zeros({3}), {}, "bias");
}

}  // namespace
}  // namespace weft
