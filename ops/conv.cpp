// conv2d, NCHW, as im2col + GEMM (Eigen), with forward and backward.
//
// Per image n, with K = C·kh·kw and P = Ho·Wo:
//   col_n [K, P]   = im2col(x_n)            (skipped for 1×1 stride-1 pad-0: col_n = x_n)
//   y_n   [O, P]   = W [O, K] · col_n + bias
//   dW    [O, K]  += dy_n · col_nᵀ
//   dcol  [K, P]   = Wᵀ · dy_n,  dx_n = col2im(dcol)   (1×1 fast path: dx_n = Wᵀ · dy_n)
// Every product sums its depth (K, O or the columns) in short blocks
// (ops/depth_blocked_gemm.h), which keeps float32 results within PyTorch's accuracy.
//
// Threading (see conv_plan): OpenMP over groups of images, each GEMM single-threaded,
// when there are at least as many images as threads; else the images in turn with
// Eigen's threaded GEMM. At batch 8 on 2 threads, interleaved A/B runs on the shared
// machine had the batch-parallel form ahead on all nine ResNet-50 shapes tried, forward
// and backward (Eigen's threaded GEMM synchronises once per panel, and each sync costs
// a scheduler slice when other jobs hold a core). Each thread reuses its column and
// staging buffers across calls (thread_local): the hot loop does not allocate.
#include <omp.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstring>
#include <vector>

#include "graph/threads.h"
#include "ops/conv_backend.h"
#include "ops/conv_geometry.h"
#include "ops/conv_onednn.h"
#include "ops/depth_blocked_gemm.h"
#include "ops/ops.h"

