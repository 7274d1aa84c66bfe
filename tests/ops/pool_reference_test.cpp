// Pooling in float32 against direct loops in double: forward and backward.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "graph/error.h"
#include "ops/ops.h"
#include "tests/ops/test_util.h"

namespace weft {
namespace {

using testing::rel_l2;

// A random permutation of distinct values, so every max is unique.
Tensor distinct_values(const Shape& s, Generator& g) {
  const int64_t n = shape_numel(s);
  std::vector<double> v(n);
  std::iota(v.begin(), v.end(), 0.0);
  for (int64_t i = n - 1; i > 0; --i)
    std::swap(v[i], v[static_cast<int64_t>(g.uniform() * (i + 1)) % (i + 1)]);
  for (double& e : v) e = 0.01 * e - 3.0;
  return Tensor::from_data(s, v);
}

struct Window {
  int64_t h0, h1, w0, w1;  // [h0, h1) × [w0, w1), clipped to the input
};

// Runs op on x (float32, requires grad) with a random output gradient; returns y, dx.
std::pair<Tensor, Tensor> run(const std::function<Tensor(const Tensor&)>& op, Tensor x,
                              Generator& g, Tensor& gy) {
  x.set_requires_grad();
  Tensor y = op(x);
  gy = Tensor::randn(y.shape(), g);
  y.backward(gy);
  return {y, x.grad()};
}

struct PoolCase {
  int64_t N, C, H, W, k, s, p;
};

class PoolReference : public ::testing::TestWithParam<PoolCase> {};

TEST_P(PoolReference, MaxPoolMatchesDirectLoops) {
  const PoolCase c = GetParam();
  Generator g(3);
  Tensor x = distinct_values({c.N, c.C, c.H, c.W}, g), gy;
  auto [y, dx] = run([&](const Tensor& t) { return ops::max_pool2d(t, c.k, c.s, c.p); }, x, g,
                     gy);
  const int64_t Ho = (c.H + 2 * c.p - c.k) / c.s + 1, Wo = (c.W + 2 * c.p - c.k) / c.s + 1;
  ASSERT_EQ(y.shape(), (Shape{c.N, c.C, Ho, Wo}));
  const auto xv = x.to_vector(), gv = gy.to_vector();
  std::vector<double> ry(y.numel()), rdx(x.numel(), 0.0);
  for (int64_t pl = 0; pl < c.N * c.C; ++pl)
    for (int64_t i = 0; i < Ho; ++i)
      for (int64_t j = 0; j < Wo; ++j) {
        double best = -std::numeric_limits<double>::infinity();
        int64_t at = -1;
        for (int64_t a = 0; a < c.k; ++a)
          for (int64_t b = 0; b < c.k; ++b) {
            const int64_t h = i * c.s - c.p + a, w = j * c.s - c.p + b;
            if (h < 0 || h >= c.H || w < 0 || w >= c.W) continue;
            const int64_t xi = (pl * c.H + h) * c.W + w;
            if (xv[xi] > best) best = xv[xi], at = xi;
          }
        const int64_t o = (pl * Ho + i) * Wo + j;
        ry[o] = best;
        rdx[at] += gv[o];
      }
  EXPECT_LE(rel_l2(y.to_vector(), ry), 1e-5);
  EXPECT_LE(rel_l2(dx.to_vector(), rdx), 1e-5);
}

TEST_P(PoolReference, AvgPoolMatchesDirectLoops) {
  const PoolCase c = GetParam();
  Generator g(4);
  Tensor x = Tensor::randn({c.N, c.C, c.H, c.W}, g), gy;
  auto [y, dx] = run([&](const Tensor& t) { return ops::avg_pool2d(t, c.k, c.s, c.p); }, x, g,
                     gy);
  const int64_t Ho = (c.H + 2 * c.p - c.k) / c.s + 1, Wo = (c.W + 2 * c.p - c.k) / c.s + 1;
  ASSERT_EQ(y.shape(), (Shape{c.N, c.C, Ho, Wo}));
  const auto xv = x.to_vector(), gv = gy.to_vector();
  std::vector<double> ry(y.numel()), rdx(x.numel(), 0.0);
  for (int64_t pl = 0; pl < c.N * c.C; ++pl)
    for (int64_t i = 0; i < Ho; ++i)
      for (int64_t j = 0; j < Wo; ++j) {
        const int64_t o = (pl * Ho + i) * Wo + j;
        double acc = 0;
        for (int64_t a = 0; a < c.k; ++a)
          for (int64_t b = 0; b < c.k; ++b) {
            const int64_t h = i * c.s - c.p + a, w = j * c.s - c.p + b;
            if (h < 0 || h >= c.H || w < 0 || w >= c.W) continue;  // padding counts as 0
            acc += xv[(pl * c.H + h) * c.W + w];
            rdx[(pl * c.H + h) * c.W + w] += gv[o] / (c.k * c.k);
          }
        ry[o] = acc / (c.k * c.k);  // count_include_pad
      }
  EXPECT_LE(rel_l2(y.to_vector(), ry), 1e-5);
  EXPECT_LE(rel_l2(dx.to_vector(), rdx), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Shapes, PoolReference,
                         ::testing::Values(PoolCase{2, 3, 9, 9, 3, 2, 1},   // ResNet stem pool
                                           PoolCase{1, 2, 8, 6, 2, 2, 0},
                                           PoolCase{2, 2, 7, 5, 3, 1, 1},
                                           PoolCase{1, 1, 5, 7, 5, 3, 2},
                                           PoolCase{4, 8, 33, 33, 3, 2, 1}));  // threaded

TEST(PoolReference, AvgPoolPaddedCornerDividesByFullWindow) {
  // count_include_pad: the corner window of a 2x2 ones image with k=3, p=1 holds 4 ones
  // out of 9 cells.
  Tensor y = ops::avg_pool2d(Tensor::ones({1, 1, 2, 2}), 3, 1, 1);
  EXPECT_NEAR(y.at({0, 0, 0, 0}), 4.0 / 9.0, 1e-7);
}

TEST(PoolReference, AdaptiveAndGlobalMatchDirectLoops) {
  Generator g(5);
  for (auto [H, W, oh, ow] : std::vector<std::array<int64_t, 4>>{
           {7, 5, 3, 2}, {8, 8, 1, 1}, {4, 4, 4, 4}, {3, 5, 6, 7}, {13, 9, 5, 4}}) {
    Tensor x = Tensor::randn({2, 3, H, W}, g), gy;
    auto [y, dx] =
        run([&](const Tensor& t) { return ops::adaptive_avg_pool2d(t, oh, ow); }, x, g, gy);
    ASSERT_EQ(y.shape(), (Shape{2, 3, oh, ow}));
    const auto xv = x.to_vector(), gv = gy.to_vector();
    std::vector<double> ry(y.numel()), rdx(x.numel(), 0.0);
    for (int64_t pl = 0; pl < 6; ++pl)
      for (int64_t i = 0; i < oh; ++i)
        for (int64_t j = 0; j < ow; ++j) {
          const int64_t h0 = static_cast<int64_t>(std::floor(double(i) * H / oh));
          const int64_t h1 = static_cast<int64_t>(std::ceil(double(i + 1) * H / oh));
          const int64_t w0 = static_cast<int64_t>(std::floor(double(j) * W / ow));
          const int64_t w1 = static_cast<int64_t>(std::ceil(double(j + 1) * W / ow));
          const int64_t o = (pl * oh + i) * ow + j;
          const double n = double((h1 - h0) * (w1 - w0));
          double acc = 0;
          for (int64_t h = h0; h < h1; ++h)
            for (int64_t w = w0; w < w1; ++w) {
              acc += xv[(pl * H + h) * W + w];
              rdx[(pl * H + h) * W + w] += gv[o] / n;
            }
          ry[o] = acc / n;
        }
    EXPECT_LE(rel_l2(y.to_vector(), ry), 1e-5) << H << "x" << W << " -> " << oh << "x" << ow;
    EXPECT_LE(rel_l2(dx.to_vector(), rdx), 1e-5) << H << "x" << W << " -> " << oh << "x" << ow;
  }
  Tensor x = Tensor::randn({3, 4, 5, 6}, g), gy;
  auto [y, dx] = run([](const Tensor& t) { return ops::global_avg_pool2d(t); }, x, g, gy);
  ASSERT_EQ(y.shape(), (Shape{3, 4}));
  const auto xv = x.to_vector(), gv = gy.to_vector();
  std::vector<double> ry(12, 0.0), rdx(x.numel());
  for (int64_t pl = 0; pl < 12; ++pl)
    for (int64_t i = 0; i < 30; ++i) {
      ry[pl] += xv[pl * 30 + i] / 30.0;
      rdx[pl * 30 + i] = gv[pl] / 30.0;
    }
  EXPECT_LE(rel_l2(y.to_vector(), ry), 1e-5);
  EXPECT_LE(rel_l2(dx.to_vector(), rdx), 1e-5);
}

void expect_error(const std::function<void()>& f, const std::string& op, const Shape& x,
                  const std::string& what) {
  try {
    f();
    ADD_FAILURE() << "no error for " << what;
  } catch (const Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(op), std::string::npos) << m;
    EXPECT_NE(m.find(shape_str(x)), std::string::npos) << m;
    EXPECT_NE(m.find(what), std::string::npos) << m;
  }
}

TEST(PoolBadInput, ClearErrors) {
  const Tensor x = Tensor::zeros({1, 2, 4, 4});
  expect_error([&] { ops::max_pool2d(x, 5, 1, 0); }, "max_pool2d", x.shape(),
               "larger than the padded input");
  expect_error([&] { ops::avg_pool2d(x, 2, 0, 0); }, "avg_pool2d", x.shape(), "positive");
  expect_error([&] { ops::max_pool2d(x, 2, 2, 2); }, "max_pool2d", x.shape(), "half the kernel");
  const Tensor x3 = Tensor::zeros({2, 4, 4});
  expect_error([&] { ops::max_pool2d(x3, 2, 2); }, "max_pool2d", x3.shape(), "4-D");
  expect_error([&] { ops::global_avg_pool2d(x3); }, "global_avg_pool2d", x3.shape(), "4-D");
  expect_error([&] { ops::adaptive_avg_pool2d(x, 0, 2); }, "adaptive_avg_pool2d", x.shape(),
               "must be positive");
}

}  // namespace
}  // namespace weft
