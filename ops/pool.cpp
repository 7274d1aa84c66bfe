// Pooling over the spatial axes of NCHW tensors: max_pool2d (also over channel blocks),
// avg_pool2d, adaptive_avg_pool2d, global_avg_pool2d. Output sizes round down (PyTorch's
// ceil_mode=False). Planes (n, c) are independent and run in parallel.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "graph/threads.h"
#include "ops/ops.h"

namespace weft {
namespace {

void check_nchw(const char* op, const Tensor& x) {
  if (x.dim() != 4) fail(op, ": expected a 4-D input [N,C,H,W], got ", describe(x));
  if (x.dtype() == DType::I64) fail(op, ": expected float32 or float64, got ", describe(x));
}

struct PoolGeometry {
  int64_t planes, H, W, k, s, p, Ho, Wo;
  // Window of output (i, j), clipped to the input: rows [h0, h1), columns [w0, w1).
  int64_t h0(int64_t i) const { return std::max<int64_t>(i * s - p, 0); }
  int64_t h1(int64_t i) const { return std::min(i * s - p + k, H); }
  int64_t w0(int64_t j) const { return std::max<int64_t>(j * s - p, 0); }
  int64_t w1(int64_t j) const { return std::min(j * s - p + k, W); }
};

// fn(plane, output offset, h0, h1, w0, w1) for every output window of a geometry (pooling
// windows or adaptive bins), planes in parallel when there is enough work.
template <class Geometry, class Fn>
void for_each_window(const Geometry& g, int64_t parallel_above, Fn fn) {
#pragma omp parallel for num_threads(num_threads()) if (g.planes * g.H * g.W > parallel_above)
  for (int64_t pl = 0; pl < g.planes; ++pl)
    for (int64_t i = 0; i < g.Ho; ++i) {
      const int64_t h0 = g.h0(i), h1 = g.h1(i);
      for (int64_t j = 0; j < g.Wo; ++j) fn(pl, (pl * g.Ho + i) * g.Wo + j, h0, h1, g.w0(j), g.w1(j));
    }
}

// Square window `kernel`, `stride`, `padding`, as PyTorch checks them: padding at most
// half the kernel (so every window holds at least one real pixel). With `block` L > 1
// (max_pool2d's channel_block) x is blocked [N, C/L, H, W, L] and a plane is one block.
PoolGeometry pool_geometry(const char* op, const Tensor& x, const Attrs& a, int64_t block = 1) {
  if (block > 1) {
    if (x.dim() != 5 || x.size(4) != block)
      fail(op, ": channel_block ", block, " needs x [N, C/", block, ", H, W, ", block,
           "]; got ", describe(x));
  } else {
    check_nchw(op, x);
  }
  PoolGeometry g{};
  g.planes = x.size(0) * x.size(1);
  g.H = x.size(2), g.W = x.size(3);
  g.k = a.get_int("kernel"), g.s = a.get_int("stride"), g.p = a.get_int("padding", 0);
  if (g.k <= 0 || g.s <= 0 || g.p < 0)
    fail(op, ": kernel ", g.k, " and stride ", g.s, " must be positive and padding ", g.p,
         " non-negative; input ", describe(x));
  if (2 * g.p > g.k)
    fail(op, ": padding ", g.p, " must be at most half the kernel ", g.k, "; input ",
         describe(x));
  if (g.k > g.H + 2 * g.p || g.k > g.W + 2 * g.p)
    fail(op, ": kernel ", g.k, "x", g.k, " is larger than the padded input ", g.H + 2 * g.p,
         "x", g.W + 2 * g.p, "; input ", describe(x));
  g.Ho = (g.H + 2 * g.p - g.k) / g.s + 1;
  g.Wo = (g.W + 2 * g.p - g.k) / g.s + 1;
  return g;
}

Attrs pool_attrs(int64_t kernel, int64_t stride, int64_t padding) {
  return {{"kernel", kernel}, {"stride", stride}, {"padding", padding}};
}

// ---- max pool: padding is −∞; the flat argmax (h·W + w within the plane) is saved ----

// The L channels of a block side by side (L = 1: NCHW), each lane its own max and argmax
// (the flat h·W + w within the plane), vectorised across lanes.
template <class T, int L>
Tensor max_pool_forward(const Tensor& x, const PoolGeometry& g, Tensor& argmax) {
  Tensor y = L > 1 ? Tensor::empty({x.size(0), x.size(1), g.Ho, g.Wo, L}, x.dtype())
                   : Tensor::empty({x.size(0), x.size(1), g.Ho, g.Wo}, x.dtype());
  argmax = Tensor::empty(y.shape(), DType::I64);
  const T* px = x.data<T>();
  T* py = y.data<T>();
  int64_t* pa = argmax.data<int64_t>();
  for_each_window(g, 16384, [&](int64_t pl, int64_t o, int64_t h0, int64_t h1, int64_t w0, int64_t w1) {
    const T* xp = px + pl * g.H * g.W * L;
    // Lanes in 32-bit integers beside the values (one vector each; int64 lanes and bool
    // masks kept the compiler from vectorising this loop).
    T best[L];
    int32_t at[L];
    for (int l = 0; l < L; ++l)
      best[l] = -std::numeric_limits<T>::infinity(), at[l] = static_cast<int32_t>(h0 * g.W + w0);
    for (int64_t h = h0; h < h1; ++h)
      for (int64_t w = w0; w < w1; ++w) {
        const T* v = xp + (h * g.W + w) * L;
        const int32_t here = static_cast<int32_t>(h * g.W + w);
#pragma omp simd
        for (int l = 0; l < L; ++l) {
          const int32_t take = (v[l] > best[l]) | (v[l] != v[l]);  // NaN propagates
          best[l] = take ? v[l] : best[l];
          at[l] = take ? here : at[l];
        }
      }
    for (int l = 0; l < L; ++l) py[o * L + l] = best[l], pa[o * L + l] = at[l];
  });
  return y;
}

template <class T, int L>
Tensor max_pool_backward(const Tensor& x, const PoolGeometry& g, const Tensor& gy,
                                 const Tensor& argmax) {
  Tensor gx = Tensor::zeros(x.shape(), x.dtype());
  const T* pg = gy.data<T>();
  const int64_t* pa = argmax.data<int64_t>();
  T* px = gx.data<T>();
  const int64_t out = g.Ho * g.Wo;
#pragma omp parallel for num_threads(num_threads()) if (g.planes * out > 4096)
  for (int64_t pl = 0; pl < g.planes; ++pl)
    for (int64_t o = 0; o < out; ++o)
      for (int l = 0; l < L; ++l) {
        const int64_t k = (pl * out + o) * L + l;
        px[(pl * g.H * g.W + pa[k]) * L + l] += pg[k];
      }
  return gx;
}

// ---- average pool, count_include_pad: every window divides by k·k ----

template <class T>
Tensor avg_pool_forward(const Tensor& x, const PoolGeometry& g) {
  Tensor y = Tensor::empty({x.size(0), x.size(1), g.Ho, g.Wo}, x.dtype());
  const T* px = x.data<T>();
  T* py = y.data<T>();
  const T inv = T(1) / T(g.k * g.k);
  for_each_window(g, 16384, [&](int64_t pl, int64_t o, int64_t h0, int64_t h1, int64_t w0, int64_t w1) {
    const T* xp = px + pl * g.H * g.W;
    T acc = 0;
    for (int64_t h = h0; h < h1; ++h)
      for (int64_t w = w0; w < w1; ++w) acc += xp[h * g.W + w];
    py[o] = acc * inv;
  });
  return y;
}

template <class T>
Tensor avg_pool_backward(const Tensor& x, const PoolGeometry& g, const Tensor& gy) {
  Tensor gx = Tensor::zeros(x.shape(), x.dtype());
  const T* pg = gy.data<T>();
  T* px = gx.data<T>();
  const T inv = T(1) / T(g.k * g.k);
  for_each_window(g, 16384, [&](int64_t pl, int64_t o, int64_t h0, int64_t h1, int64_t w0, int64_t w1) {
    T* xp = px + pl * g.H * g.W;
    const T v = pg[o] * inv;
    for (int64_t h = h0; h < h1; ++h)
      for (int64_t w = w0; w < w1; ++w) xp[h * g.W + w] += v;
  });
  return gx;
}

// ---- adaptive average pool: bin i covers [floor(i·H/out), ceil((i+1)·H/out)) ----

struct AdaptiveGeometry {
  int64_t planes, H, W, Ho, Wo;
  int64_t h0(int64_t i) const { return i * H / Ho; }
  int64_t h1(int64_t i) const { return ((i + 1) * H + Ho - 1) / Ho; }
  int64_t w0(int64_t j) const { return j * W / Wo; }
  int64_t w1(int64_t j) const { return ((j + 1) * W + Wo - 1) / Wo; }
};

AdaptiveGeometry adaptive_geometry(const Tensor& x, const Attrs& a) {
  check_nchw("adaptive_avg_pool2d", x);
  AdaptiveGeometry g{x.size(0) * x.size(1), x.size(2), x.size(3), a.get_int("out_h"),
                     a.get_int("out_w")};
  if (g.Ho <= 0 || g.Wo <= 0)
    fail("adaptive_avg_pool2d: output size ", g.Ho, "x", g.Wo, " must be positive; input ",
         describe(x));
  return g;
}

template <class T>
Tensor adaptive_forward(const Tensor& x, const AdaptiveGeometry& g) {
  Tensor y = Tensor::empty({x.size(0), x.size(1), g.Ho, g.Wo}, x.dtype());
  const T* px = x.data<T>();
  T* py = y.data<T>();
  for_each_window(g, 16384, [&](int64_t pl, int64_t o, int64_t h0, int64_t h1, int64_t w0, int64_t w1) {
    const T* xp = px + pl * g.H * g.W;
    T acc = 0;
    for (int64_t h = h0; h < h1; ++h)
      for (int64_t w = w0; w < w1; ++w) acc += xp[h * g.W + w];
    py[o] = acc / T((h1 - h0) * (w1 - w0));
  });
  return y;
}

template <class T>
Tensor adaptive_backward(const Tensor& x, const AdaptiveGeometry& g, const Tensor& gy) {
  Tensor gx = Tensor::zeros(x.shape(), x.dtype());
  const T* pg = gy.data<T>();
  T* px = gx.data<T>();
  for_each_window(g, 16384, [&](int64_t pl, int64_t o, int64_t h0, int64_t h1, int64_t w0, int64_t w1) {
    T* xp = px + pl * g.H * g.W;
    const T v = pg[o] / T((h1 - h0) * (w1 - w0));
    for (int64_t h = h0; h < h1; ++h)
      for (int64_t w = w0; w < w1; ++w) xp[h * g.W + w] += v;
  });
  return gx;
}

// ---- global average pool: [N,C,H,W] -> [N,C] ----

template <class T>
Tensor global_forward(const Tensor& x) {
  const int64_t planes = x.size(0) * x.size(1), hw = x.size(2) * x.size(3);
  Tensor y = Tensor::empty({x.size(0), x.size(1)}, x.dtype());
  const T* px = x.data<T>();
  T* py = y.data<T>();
#pragma omp parallel for num_threads(num_threads()) if (planes * hw > 16384)
  for (int64_t pl = 0; pl < planes; ++pl) {
    double acc = 0;  // a whole plane: accumulate in double
    for (int64_t i = 0; i < hw; ++i) acc += px[pl * hw + i];
    py[pl] = static_cast<T>(acc / static_cast<double>(hw));
  }
  return y;
}

template <class T>
Tensor global_backward(const Tensor& x, const Tensor& gy) {
  const int64_t planes = x.size(0) * x.size(1), hw = x.size(2) * x.size(3);
  Tensor gx = Tensor::empty(x.shape(), x.dtype());
  const T* pg = gy.data<T>();
  T* px = gx.data<T>();
  const T inv = T(1) / T(hw);
#pragma omp parallel for num_threads(num_threads()) if (planes * hw > 16384)
  for (int64_t pl = 0; pl < planes; ++pl) std::fill(px + pl * hw, px + (pl + 1) * hw, pg[pl] * inv);
  return gx;
}

}  // namespace

WEFT_REGISTER_OP(max_pool2d) {
  OpDef d;
  d.name = "max_pool2d";
  d.doc = "max over k×k windows of [N,C,H,W], or of a blocked [N,C/L,H,W,L] with attr "
          "channel_block L (attrs kernel, stride, padding; padding is -inf)";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const int64_t L = c.attrs.get_int("channel_block", 1);
    if (L != 1 && L != 8 && L != 16)
      fail("max_pool2d: channel_block must be 1, 8 or 16; got ", L);
    const PoolGeometry g = pool_geometry("max_pool2d", c.in(0), c.attrs, L);
    Tensor argmax;
    Tensor y = dispatch_float(c.in(0).dtype(), "max_pool2d", [&]<class T>() {
      if (L == 16) return max_pool_forward<T, 16>(c.in(0), g, argmax);
      if (L == 8) return max_pool_forward<T, 8>(c.in(0), g, argmax);
      return max_pool_forward<T, 1>(c.in(0), g, argmax);
    });
    c.saved.push_back(argmax);
    return y;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const int64_t L = c.attrs.get_int("channel_block", 1);
    const PoolGeometry g = pool_geometry("max_pool2d", c.in(0), c.attrs, L);
    return {dispatch_float(c.in(0).dtype(), "max_pool2d", [&]<class T>() {
      const Tensor& gy = c.grad_output;
      if (L == 16) return max_pool_backward<T, 16>(c.in(0), g, gy, c.saved.at(0));
      if (L == 8) return max_pool_backward<T, 8>(c.in(0), g, gy, c.saved.at(0));
      return max_pool_backward<T, 1>(c.in(0), g, gy, c.saved.at(0));
    })};
  };
  return d;
}

