// Bilinear image sampling at continuous pixel positions (the silhouette loss reads the
// distance-transform image at projected vertices through it).
#include <cmath>

#include "ops/geometry.h"
#include "ops/geometry_checks.h"
#include "ops/ops.h"

namespace weft {
namespace {

constexpr const char* kOp = "image_sample_bilinear";

// The four taps around (x, y), clamped to the image, with their weights and the
// derivatives of those weights in x and y (zero where the point is clamped).
struct Taps {
  int64_t idx[4];
  double w[4], dwdx[4], dwdy[4];
};

Taps taps(double x, double y, int64_t H, int64_t W) {
  const bool clamp_x = !(x > 0 && x < W - 1), clamp_y = !(y > 0 && y < H - 1);
  x = std::min(std::max(x, 0.0), static_cast<double>(W - 1));
  y = std::min(std::max(y, 0.0), static_cast<double>(H - 1));
  const int64_t x0 = std::min<int64_t>(static_cast<int64_t>(std::floor(x)), std::max<int64_t>(W - 2, 0));
  const int64_t y0 = std::min<int64_t>(static_cast<int64_t>(std::floor(y)), std::max<int64_t>(H - 2, 0));
  const int64_t x1 = std::min(x0 + 1, W - 1), y1 = std::min(y0 + 1, H - 1);
  const double fx = x - x0, fy = y - y0;
  Taps t;
  t.idx[0] = y0 * W + x0, t.idx[1] = y0 * W + x1, t.idx[2] = y1 * W + x0, t.idx[3] = y1 * W + x1;
  t.w[0] = (1 - fx) * (1 - fy), t.w[1] = fx * (1 - fy), t.w[2] = (1 - fx) * fy, t.w[3] = fx * fy;
  const double sx = clamp_x ? 0 : 1, sy = clamp_y ? 0 : 1;
  t.dwdx[0] = -(1 - fy) * sx, t.dwdx[1] = (1 - fy) * sx, t.dwdx[2] = -fy * sx, t.dwdx[3] = fy * sx;
  t.dwdy[0] = -(1 - fx) * sy, t.dwdy[1] = -fx * sy, t.dwdy[2] = (1 - fx) * sy, t.dwdy[3] = fx * sy;
  return t;
}

void check(const Tensor& image, const Tensor& points) {
  geometry_checks::expect_shape(kOp, "image", image, {-1, -1, -1});
  geometry_checks::expect_shape(kOp, "points", points, {image.size(0), -1, 2});
  geometry_checks::expect_same_float_dtype(kOp, {&image, &points});
}

}  // namespace

WEFT_REGISTER_OP(image_sample_bilinear) {
  OpDef d;
  d.name = kOp;
  d.doc = "bilinear samples of images [B,H,W] at pixel positions [B,N,2] -> [B,N]";
  d.num_inputs = 2;
  d.forward = [](const ForwardContext& c) {
    const Tensor &image = c.in(0), &points = c.in(1);
    check(image, points);
    const int64_t B = image.size(0), H = image.size(1), W = image.size(2), N = points.size(1);
    Tensor out = Tensor::empty({B, N}, image.dtype());
    dispatch_float(image.dtype(), kOp, [&]<class T>() {
      const T* img = image.data<T>();
      const T* pts = points.data<T>();
      T* po = out.data<T>();
#pragma omp parallel for collapse(2) if (B * N > 4096)
      for (int64_t b = 0; b < B; ++b)
        for (int64_t n = 0; n < N; ++n) {
          const T* p = pts + (b * N + n) * 2;
          if (!std::isfinite(p[0]) || !std::isfinite(p[1])) {
            po[b * N + n] = std::numeric_limits<T>::quiet_NaN();
            continue;
          }
          const Taps t = taps(p[0], p[1], H, W);
          double v = 0;
          for (int k = 0; k < 4; ++k) v += t.w[k] * img[b * H * W + t.idx[k]];
          po[b * N + n] = static_cast<T>(v);
        }
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor &image = c.in(0), &points = c.in(1);
    const int64_t B = image.size(0), H = image.size(1), W = image.size(2), N = points.size(1);
    Tensor gi = Tensor::zeros(image.shape(), image.dtype());
    Tensor gp = Tensor::zeros(points.shape(), points.dtype());
    dispatch_float(image.dtype(), kOp, [&]<class T>() {
      const T* img = image.data<T>();
      const T* pts = points.data<T>();
      const T* go = c.grad_output.data<T>();
      T* pgi = gi.data<T>();
      T* pgp = gp.data<T>();
      // Frames are independent; the image gradient scatters within a frame.
#pragma omp parallel for if (B > 1)
      for (int64_t b = 0; b < B; ++b)
        for (int64_t n = 0; n < N; ++n) {
          const T* p = pts + (b * N + n) * 2;
          if (!std::isfinite(p[0]) || !std::isfinite(p[1])) continue;
          const Taps t = taps(p[0], p[1], H, W);
          const double g = go[b * N + n];
          double gx = 0, gy = 0;
          for (int k = 0; k < 4; ++k) {
            const double v = img[b * H * W + t.idx[k]];
            gx += t.dwdx[k] * v;
            gy += t.dwdy[k] * v;
            pgi[b * H * W + t.idx[k]] += static_cast<T>(g * t.w[k]);
          }
          pgp[(b * N + n) * 2] = static_cast<T>(g * gx);
          pgp[(b * N + n) * 2 + 1] = static_cast<T>(g * gy);
        }
    });
    return {c.needs_grad[0] ? gi : Tensor(), c.needs_grad[1] ? gp : Tensor()};
  };
  return d;
}

namespace ops {
Tensor image_sample_bilinear(const Tensor& image, const Tensor& points) {
  return apply(kOp, {image, points});
}
}  // namespace ops

}  // namespace weft
