// conv2d on each backend of ops/conv_backend.h and in both layouts (NCHW, channel
// blocks): the same values as weft's float64 Eigen kernels, float32 central differences
// for the gradients, and float32 accuracy on ResNet's deepest 3×3 conv.
#include <gtest/gtest.h>

#include <algorithm>

#include "graph/autograd.h"
#include "ops/conv_backend.h"
#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::rel_l2;

// Sets a backend for one test and restores the previous one.
struct BackendScope {
  ConvBackend saved = conv_backend();
  explicit BackendScope(ConvBackend b) { set_conv_backend(b); }
  ~BackendScope() { set_conv_backend(saved); }
};

// [N,C,H,W] -> [N,C/L,H,W,L] and back, with the graph's own ops.
Tensor blocked(const Tensor& x, int64_t L) {
  const Shape s = x.shape();
  return ops::permute(ops::reshape(x, {s[0], s[1] / L, L, s[2], s[3]}), {0, 1, 3, 4, 2});
}
Tensor unblocked(const Tensor& x) {
  const Shape s = x.shape();
  return ops::reshape(ops::permute(x, {0, 1, 4, 2, 3}), {s[0], s[1] * s[4], s[2], s[3]});
}

struct Case {
  ConvBackend backend;
  int64_t block;
};

void PrintTo(const Case& c, std::ostream* os) {
  *os << conv_backend_name(c.backend) << ", channel block " << c.block;
}