namespace weft {
namespace {

template <class T>
using RowMat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
template <class T>
using CMapMat = Eigen::Map<const RowMat<T>>;
template <class T>
using CMapVec = Eigen::Map<const Eigen::Matrix<T, Eigen::Dynamic, 1>>;

std::string conv_desc(const Tensor& x, const Tensor& w) {
  return "input " + describe(x) + ", weight " + describe(w);
}

}  // namespace

ConvGeometry conv_geometry(const std::vector<Tensor>& in, const Attrs& a) {
  if (in.size() != 2 && in.size() != 3)
    fail("conv2d: expected 2 inputs (x, weight) or 3 (x, weight, bias), got ", in.size());
  const Tensor& x = in[0];
  const Tensor& w = in[1];
  const int64_t block = a.get_int("channel_block", 1);
  if (block != 1 && block != 8 && block != 16)
    fail("conv2d: channel_block must be 1 (NCHW), 8 or 16; got ", block, "; ", conv_desc(x, w));
  // A blocked output may come from a blocked or an NCHW input (rank 5 or 4).
  const bool blocked_in = block > 1 && x.dim() == 5;
  if ((x.dim() != 4 && !blocked_in) || w.dim() != 4 || (blocked_in && x.size(4) != block))
    fail("conv2d: expected an input [N,C,H,W]",
         block > 1 ? " or [N,C/" + std::to_string(block) + ",H,W," + std::to_string(block) + "]"
                   : std::string(),
         " and a 4-D weight [O,C,kh,kw]; got ", conv_desc(x, w));
  if (x.dtype() != w.dtype()) fail("conv2d: dtype mismatch: ", conv_desc(x, w));
  if (x.dtype() == DType::I64) fail("conv2d: expected float32 or float64, got ", conv_desc(x, w));
  ConvGeometry g{};
  g.block = block;
  g.in_block = blocked_in ? block : 1;
  g.N = x.size(0), g.C = x.size(1) * g.in_block, g.H = x.size(2), g.W = x.size(3);
  if (block > 1 && w.size(0) % block != 0)
    fail("conv2d: a blocked output needs output channels divisible by ", block, "; ",
         conv_desc(x, w));
  g.O = w.size(0), g.kh = w.size(2), g.kw = w.size(3);
  if (w.size(1) != g.C)
    fail("conv2d: weight has ", w.size(1), " input channels but the input has ", g.C, "; ",
         conv_desc(x, w));
  if (in.size() == 3) {
    const Tensor& b = in[2];
    if (b.dtype() != x.dtype())
      fail("conv2d: bias dtype mismatch: bias ", describe(b), ", ", conv_desc(x, w));
    if (b.dim() != 1 || b.size(0) != g.O)
      fail("conv2d: bias must be [", g.O, "] (one per output channel); got bias ", describe(b),
           ", ", conv_desc(x, w));
  }
  const std::vector<int64_t> stride = a.get_ints("stride", {1, 1});
  const std::vector<int64_t> pad = a.get_ints("padding", {0, 0});
  const std::vector<int64_t> dil = a.get_ints("dilation", {1, 1});
  if (stride.size() != 2 || pad.size() != 2 || dil.size() != 2)
    fail("conv2d: stride, padding and dilation need two values (h, w); ", conv_desc(x, w));
  g.sh = stride[0], g.sw = stride[1], g.ph = pad[0], g.pw = pad[1], g.dh = dil[0], g.dw = dil[1];
  if (g.sh <= 0 || g.sw <= 0 || g.dh <= 0 || g.dw <= 0 || g.ph < 0 || g.pw < 0)
    fail("conv2d: stride (", g.sh, ", ", g.sw, ") and dilation (", g.dh, ", ", g.dw,
         ") must be positive and padding (", g.ph, ", ", g.pw, ") non-negative; ",
         conv_desc(x, w));
  const int64_t ext_h = g.dh * (g.kh - 1) + 1, ext_w = g.dw * (g.kw - 1) + 1;
  if (ext_h > g.H + 2 * g.ph || ext_w > g.W + 2 * g.pw)
    fail("conv2d: dilated kernel ", ext_h, "x", ext_w, " is larger than the padded input ",
         g.H + 2 * g.ph, "x", g.W + 2 * g.pw, "; ", conv_desc(x, w));
  g.Ho = (g.H + 2 * g.ph - ext_h) / g.sh + 1;
  g.Wo = (g.W + 2 * g.pw - ext_w) / g.sw + 1;
  return g;
}

namespace {

// Output columns ow whose input column ow·sw + off lies in [0, W): [lo, hi).
inline void valid_range(int64_t off, int64_t sw, int64_t W, int64_t Wo, int64_t& lo,
                        int64_t& hi) {
  lo = off >= 0 ? 0 : (-off + sw - 1) / sw;
  const int64_t n = W - off;  // ow·sw < n
  hi = n <= 0 ? 0 : (n + sw - 1) / sw;
  lo = std::min(lo, Wo);
  hi = std::clamp(hi, lo, Wo);
}

// x [C, H, W] -> the columns of one image in col [K, ld] (its P columns start at col;
// ld ≥ P when several images share the matrix); padding reads as 0.
template <class T>
void im2col(const T* x, const ConvGeometry& g, T* col, int64_t ld) {
  for (int64_t c = 0; c < g.C; ++c) {
    const T* xc = x + c * g.H * g.W;
    for (int64_t ki = 0; ki < g.kh; ++ki) {
      for (int64_t kj = 0; kj < g.kw; ++kj) {
        T* row = col + ((c * g.kh + ki) * g.kw + kj) * ld;
        const int64_t off_w = kj * g.dw - g.pw;
        int64_t lo, hi;
        valid_range(off_w, g.sw, g.W, g.Wo, lo, hi);
        for (int64_t oh = 0; oh < g.Ho; ++oh) {
          T* r = row + oh * g.Wo;
          const int64_t ih = oh * g.sh - g.ph + ki * g.dh;
          if (ih < 0 || ih >= g.H) {
            std::fill(r, r + g.Wo, T(0));
            continue;
          }
          const T* xr = xc + ih * g.W + off_w;
          std::fill(r, r + lo, T(0));
          if (g.sw == 1) {
            std::memcpy(r + lo, xr + lo, sizeof(T) * (hi - lo));
          } else {
            for (int64_t ow = lo; ow < hi; ++ow) r[ow] = xr[ow * g.sw];
          }
          std::fill(r + hi, r + g.Wo, T(0));
        }
      }
    }
  }
}

// dx [C, H, W] += col2im(dcol); the adjoint of im2col (same layout and ld).
template <class T>
void col2im_add(const T* dcol, const ConvGeometry& g, T* dx, int64_t ld) {
  for (int64_t c = 0; c < g.C; ++c) {
    T* xc = dx + c * g.H * g.W;
    for (int64_t ki = 0; ki < g.kh; ++ki) {
      for (int64_t kj = 0; kj < g.kw; ++kj) {
        const T* row = dcol + ((c * g.kh + ki) * g.kw + kj) * ld;
        const int64_t off_w = kj * g.dw - g.pw;
        int64_t lo, hi;
        valid_range(off_w, g.sw, g.W, g.Wo, lo, hi);
        for (int64_t oh = 0; oh < g.Ho; ++oh) {
          const int64_t ih = oh * g.sh - g.ph + ki * g.dh;
          if (ih < 0 || ih >= g.H) continue;
          const T* r = row + oh * g.Wo;
          T* xr = xc + ih * g.W + off_w;
          if (g.sw == 1) {
            for (int64_t ow = lo; ow < hi; ++ow) xr[ow] += r[ow];
          } else {
            for (int64_t ow = lo; ow < hi; ++ow) xr[ow * g.sw] += r[ow];
          }
        }
      }
    }
  }
}

// Copies rows×P blocks between one image's [rows, P] matrix and its columns in a shared
// [rows, ld] matrix.
template <class T>
void pack_image(const T* src, int64_t rows, int64_t P, T* dst, int64_t ld) {
  for (int64_t r = 0; r < rows; ++r) std::memcpy(dst + r * ld, src + r * P, sizeof(T) * P);
}
template <class T>
void unpack_image(const T* src, int64_t rows, int64_t P, int64_t ld, T* dst) {
  for (int64_t r = 0; r < rows; ++r) std::memcpy(dst + r * P, src + r * ld, sizeof(T) * P);
}

// Reusable scratch per thread, dtype and use (0: columns, 1: output/gradient staging,
// 2: weight-gradient accumulator); grows to the largest size asked for and is kept
// across calls.
template <class T, int Use>
T* scratch(int64_t elements) {
  thread_local std::vector<T> buffer;
  if (static_cast<int64_t>(buffer.size()) < elements) {
    buffer.clear();
    buffer.shrink_to_fit();
    buffer.resize(elements);
  }
  return buffer.data();
}

// How the batch is cut: images are taken in groups of G whose columns share one GEMM
// (G·P columns), so that the small late-stage images (P = Ho·Wo = 16..64 at 128×128
// input) still give the GEMM a wide right-hand side: on this machine the 4×4-output
// ResNet-50 layers ran at ~65–85 GFLOP/s per thread one image at a time and ~95–110
// with 64+ columns per GEMM (single thread, CPU time). With at least as
// many images as threads the groups run in parallel, each GEMM single-threaded, and G is
// capped so every thread gets the same number of groups; with fewer images than threads
// (e.g. one image at inference) the images run in turn and Eigen threads each GEMM.
struct ConvPlan {
  int64_t G, groups;
  bool parallel;
};

constexpr int64_t kMinGemmColumns = 512;

ConvPlan conv_plan(const ConvGeometry& g) {
  const int64_t threads = num_threads();
  ConvPlan p{1, g.N, false};
  while (p.G < g.N && p.G * g.P() < kMinGemmColumns) ++p.G;
  if (threads > 1 && g.N >= threads) {
    p.G = std::min(p.G, g.N / threads);
    const int64_t per_thread = ((g.N + p.G - 1) / p.G + threads - 1) / threads;
    p.G = (g.N + per_thread * threads - 1) / (per_thread * threads);
    p.parallel = true;
  }
  p.groups = (g.N + p.G - 1) / p.G;
  return p;
}

template <class F>
void for_each_group(const ConvPlan& p, F body) {
  if (p.parallel) {
#pragma omp parallel for num_threads(num_threads()) schedule(static)
    for (int64_t i = 0; i < p.groups; ++i) body(i);
  } else {
    for (int64_t i = 0; i < p.groups; ++i) body(i);
  }
}

// Builds the column matrix [K, Gi·P] of images [n0, n0 + Gi); returns it (for one
// pointwise image: the image itself, no copy).
template <class T>
const T* build_columns(const T* x, const ConvGeometry& g, int64_t n0, int64_t Gi) {
  const int64_t CHW = g.C * g.H * g.W, P = g.P(), ld = Gi * P;
  if (g.pointwise() && Gi == 1) return x + n0 * CHW;
  T* col = scratch<T, 0>(g.K() * ld);
  for (int64_t j = 0; j < Gi; ++j) {
    const T* xn = x + (n0 + j) * CHW;
    if (g.pointwise()) pack_image(xn, g.C, P, col + j * P, ld);
    else im2col(xn, g, col + j * P, ld);
  }
  return col;
}

template <class T>
Tensor conv_forward(const std::vector<Tensor>& in, const ConvGeometry& g) {
  const Tensor& x = in[0];
  const Tensor& w = in[1];
  Tensor y = Tensor::empty({g.N, g.O, g.Ho, g.Wo}, x.dtype());
  const int64_t K = g.K(), P = g.P();
  const T* px = x.data<T>();
  const T* pb = in.size() == 3 ? in[2].data<T>() : nullptr;
  T* py = y.data<T>();
  CMapMat<T> Wm(w.data<T>(), g.O, K);
  const ConvPlan plan = conv_plan(g);
  for_each_group(plan, [&](int64_t gi) {
    const int64_t n0 = gi * plan.G, Gi = std::min(plan.G, g.N - n0), ld = Gi * P;
    const T* col = build_columns(px, g, n0, Gi);
    // One image writes straight into y; a group is staged and then split per image.
    T* out = Gi == 1 ? py + n0 * g.O * P : scratch<T, 1>(g.O * ld);
    Eigen::Map<RowMat<T>> Y(out, g.O, ld);
    gemm_in_depth_blocks(Y, Wm, CMapMat<T>(col, K, ld), false);
    if (pb) Y.colwise() += CMapVec<T>(pb, g.O);
    if (Gi > 1)
      for (int64_t j = 0; j < Gi; ++j) unpack_image(out + j * P, g.O, P, ld, py + (n0 + j) * g.O * P);
  });
  return y;
}

template <class T>
std::vector<Tensor> conv_backward(const BackwardContext& c, const ConvGeometry& g) {
  const Tensor& x = c.in(0);
  const Tensor& w = c.in(1);
  const Tensor& gy = c.grad_output;
  const bool want_x = c.needs_grad[0], want_w = c.needs_grad[1];
  const bool want_b = c.inputs.size() == 3 && c.needs_grad[2];
  const int64_t K = g.K(), P = g.P(), CHW = g.C * g.H * g.W;
  const T* px = x.data<T>();
  const T* pgy = gy.data<T>();
  CMapMat<T> Wm(w.data<T>(), g.O, K);

  Tensor gx, gw, gb;
  // gx is zeroed image by image inside the (parallel) loop, where it is first touched.
  if (want_x) gx = Tensor::empty(x.shape(), x.dtype());
  if (want_w) gw = Tensor::empty(w.shape(), w.dtype());  // set by thread 0 below
  if (want_b) {
    gb = Tensor::zeros({g.O}, x.dtype());
    T* pgb = gb.data<T>();
    for (int64_t n = 0; n < g.N; ++n) {
      CMapMat<T> GY(pgy + n * g.O * P, g.O, P);
      Eigen::Map<Eigen::Matrix<T, Eigen::Dynamic, 1>>(pgb, g.O) += GY.rowwise().sum();
    }
  }
  auto result = [&]() -> std::vector<Tensor> {
    if (c.inputs.size() == 3) return {gx, gw, gb};
    return {gx, gw};
  };
  if (!want_x && !want_w) return result();

  // Weight gradient: each thread of the team accumulates its groups into its own
  // [O, K] matrix (thread 0 straight into gw, the others into reused thread-local
  // scratch), then the team sums them into gw, rows split across threads, in a fixed
  // order (results do not depend on scheduling).
  const ConvPlan plan = conv_plan(g);
  const int team = plan.parallel ? num_threads() : 1;
  std::vector<T*> acc(team, nullptr);
  T* pgw = want_w ? gw.data<T>() : nullptr;
  T* pgx = want_x ? gx.data<T>() : nullptr;

  // first: the group's product initialises the accumulator instead of adding to it.
  auto group = [&](int64_t gi, T* gw_acc, bool first) {
    const int64_t n0 = gi * plan.G, Gi = std::min(plan.G, g.N - n0), ld = Gi * P;
    // dy of the group as [O, Gi·P]
    const T* dy = pgy + n0 * g.O * P;
    if (Gi > 1) {
      T* stage = scratch<T, 1>(g.O * ld);
      for (int64_t j = 0; j < Gi; ++j)
        pack_image(pgy + (n0 + j) * g.O * P, g.O, P, stage + j * P, ld);
      dy = stage;
    }
    CMapMat<T> GY(dy, g.O, ld);
    if (want_w) {
      const T* col = build_columns(px, g, n0, Gi);
      Eigen::Map<RowMat<T>> GW(gw_acc, g.O, K);
      gemm_in_depth_blocks(GW, GY, CMapMat<T>(col, K, ld).transpose(), !first);
    }
    if (want_x) {
      if (g.pointwise() && Gi == 1) {
        gemm_in_depth_blocks(Eigen::Map<RowMat<T>>(pgx + n0 * CHW, g.C, P), Wm.transpose(), GY,
                             false);
      } else {
        T* dcol = scratch<T, 0>(K * ld);  // the columns are no longer needed
        gemm_in_depth_blocks(Eigen::Map<RowMat<T>>(dcol, K, ld), Wm.transpose(), GY, false);
        for (int64_t j = 0; j < Gi; ++j) {
          T* gxn = pgx + (n0 + j) * CHW;
          if (g.pointwise()) {
            unpack_image(dcol + j * P, g.C, P, ld, gxn);
          } else {
            std::fill(gxn, gxn + CHW, T(0));  // first touch by the thread that fills it
            col2im_add(dcol + j * P, g, gxn, ld);
          }
        }
      }
    }
  };
  // Thread t of a team of nt runs groups [groups·t/nt, groups·(t+1)/nt).
  auto run_share = [&](int t, int nt) {
    const int64_t g0 = plan.groups * t / nt, g1 = plan.groups * (t + 1) / nt;
    T* gw_acc = nullptr;
    if (want_w) {
      gw_acc = acc[t] = t == 0 ? pgw : scratch<T, 2>(g.O * K);
      if (g0 == g1) std::fill(gw_acc, gw_acc + g.O * K, T(0));  // no group to initialise it
    }
    for (int64_t gi = g0; gi < g1; ++gi) group(gi, gw_acc, gi == g0);
  };
  if (team == 1) {
    run_share(0, 1);
  } else {
#pragma omp parallel num_threads(team)
    {
      const int t = omp_get_thread_num(), nt = omp_get_num_threads();
      run_share(t, nt);
      if (want_w) {
#pragma omp barrier
        const int64_t r0 = g.O * t / nt, r1 = g.O * (t + 1) / nt;
        Eigen::Map<RowMat<T>> rows(pgw + r0 * K, r1 - r0, K);
        for (int s = 1; s < nt; ++s) rows += CMapMat<T>(acc[s] + r0 * K, r1 - r0, K);
      }
    }
  }
  return result();
}

// Copies between [N, C/L, H, W, L] (blocked) and [N, C, H, W], for the Eigen kernels,
// which are NCHW-native.
template <class T>
Tensor unblock(const Tensor& t) {
  const int64_t N = t.size(0), Cb = t.size(1), S = t.size(2) * t.size(3), L = t.size(4);
  Tensor out = Tensor::empty({N, Cb * L, t.size(2), t.size(3)}, t.dtype());
  const T* src = t.data<T>();
  T* dst = out.data<T>();
  for (int64_t nc = 0; nc < N * Cb; ++nc)
    for (int64_t p = 0; p < S; ++p)
      for (int64_t l = 0; l < L; ++l) dst[(nc * L + l) * S + p] = src[(nc * S + p) * L + l];
  return out;
}
template <class T>
Tensor to_blocks(const Tensor& t, int64_t L) {
  const int64_t N = t.size(0), Cb = t.size(1) / L, S = t.size(2) * t.size(3);
  Tensor out = Tensor::empty({N, Cb, t.size(2), t.size(3), L}, t.dtype());
  const T* src = t.data<T>();
  T* dst = out.data<T>();
  for (int64_t nc = 0; nc < N * Cb; ++nc)
    for (int64_t l = 0; l < L; ++l)
      for (int64_t p = 0; p < S; ++p) dst[(nc * S + p) * L + l] = src[(nc * L + l) * S + p];
  return out;
}

bool use_onednn(const Tensor& x) {
  return x.dtype() == DType::F32 && conv_backend() != ConvBackend::eigen;
}

// The Eigen kernels on blocked tensors: through NCHW copies.
template <class T>
Tensor eigen_forward(const std::vector<Tensor>& in, ConvGeometry g) {
  if (g.block == 1) return conv_forward<T>(in, g);
  const int64_t L = g.block;
  std::vector<Tensor> nchw = in;
  if (g.in_block > 1) nchw[0] = unblock<T>(in[0]);
  g.block = g.in_block = 1;
  return to_blocks<T>(conv_forward<T>(nchw, g), L);
}

template <class T>
std::vector<Tensor> eigen_backward(const BackwardContext& c, ConvGeometry g) {
  if (g.block == 1) return conv_backward<T>(c, g);
  const int64_t L = g.block, in_block = g.in_block;
  std::vector<Tensor> inputs = c.inputs;
  if (in_block > 1) inputs[0] = unblock<T>(c.in(0));
  g.block = g.in_block = 1;
  const Tensor gy = unblock<T>(c.grad_output);
  const BackwardContext nchw{inputs, c.output, gy, c.attrs, c.saved, c.needs_grad};
  std::vector<Tensor> grads = conv_backward<T>(nchw, g);
  if (grads[0].defined() && in_block > 1) grads[0] = to_blocks<T>(grads[0], L);
  return grads;
}

}  // namespace

WEFT_REGISTER_OP(conv2d) {
  OpDef d;
  d.name = "conv2d";
  d.doc = "2-D convolution: x [N,C,H,W] (or blocked [N,C/L,H,W,L] with channel_block L), "
          "weight [O,C,kh,kw], optional bias [O]; attrs stride, padding, dilation (h, w), "
          "channel_block; float32 on the backend of ops/conv_backend.h";
  d.num_inputs = -1;  // 2 or 3 (bias)
  d.forward = [](const ForwardContext& c) {
    const ConvGeometry g = conv_geometry(c.inputs, c.attrs);
    if (use_onednn(c.in(0)))
      return onednn_conv_forward(c.in(0), c.in(1), c.inputs.size() == 3 ? c.in(2) : Tensor(), g);
    return dispatch_float(c.in(0).dtype(), "conv2d",
                          [&]<class T>() { return eigen_forward<T>(c.inputs, g); });
  };
  d.backward = [](const BackwardContext& c) {
    const ConvGeometry g = conv_geometry(c.inputs, c.attrs);
    if (use_onednn(c.in(0))) {
      const bool has_bias = c.inputs.size() == 3;
      ConvGradients r = onednn_conv_backward(c.in(0), c.in(1), c.grad_output, g, c.needs_grad[0],
                                             c.needs_grad[1], has_bias && c.needs_grad[2]);
      if (has_bias) return std::vector<Tensor>{r.x, r.w, r.bias};
      return std::vector<Tensor>{r.x, r.w};
    }
    return dispatch_float(c.in(0).dtype(), "conv2d",
                          [&]<class T>() { return eigen_backward<T>(c, g); });
  };
  return d;
}

namespace {

// y = relu?(y · scale[c] + shift[c] + z), in place, c the output channel of each element
// (NCHW or channel blocks).
template <class T>
void apply_epilogue(Tensor& y, const ConvGeometry& g, const ConvEpilogue& e) {
  T* py = y.data<T>();
  const T* ps = e.scale.data<T>();
  const T* pb = e.shift.data<T>();
  const T* pz = e.residual.defined() ? e.residual.data<T>() : nullptr;
  const int64_t L = g.block, P = g.P(), n = y.numel();
#pragma omp parallel for num_threads(num_threads()) if (n > 65536)
  for (int64_t i = 0; i < n; ++i) {
    const int64_t c = L > 1 ? (i / (P * L)) % (g.O / L) * L + i % L : (i / P) % g.O;
    T v = py[i] * ps[c] + pb[c];
    if (pz) v += pz[i];
    py[i] = e.relu ? std::max(T(0), v) : v;
  }
}

}  // namespace

WEFT_REGISTER_OP(conv2d_affine) {
  OpDef d;
  d.name = "conv2d_affine";
  d.doc = "inference: relu?(conv2d(x, w) * scale[o] + shift[o] (+ residual)), a conv with "
          "its batch norm folded in; inputs x, weight, scale, shift, optional residual; attrs "
          "as conv2d and relu; no gradient";
  d.num_inputs = -1;  // 4 or 5
  d.differentiable = false;
  d.forward = [](const ForwardContext& c) {
    if (c.inputs.size() != 4 && c.inputs.size() != 5)
      fail("conv2d_affine: expected 4 inputs (x, weight, scale, shift) or 5 (and a residual), "
           "got ", c.inputs.size());
    const ConvGeometry g = conv_geometry({c.in(0), c.in(1)}, c.attrs);
    ConvEpilogue e{c.in(2), c.in(3), c.inputs.size() == 5 ? c.in(4) : Tensor(),
                   c.attrs.get_bool("relu", false)};
    for (const Tensor* t : {&e.scale, &e.shift})
      if (t->dtype() != c.in(0).dtype() || t->dim() != 1 || t->size(0) != g.O)
        fail("conv2d_affine: scale and shift must be [", g.O, "] of the input's dtype; got ",
             describe(*t));
    if (e.residual.defined() &&
        (e.residual.shape() != g.output_shape() || e.residual.dtype() != c.in(0).dtype()))
      fail("conv2d_affine: the residual ", describe(e.residual), " must match the output ",
           shape_str(g.output_shape()));
    if (use_onednn(c.in(0)) && g.block > 1)
      return onednn_conv_forward(c.in(0), c.in(1), Tensor(), g, &e);
    Tensor y = use_onednn(c.in(0))
                   ? onednn_conv_forward(c.in(0), c.in(1), Tensor(), g)
                   : dispatch_float(c.in(0).dtype(), "conv2d_affine", [&]<class T>() {
                       return eigen_forward<T>({c.in(0), c.in(1)}, g);
                     });
    dispatch_float(y.dtype(), "conv2d_affine", [&]<class T>() {
      apply_epilogue<T>(y, g, e);
      return 0;
    });
    return y;
  };
  return d;
}

namespace ops {
namespace {
Attrs conv_attrs(const Conv2dOptions& o) {
  return {{"stride", std::vector<int64_t>{o.stride_h, o.stride_w}},
          {"padding", std::vector<int64_t>{o.pad_h, o.pad_w}},
          {"dilation", std::vector<int64_t>{o.dilation_h, o.dilation_w}},
          {"channel_block", o.channel_block}};
}
}  // namespace

Tensor conv2d(const Tensor& x, const Tensor& w, const Tensor& bias, const Conv2dOptions& o) {
  const Attrs attrs = conv_attrs(o);
  if (bias.defined()) return apply("conv2d", {x, w, bias}, attrs);
  return apply("conv2d", {x, w}, attrs);
}

Tensor conv2d_affine(const Tensor& x, const Tensor& w, const Tensor& scale, const Tensor& shift,
                     const Tensor& residual, bool relu, const Conv2dOptions& o) {
  Attrs attrs = conv_attrs(o);
  attrs.set("relu", relu);
  if (residual.defined()) return apply("conv2d_affine", {x, w, scale, shift, residual}, attrs);
  return apply("conv2d_affine", {x, w, scale, shift}, attrs);
}
}  // namespace ops

}  // namespace weft