WEFT_REGISTER_OP(avg_pool2d) {
  OpDef d;
  d.name = "avg_pool2d";
  d.doc = "mean over k×k windows of [N,C,H,W] (attrs kernel, stride, padding; "
          "count_include_pad)";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const PoolGeometry g = pool_geometry("avg_pool2d", c.in(0), c.attrs);
    return dispatch_float(c.in(0).dtype(), "avg_pool2d",
                          [&]<class T>() { return avg_pool_forward<T>(c.in(0), g); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const PoolGeometry g = pool_geometry("avg_pool2d", c.in(0), c.attrs);
    return {dispatch_float(c.in(0).dtype(), "avg_pool2d", [&]<class T>() {
      return avg_pool_backward<T>(c.in(0), g, c.grad_output);
    })};
  };
  return d;
}

WEFT_REGISTER_OP(adaptive_avg_pool2d) {
  OpDef d;
  d.name = "adaptive_avg_pool2d";
  d.doc = "mean over out_h×out_w adaptive bins of [N,C,H,W] (PyTorch's bin edges)";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const AdaptiveGeometry g = adaptive_geometry(c.in(0), c.attrs);
    return dispatch_float(c.in(0).dtype(), "adaptive_avg_pool2d",
                          [&]<class T>() { return adaptive_forward<T>(c.in(0), g); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const AdaptiveGeometry g = adaptive_geometry(c.in(0), c.attrs);
    return {dispatch_float(c.in(0).dtype(), "adaptive_avg_pool2d", [&]<class T>() {
      return adaptive_backward<T>(c.in(0), g, c.grad_output);
    })};
  };
  return d;
}

WEFT_REGISTER_OP(global_avg_pool2d) {
  OpDef d;
  d.name = "global_avg_pool2d";
  d.doc = "mean over H and W: [N,C,H,W] -> [N,C]";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    check_nchw("global_avg_pool2d", c.in(0));
    return dispatch_float(c.in(0).dtype(), "global_avg_pool2d",
                          [&]<class T>() { return global_forward<T>(c.in(0)); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {dispatch_float(c.in(0).dtype(), "global_avg_pool2d", [&]<class T>() {
      return global_backward<T>(c.in(0), c.grad_output);
    })};
  };
  return d;
}

namespace ops {
Tensor max_pool2d(const Tensor& x, int64_t kernel, int64_t stride, int64_t padding,
                  int64_t channel_block) {
  Attrs attrs = pool_attrs(kernel, stride, padding);
  if (channel_block != 1) attrs.set("channel_block", channel_block);
  return apply("max_pool2d", {x}, attrs);
}
Tensor avg_pool2d(const Tensor& x, int64_t kernel, int64_t stride, int64_t padding) {
  return apply("avg_pool2d", {x}, pool_attrs(kernel, stride, padding));
}
Tensor adaptive_avg_pool2d(const Tensor& x, int64_t out_h, int64_t out_w) {
  return apply("adaptive_avg_pool2d", {x}, {{"out_h", out_h}, {"out_w", out_w}});
}
Tensor global_avg_pool2d(const Tensor& x) { return apply("global_avg_pool2d", {x}); }
}  // namespace ops

}  // namespace weft