std::string case_name(const ::testing::TestParamInfo<Case>& i) {
  std::string name = std::string(conv_backend_name(i.param.backend)) + "_block" +
                     std::to_string(i.param.block);
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

class ConvBackendLayout : public ::testing::TestWithParam<Case> {};

// Forward and all three gradients of a strided 3×3 conv with bias, float32 on the
// backend under test against float64 on the Eigen kernels (NCHW).
TEST_P(ConvBackendLayout, MatchesFloat64Eigen) {
  const Case k = GetParam();
  Generator gen(11);
  const Tensor x0 = Tensor::randn({3, 32, 9, 7}, gen);
  const Tensor w0 = Tensor::randn({16, 32, 3, 3}, gen, DType::F32, 0.0, 0.1);
  const Tensor b0 = Tensor::randn({16}, gen);
  const ops::Conv2dOptions o{2, 2, 1, 1, 1, 1};
  Tensor x64 = x0.to(DType::F64), w64 = w0.to(DType::F64), b64 = b0.to(DType::F64);
  for (Tensor* t : {&x64, &w64, &b64}) t->set_requires_grad();
  Tensor y64 = ops::conv2d(x64, w64, b64, o);
  const Tensor gy = Tensor::randn(y64.shape(), gen);
  y64.backward(gy.to(DType::F64));

  BackendScope scope(k.backend);
  Tensor x = x0.clone(), w = w0.clone(), b = b0.clone();
  for (Tensor* t : {&x, &w, &b}) t->set_requires_grad();
  ops::Conv2dOptions ob = o;
  ob.channel_block = k.block;
  Tensor y = k.block > 1 ? unblocked(ops::conv2d(blocked(x, k.block), w, b, ob))
                         : ops::conv2d(x, w, b, ob);
  ASSERT_EQ(y.shape(), y64.shape());
  y.backward(gy);
  EXPECT_LE(rel_l2(y.to_vector(), y64.to_vector()), 1e-6) << "output";
  EXPECT_LE(rel_l2(x.grad().to_vector(), x64.grad().to_vector()), 1e-6) << "input gradient";
  EXPECT_LE(rel_l2(w.grad().to_vector(), w64.grad().to_vector()), 1e-6) << "weight gradient";
  EXPECT_LE(rel_l2(b.grad().to_vector(), b64.grad().to_vector()), 1e-6) << "bias gradient";
}

// The gradient check of a float32-only backend: L = Σ r ⊙ conv2d(x, w, b), analytic
// gradients against central differences in float32 (step 1e-2 on values of order 1;
// the loss is evaluated in double from the float32 output, so the difference quotient
// carries about 1e-3 relative noise).
TEST_P(ConvBackendLayout, GradientsMatchCentralDifferences) {
  const Case k = GetParam();
  BackendScope scope(k.backend);
  Generator gen(5);
  Tensor x = Tensor::randn({2, 16, 5, 6}, gen);
  Tensor w = Tensor::randn({16, 16, 3, 3}, gen, DType::F32, 0.0, 0.2);
  Tensor b = Tensor::randn({16}, gen);
  ops::Conv2dOptions o{1, 2, 1, 1, 1, 1};
  o.channel_block = k.block;
  auto input = [&](const Tensor& t) { return k.block > 1 ? blocked(t, k.block) : t; };
  const Shape yshape = ops::conv2d(input(x), w, b, o).shape();
  const Tensor r = Tensor::randn(yshape, gen);
  const std::vector<double> rv = r.to_vector();
  auto loss = [&]() {
    NoGradGuard no_grad;
    const std::vector<double> y = ops::conv2d(input(x), w, b, o).to_vector();
    double s = 0;
    for (size_t i = 0; i < y.size(); ++i) s += y[i] * rv[i];
    return s;
  };
  for (Tensor* t : {&x, &w, &b}) t->set_requires_grad();
  ops::conv2d(input(x), w, b, o).backward(r);
  for (Tensor* t : {&x, &w, &b}) {
    const std::vector<double> analytic = t->grad().to_vector();
    float* p = t->data<float>();
    double worst = 0;
    // Every 7th element: enough to cover each kernel tap, channel and border.
    for (int64_t i = 0; i < t->numel(); i += 7) {
      const float saved = p[i];
      const float h = 1e-2f;
      p[i] = saved + h;
      const double up = loss();
      p[i] = saved - h;
      const double down = loss();
      p[i] = saved;
      const double numeric = (up - down) / (2.0 * h);
      worst = std::max(worst, std::abs(numeric - analytic[i]) / std::max(1.0, std::abs(numeric)));
    }
    EXPECT_LE(worst, 2e-3) << "input " << shape_str(t->shape());
  }
}

// Winograd (3×3, stride 1, 18×18 output: the shapes onednn-winograd uses it for) against
// float64 and central differences. Its float32 error is larger than the direct kernels'
// (docs/BENCHMARKS.md), still far below anything a network would notice.
TEST(ConvBackendWinograd, MatchesFloat64AndCentralDifferences) {
  BackendScope scope(ConvBackend::onednn_winograd);
  Generator gen(23);
  const Tensor x0 = Tensor::randn({2, 1, 18, 18, 16}, gen);
  const Tensor w0 = Tensor::randn({16, 16, 3, 3}, gen, DType::F32, 0.0, 0.1);
  ops::Conv2dOptions o{1, 1, 1, 1, 1, 1};
  o.channel_block = 16;
  Tensor x64 = x0.to(DType::F64), w64 = w0.to(DType::F64);
  x64.set_requires_grad();
  w64.set_requires_grad();
  {
    BackendScope eigen(ConvBackend::eigen);
    Tensor y64 = ops::conv2d(x64, w64, Tensor(), o);
    y64.backward(Tensor::ones(y64.shape(), DType::F64));
  }
  Tensor x = x0.clone(), w = w0.clone();
  x.set_requires_grad();
  w.set_requires_grad();
  Tensor y = ops::conv2d(x, w, Tensor(), o);
  y.backward(Tensor::ones(y.shape()));
  {
    BackendScope eigen(ConvBackend::eigen);
    Tensor y64 = ops::conv2d(x64.detach(), w64.detach(), Tensor(), o);
    EXPECT_LE(rel_l2(y.to_vector(), y64.to_vector()), 1e-5) << "output";
  }
  EXPECT_LE(rel_l2(x.grad().to_vector(), x64.grad().to_vector()), 1e-5) << "input gradient";
  EXPECT_LE(rel_l2(w.grad().to_vector(), w64.grad().to_vector()), 1e-5) << "weight gradient";
  // Central differences of L = Σ y for a few weights (the loss is a sum of 10k outputs:
  // step 0.05 keeps the float32 noise of the difference below 1e-3 relative).
  const std::vector<double> analytic = w.grad().to_vector();
  float* pw = w.data<float>();
  auto loss = [&] {
    NoGradGuard no_grad;
    double s = 0;
    for (double v : ops::conv2d(x0, w, Tensor(), o).to_vector()) s += v;
    return s;
  };
  for (int64_t i = 0; i < w.numel(); i += 97) {
    const float saved = pw[i];
    pw[i] = saved + 0.05f;
    const double up = loss();
    pw[i] = saved - 0.05f;
    const double down = loss();
    pw[i] = saved;
    const double numeric = (up - down) / 0.1;
    EXPECT_NEAR(analytic[i], numeric, 2e-3 * std::max(1.0, std::abs(numeric))) << "weight " << i;
  }
}

// An NCHW input with a blocked output (a network's first conv, 3 input channels), and
// back: values and the gradients of the weights and of the NCHW input.
class ConvBackendBlockedOutput : public ::testing::TestWithParam<Case> {};

TEST_P(ConvBackendBlockedOutput, NchwInputToBlockedOutput) {
  const Case k = GetParam();
  Generator gen(13);
  const Tensor x0 = Tensor::randn({2, 3, 11, 11}, gen);
  const Tensor w0 = Tensor::randn({32, 3, 7, 7}, gen, DType::F32, 0.0, 0.1);
  const ops::Conv2dOptions o{2, 2, 3, 3, 1, 1};
  Tensor x64 = x0.to(DType::F64), w64 = w0.to(DType::F64);
  x64.set_requires_grad();
  w64.set_requires_grad();
  Tensor y64 = ops::conv2d(x64, w64, Tensor(), o);
  const Tensor gy = Tensor::randn(y64.shape(), gen);
  y64.backward(gy.to(DType::F64));

  BackendScope scope(k.backend);
  Tensor x = x0.clone(), w = w0.clone();
  x.set_requires_grad();
  w.set_requires_grad();
  ops::Conv2dOptions ob = o;
  ob.channel_block = k.block;
  const Tensor yb = ops::conv2d(x, w, Tensor(), ob);
  ASSERT_EQ(yb.dim(), 5);
  const Tensor y = unblocked(yb);
  y.backward(gy);
  EXPECT_LE(rel_l2(y.to_vector(), y64.to_vector()), 1e-6) << "output";
  EXPECT_LE(rel_l2(x.grad().to_vector(), x64.grad().to_vector()), 1e-6) << "input gradient";
  EXPECT_LE(rel_l2(w.grad().to_vector(), w64.grad().to_vector()), 1e-6) << "weight gradient";
}

INSTANTIATE_TEST_SUITE_P(Backends, ConvBackendBlockedOutput,
                         ::testing::Values(Case{ConvBackend::eigen, 16}, Case{ConvBackend::onednn, 8},
                                           Case{ConvBackend::onednn, 16}),
                         case_name);

// max_pool2d over channel blocks: the values and the gradient of the NCHW op.
TEST(BlockedLayout, MaxPoolMatchesNchw) {
  Generator gen(17);
  const Tensor x0 = Tensor::randn({2, 32, 9, 8}, gen);
  const Tensor gy = Tensor::randn({2, 32, 5, 4}, gen);
  auto run = [&](int64_t L) {
    Tensor x = x0.clone();
    x.set_requires_grad();
    const Tensor y = L > 1 ? unblocked(ops::max_pool2d(blocked(x, L), 3, 2, 1, L))
                           : ops::max_pool2d(x, 3, 2, 1);
    y.backward(gy);
    return std::vector<std::vector<double>>{y.to_vector(), x.grad().to_vector()};
  };
  const auto plain = run(1);
  for (int64_t L : {8, 16}) {
    const auto blocks = run(L);
    EXPECT_EQ(blocks[0], plain[0]) << "block " << L;
    EXPECT_EQ(blocks[1], plain[1]) << "block " << L;
  }
}

INSTANTIATE_TEST_SUITE_P(Backends, ConvBackendLayout,
                         ::testing::Values(Case{ConvBackend::eigen, 1}, Case{ConvBackend::eigen, 16},
                                           Case{ConvBackend::onednn, 1},
                                           Case{ConvBackend::onednn, 8},
                                           Case{ConvBackend::onednn, 16},
                                           Case{ConvBackend::onednn_winograd, 16}),
                         case_name);

// ResNet's deepest 3×3 conv (512 channels × 9 taps = 4608 terms per output) in float32,
// against float64. PyTorch 1.13's own float32 run of this case on the machine of
// docs/BENCHMARKS.md ("conv2d backends") is 1.69e-7 (output), 2.13e-7 (input gradient)
// and 6.5e-8 (weight gradient) off float64 (bench/conv_accuracy_torch.py); oneDNN in
// channel blocks is PyTorch's computation and must not be further off than that.
TEST(ConvBackendAccuracy, OneDnnBlockedWithinPyTorchsFloat32Error) {
  BackendScope scope(ConvBackend::onednn);
  Generator gen(3);
  const Tensor x32 = ops::relu(Tensor::randn({2, 512, 4, 4}, gen));
  const Tensor w32 = ops::scale(Tensor::randn({512, 512, 3, 3}, gen), 0.02);
  const Tensor gy32 = Tensor::randn({2, 512, 4, 4}, gen);
  ops::Conv2dOptions same{1, 1, 1, 1, 1, 1};
  auto run = [&](DType d, int64_t block) {
    Tensor x = x32.to(d), w = w32.to(d);
    x.set_requires_grad();
    w.set_requires_grad();
    ops::Conv2dOptions o = same;
    o.channel_block = block;
    const Tensor y = block > 1 ? unblocked(ops::conv2d(blocked(x, block), w, Tensor(), o))
                               : ops::conv2d(x, w, Tensor(), o);
    y.backward(gy32.to(d));
    return std::vector<std::vector<double>>{y.to_vector(), x.grad().to_vector(),
                                            w.grad().to_vector()};
  };
  const auto f64 = run(DType::F64, 1);
  for (int64_t block : {1, 16}) {
    const auto f32 = run(DType::F32, block);
    EXPECT_LE(rel_l2(f32[0], f64[0]), 1.75e-7) << "output, block " << block;
    EXPECT_LE(rel_l2(f32[1], f64[1]), 2.2e-7) << "input gradient, block " << block;
    EXPECT_LE(rel_l2(f32[2], f64[2]), 7e-8) << "weight gradient, block " << block;
  }
}

// batch_norm over channel blocks: the values, gradients and running statistics of the
// NCHW op, lane l of block cb being channel cb·L + l.
TEST(BlockedLayout, BatchNormMatchesNchw) {
  Generator gen(9);
  const Tensor x0 = Tensor::randn({3, 32, 4, 5}, gen, DType::F32, 0.5, 2.0);
  const Tensor w0 = Tensor::randn({32}, gen), b0 = Tensor::randn({32}, gen);
  const Tensor gy = Tensor::randn({3, 32, 4, 5}, gen);
  for (bool training : {true, false}) {
    auto run = [&](int64_t L) {
      Tensor x = x0.clone(), w = w0.clone(), b = b0.clone();
      for (Tensor* t : {&x, &w, &b}) t->set_requires_grad();
      Tensor rm = Tensor::full({32}, 0.25), rv = Tensor::full({32}, 1.5);
      const Tensor y =
          L > 1 ? unblocked(ops::batch_norm(blocked(x, L), w, b, rm, rv, training, 0.1, 1e-5, {L}))
                : ops::batch_norm(x, w, b, rm, rv, training);
      y.backward(gy);
      return std::vector<std::vector<double>>{y.to_vector(), x.grad().to_vector(),
                                              w.grad().to_vector(), b.grad().to_vector(),
                                              rm.to_vector(), rv.to_vector()};
    };
    const auto plain = run(1);
    for (int64_t L : {8, 16}) {
      const auto blocks = run(L);
      for (size_t i = 0; i < plain.size(); ++i)
        EXPECT_LE(rel_l2(blocks[i], plain[i]), 1e-7)
            << "result " << i << ", block " << L << (training ? ", training" : ", eval");
    }
  }
}

// batch_norm with a residual and relu fused is relu(add(batch_norm(x), z)) to the last
// bit, values and gradients.
TEST(BlockedLayout, BatchNormResidualReluIsTheUnfusedOps) {
  Generator gen(19);
  const Tensor x0 = Tensor::randn({2, 16, 3, 4}, gen), z0 = Tensor::randn({2, 16, 3, 4}, gen);
  const Tensor w0 = Tensor::randn({16}, gen), b0 = Tensor::randn({16}, gen);
  const Tensor gy = Tensor::randn({2, 16, 3, 4}, gen);
  auto run = [&](bool fused) {
    Tensor x = x0.clone(), z = z0.clone(), w = w0.clone(), b = b0.clone();
    for (Tensor* t : {&x, &z, &w, &b}) t->set_requires_grad();
    Tensor rm = Tensor::zeros({16}), rv = Tensor::ones({16});
    const Tensor y =
        fused ? ops::batch_norm(x, w, b, rm, rv, true, 0.1, 1e-5, {1, z, true})
              : ops::relu(ops::add(ops::batch_norm(x, w, b, rm, rv, true), z));
    y.backward(gy);
    return std::vector<std::vector<double>>{y.to_vector(), x.grad().to_vector(),
                                            z.grad().to_vector(), w.grad().to_vector(),
                                            b.grad().to_vector(), rm.to_vector(), rv.to_vector()};
  };
  const auto fused = run(true), plain = run(false);
  for (size_t i = 0; i < plain.size(); ++i) EXPECT_EQ(fused[i], plain[i]) << "result " << i;
}

// conv2d_affine (a conv with its batch norm folded in, the shortcut and relu in the
// epilogue) against the same arithmetic in float64 by separate ops, per backend and
// layout, with and without the residual and the relu.
TEST_P(ConvBackendLayout, Conv2dAffineIsConvThenAffineThenResidualThenRelu) {
  const Case k = GetParam();
  Generator gen(29);
  const Tensor x0 = Tensor::randn({2, 16, 7, 6}, gen);
  const Tensor w0 = Tensor::randn({32, 16, 3, 3}, gen, DType::F32, 0.0, 0.1);
  const Tensor scale = Tensor::rand({32}, gen, DType::F32, 0.5, 1.5);
  const Tensor shift = Tensor::randn({32}, gen);
  const Tensor z0 = Tensor::randn({2, 32, 7, 6}, gen);
  const ops::Conv2dOptions o{1, 1, 1, 1, 1, 1};
  for (bool residual : {false, true})
    for (bool relu : {false, true}) {
      Tensor want = ops::conv2d(x0.to(DType::F64), w0.to(DType::F64), Tensor(), o);
      want = ops::add(ops::mul(want, ops::reshape(scale.to(DType::F64), {1, 32, 1, 1})),
                      ops::reshape(shift.to(DType::F64), {1, 32, 1, 1}));
      if (residual) want = ops::add(want, z0.to(DType::F64));
      if (relu) want = ops::relu(want);
      BackendScope scope(k.backend);
      ops::Conv2dOptions ob = o;
      ob.channel_block = k.block;
      const Tensor x = k.block > 1 ? blocked(x0, k.block) : x0;
      const Tensor z = residual ? (k.block > 1 ? blocked(z0, k.block) : z0) : Tensor();
      Tensor y = ops::conv2d_affine(x, w0, scale, shift, z, relu, ob);
      if (k.block > 1) y = unblocked(y);
      EXPECT_LE(rel_l2(y.to_vector(), want.to_vector()), 1e-6)
          << (residual ? "residual " : "") << (relu ? "relu" : "");
    }
  testing::expect_error(
      [&] { ops::conv2d_affine(x0, w0, Tensor::ones({16}), shift, Tensor(), false, o); },
      {"conv2d_affine", "[32]"});
}

// batch_norm and max_pool2d name the blocked layout they expected.
TEST(BlockedLayout, WrongLayoutsNameWhatWasExpected) {
  Generator gen(37);
  const Tensor nchw = Tensor::randn({2, 16, 4, 4}, gen);
  const Tensor blocks8 = Tensor::randn({2, 2, 4, 4, 8}, gen);
  testing::expect_error(
      [&] {
        ops::batch_norm(nchw, Tensor(), Tensor(), Tensor::zeros({16}), Tensor::ones({16}), true,
                        0.1, 1e-5, {16});
      },
      {"batch_norm", "channel_block 16", "[N, C/16, ..., 16]"});
  testing::expect_error(
      [&] {
        ops::batch_norm(blocks8, Tensor(), Tensor(), Tensor::zeros({16}), Tensor::ones({16}), true,
                        0.1, 1e-5, {8, Tensor::zeros({2, 16, 4, 4}), false});
      },
      {"batch_norm", "residual", "must match x"});
  testing::expect_error([&] { ops::max_pool2d(blocks8, 3, 2, 1, 16); },
                        {"max_pool2d", "channel_block 16", "[N, C/16, H, W, 16]"});
  testing::expect_error([&] { ops::max_pool2d(nchw, 3, 2, 1, 4); },
                        {"max_pool2d", "channel_block must be 1, 8 or 16"});
}

TEST(ConvBackendSelection, NamesParseAndBadNamesFail) {
  EXPECT_EQ(parse_conv_backend("eigen", "test"), ConvBackend::eigen);
  EXPECT_EQ(parse_conv_backend("onednn", "test"), ConvBackend::onednn);
  EXPECT_EQ(parse_conv_backend("onednn-winograd", "test"), ConvBackend::onednn_winograd);
  testing::expect_error([] { parse_conv_backend("mkl", "WEFT_CONV_BACKEND"); },
                        {"WEFT_CONV_BACKEND", "mkl", "eigen, onednn or onednn-winograd"});
  BackendScope scope(ConvBackend::eigen);
  EXPECT_EQ(preferred_channel_block(), 1);
  set_conv_backend(ConvBackend::onednn);
  EXPECT_EQ(preferred_channel_block(), 16);
}

TEST(ConvBackendSelection, BlockedInputOfTheWrongShapeNamesTheLayout) {
  Generator gen(1);
  ops::Conv2dOptions o;
  o.channel_block = 16;
  testing::expect_error(
      [&] { ops::conv2d(Tensor::randn({1, 2, 4, 4, 8}, gen), Tensor::randn({16, 16, 1, 1}, gen),
                        Tensor(), o); },
      {"conv2d", "[N,C/16,H,W,16]"});
  testing::expect_error(
      [&] { ops::conv2d(Tensor::randn({1, 1, 4, 4, 16}, gen), Tensor::randn({12, 16, 1, 1}, gen),
                        Tensor(), o); },
      {"conv2d", "divisible by 16"});
}

}  // namespace
}  // namespace weft
