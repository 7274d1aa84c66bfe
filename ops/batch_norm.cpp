// batch_norm over axis 1 of x [N, C, ...] with PyTorch's semantics; or, with attr
// channel_block L > 1, over the channels of a blocked x [N, C/L, ..., L] (channel
// c = cb·L + l, the layout of ops::Conv2dOptions::channel_block). An optional sixth
// input z (x's shape) is added to the result, and with attr relu the result is
// max(0, ·), in the same pass (the backward masks dy by it and gives z that masked dy):
// the batch_norm [+ shortcut] + relu of a ResNet block without their passes over memory.
// Roundings are those of the unfused ops: the normalised value is rounded to T, then z
// is added in T.
//
// Inputs: x, weight [C], bias [C], running_mean [C], running_var [C]; attrs training,
// momentum, eps. With M = N · (product of the trailing axes) values per channel:
//   training: y = (x − μ_B) / sqrt(σ²_B + eps) · w + b with the batch mean μ_B and the
//             BIASED batch variance σ²_B; then, in place,
//             running_mean = (1 − m) running_mean + m μ_B,
//             running_var  = (1 − m) running_var  + m σ²_B · M / (M − 1)   (unbiased);
//   eval:     the same with the running statistics, which are left alone.
// Gradients flow to x, weight and bias (training: through the batch statistics too);
// the running statistics get none. Per-channel sums accumulate in double, the
// normalisation is computed in double and rounded once, and the batch statistics are
// saved for the backward in double.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <type_traits>
#include <cmath>
#include <vector>

#include "graph/threads.h"
#include "ops/ops.h"

namespace weft {
namespace {

struct BnGeometry {
  int64_t N, C, S, L;  // x viewed as [N, C/L, S, L]
  int64_t M() const { return N * S; }
  int64_t blocks() const { return C / L; }
  // Offset of element (n, block cb, position i, lane l) is ((n·C/L + cb)·S + i)·L + l.
  int64_t at(int64_t n, int64_t cb) const { return (n * blocks() + cb) * S * L; }
};

BnGeometry bn_geometry(const std::vector<Tensor>& in, const Attrs& attrs, bool training) {
  if (in.size() != 5 && in.size() != 6)
    fail("batch_norm: expected 5 inputs (x, weight, bias, running_mean, running_var) or 6 "
         "(and a residual), got ", in.size());
  const Tensor& x = in[0];
  if (x.dim() < 2) fail("batch_norm: expected x of rank >= 2 [N, C, ...], got ", describe(x));
  if (x.dtype() == DType::I64) fail("batch_norm: expected float32 or float64, got ", describe(x));
  const int64_t L = attrs.get_int("channel_block", 1);
  if (L != 1 && L != 8 && L != 16)
    fail("batch_norm: channel_block must be 1, 8 or 16; got ", L, "; x ", describe(x));
  if (L > 1 && (x.dim() < 3 || x.size(x.dim() - 1) != L))
    fail("batch_norm: channel_block ", L, " needs x [N, C/", L, ", ..., ", L, "]; got ",
         describe(x));
  BnGeometry g{x.size(0), x.size(1) * L, 1, L};
  for (int64_t a = 2; a < x.dim() - (L > 1 ? 1 : 0); ++a) g.S *= x.size(a);
  static const char* names[] = {"x", "weight", "bias", "running_mean", "running_var"};
  for (size_t i = 1; i < 5; ++i) {
    if (in[i].dtype() != x.dtype())
      fail("batch_norm: dtype mismatch: ", names[i], " ", describe(in[i]), " vs x ",
           describe(x));
    if (in[i].dim() != 1 || in[i].size(0) != g.C)
      fail("batch_norm: ", names[i], " must be [", g.C, "] (one per channel of x); got ",
           names[i], " ", describe(in[i]), ", x ", describe(x));
  }
  if (in.size() == 6 && (in[5].shape() != x.shape() || in[5].dtype() != x.dtype()))
    fail("batch_norm: the residual ", describe(in[5]), " must match x ", describe(x));
  if (training && g.M() < 2)
    fail("batch_norm: training needs more than one value per channel; x ", describe(x));
  return g;
}

template <class T, int L>
Tensor bn_forward(const ForwardContext& c, const BnGeometry& g, bool training) {
  const Tensor& x = c.in(0);
  const double momentum = c.attrs.get_float("momentum", 0.1);
  const double eps = c.attrs.get_float("eps", 1e-5);
  const bool relu = c.attrs.get_bool("relu", false);
  const T* px = x.data<T>();
  const T* pz = c.inputs.size() == 6 ? c.in(5).data<T>() : nullptr;
  const T* pw = c.in(1).data<T>();
  const T* pb = c.in(2).data<T>();
  // The running statistics are updated in place: the caller's tensors share this storage.
  Tensor running_mean = c.in(3), running_var = c.in(4);
  T* prm = running_mean.data<T>();
  T* prv = running_var.data<T>();

  // Saved in double whatever T is: the backward's x̂ = (x − μ) · inv then uses the exact
  // batch statistics, not their float32 roundings.
  Tensor mean = Tensor::empty({g.C}, DType::F64);
  Tensor invstd = Tensor::empty({g.C}, DType::F64);
  double* pmean = mean.data<double>();
  double* pinv = invstd.data<double>();
  Tensor y = Tensor::empty(x.shape(), x.dtype());
  T* py = y.data<T>();
  const double M = static_cast<double>(g.M());

  // One block of L channels per iteration, the lanes innermost (vectorised).
#pragma omp parallel for num_threads(num_threads()) if (x.numel() > 32768)
  for (int64_t cb = 0; cb < g.blocks(); ++cb) {
    double mu[L], var[L], a[L], shift[L];
    if (training) {
      // One pass over x: sums of d = x − k and d² in double, with k the channel's first
      // value, so E[d²] − E[d]² does not cancel (|E[d]| is of the order of σ).
      double k[L], s[L] = {}, ss[L] = {};
      for (int l = 0; l < L; ++l) k[l] = px[g.at(0, cb) + l];
      for (int64_t n = 0; n < g.N; ++n) {
        const T* p = px + g.at(n, cb);
        for (int64_t i = 0; i < g.S; ++i)
#pragma omp simd
          for (int l = 0; l < L; ++l) {
            const double d = p[i * L + l] - k[l];
            s[l] += d;
            ss[l] += d * d;
          }
      }
      for (int l = 0; l < L; ++l) {
        mu[l] = k[l] + s[l] / M;
        ss[l] = std::max(0.0, ss[l] - s[l] * s[l] / M);
      }
      for (int l = 0; l < L; ++l) {
        const int64_t ch = cb * L + l;
        var[l] = ss[l] / M;
        prm[ch] = static_cast<T>((1 - momentum) * prm[ch] + momentum * mu[l]);
        prv[ch] = static_cast<T>((1 - momentum) * prv[ch] + momentum * var[l] * M / (M - 1));
      }
    } else {
      for (int l = 0; l < L; ++l) mu[l] = prm[cb * L + l], var[l] = prv[cb * L + l];
    }
    // y = x · a + b'  with a = inv · w, b' = b − μ · a, in double and rounded once: in
    // float32 the rounded a and b' and the cancellation of x · a against b' (|μ| ≫ σ)
    // cost up to a few ulps of y.
    for (int l = 0; l < L; ++l) {
      const int64_t ch = cb * L + l;
      const double inv = 1.0 / std::sqrt(var[l] + eps);
      pmean[ch] = mu[l];
      pinv[ch] = inv;
      a[l] = inv * pw[ch];
      shift[l] = pb[ch] - mu[l] * a[l];
    }
    for (int64_t n = 0; n < g.N; ++n) {
      const T* p = px + g.at(n, cb);
      T* q = py + g.at(n, cb);
      const T* z = pz ? pz + g.at(n, cb) : nullptr;
      if (z && relu) {
        for (int64_t i = 0; i < g.S; ++i)
          for (int l = 0; l < L; ++l)
            q[i * L + l] =
                std::max(T(0), static_cast<T>(p[i * L + l] * a[l] + shift[l]) + z[i * L + l]);
      } else if (z) {
        for (int64_t i = 0; i < g.S; ++i)
          for (int l = 0; l < L; ++l)
            q[i * L + l] = static_cast<T>(p[i * L + l] * a[l] + shift[l]) + z[i * L + l];
      } else if (relu) {
        for (int64_t i = 0; i < g.S; ++i)
          for (int l = 0; l < L; ++l)
            q[i * L + l] = std::max(T(0), static_cast<T>(p[i * L + l] * a[l] + shift[l]));
      } else {
        for (int64_t i = 0; i < g.S; ++i)
          for (int l = 0; l < L; ++l) q[i * L + l] = static_cast<T>(p[i * L + l] * a[l] + shift[l]);
      }
    }
  }
  c.saved.push_back(mean);
  c.saved.push_back(invstd);
  if (relu) c.saved.push_back(y.detach());  // the mask of the backward (no graph: no cycle)
  return y;
}

// dy where the fused relu's result r is positive, else exactly 0 (PyTorch's
// threshold_backward), as a bit mask: a ternary here compiled to a branch per element,
// mispredicted half the time, 4–8× slower than the whole unfused backward.
template <class T>
inline T where_positive(T r, T dy) {
  using Bits = std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>;
  const Bits mask = Bits(0) - static_cast<Bits>(r > T(0));
  return std::bit_cast<T>(std::bit_cast<Bits>(dy) & mask);
}

template <class T, int L, bool Relu>
std::vector<Tensor> bn_backward(const BackwardContext& c, const BnGeometry& g, bool training) {
  const Tensor& x = c.in(0);
  const T* px = x.data<T>();
  const T* pw = c.in(1).data<T>();
  const T* pgy = c.grad_output.data<T>();
  const double* pmean = c.saved.at(0).data<double>();
  const double* pinv = c.saved.at(1).data<double>();
  // With relu: dy where the result was positive, else 0 (PyTorch's threshold_backward).
  const T* prelu = Relu ? c.saved.at(2).data<T>() : nullptr;
  const bool want_x = c.needs_grad[0], want_w = c.needs_grad[1], want_b = c.needs_grad[2];
  const bool want_z = c.inputs.size() == 6 && c.needs_grad[5];
  Tensor gx, gw, gb, gz;
  if (want_x) gx = Tensor::empty(x.shape(), x.dtype());
  if (want_z) gz = Tensor::empty(x.shape(), x.dtype());
  T* pgz = want_z ? gz.data<T>() : nullptr;
  if (want_w) gw = Tensor::empty({g.C}, x.dtype());
  if (want_b) gb = Tensor::empty({g.C}, x.dtype());
  T* pgx = want_x ? gx.data<T>() : nullptr;
  T* pgw = want_w ? gw.data<T>() : nullptr;
  T* pgb = want_b ? gb.data<T>() : nullptr;
  const double M = static_cast<double>(g.M());

#pragma omp parallel for num_threads(num_threads()) if (x.numel() > 32768)
  for (int64_t cb = 0; cb < g.blocks(); ++cb) {
    double mu[L], inv[L];
    for (int l = 0; l < L; ++l) mu[l] = pmean[cb * L + l], inv[l] = pinv[cb * L + l];
    // Σ dy and Σ dy · x̂ over the channel, x̂ = (x − μ) · inv
    double sum_dy[L] = {}, sum_dy_xhat[L] = {};
    for (int64_t n = 0; n < g.N; ++n) {
      const T* p = px + g.at(n, cb);
      const T* d = pgy + g.at(n, cb);
      const T* r = Relu ? prelu + g.at(n, cb) : nullptr;
      for (int64_t i = 0; i < g.S; ++i)
        for (int l = 0; l < L; ++l) {
          const T dv = Relu ? where_positive(r[i * L + l], d[i * L + l]) : d[i * L + l];
          sum_dy[l] += dv;
          sum_dy_xhat[l] += dv * (p[i * L + l] - mu[l]) * inv[l];
        }
    }
    for (int l = 0; l < L; ++l) {
      if (pgw) pgw[cb * L + l] = static_cast<T>(sum_dy_xhat[l]);
      if (pgb) pgb[cb * L + l] = static_cast<T>(sum_dy[l]);
    }
    if (!pgx && !pgz) continue;
    // training: dx = w·inv · (dy − mean(dy) − x̂ · mean(dy · x̂)); eval: dx = w·inv · dy
    double scale[L], mdy[L], k[L];
    for (int l = 0; l < L; ++l) {
      scale[l] = inv[l] * pw[cb * L + l];
      mdy[l] = training ? sum_dy[l] / M : 0.0;
      k[l] = training ? inv[l] * sum_dy_xhat[l] / M : 0.0;
    }
    for (int64_t n = 0; n < g.N; ++n) {
      const T* p = px + g.at(n, cb);
      const T* d = pgy + g.at(n, cb);
      const T* r = Relu ? prelu + g.at(n, cb) : nullptr;
      if (pgz) {  // the residual's gradient: the (masked) dy itself
        T* qz = pgz + g.at(n, cb);
        for (int64_t i = 0; i < g.S; ++i)
          for (int l = 0; l < L; ++l)
            qz[i * L + l] = Relu ? where_positive(r[i * L + l], d[i * L + l]) : d[i * L + l];
      }
      if (!pgx) continue;
      T* q = pgx + g.at(n, cb);
      for (int64_t i = 0; i < g.S; ++i)
        for (int l = 0; l < L; ++l) {
          const T dv = Relu ? where_positive(r[i * L + l], d[i * L + l]) : d[i * L + l];
          q[i * L + l] = static_cast<T>(scale[l] * (dv - mdy[l] - (p[i * L + l] - mu[l]) * k[l]));
        }
    }
  }
  if (c.inputs.size() == 6) return {gx, gw, gb, Tensor(), Tensor(), gz};
  return {gx, gw, gb, Tensor(), Tensor()};
}

}  // namespace

WEFT_REGISTER_OP(batch_norm) {
  OpDef d;
  d.name = "batch_norm";
  d.doc = "batch normalisation over axis 1, or over the channels of a blocked x with attr "
          "channel_block (PyTorch semantics; attrs training, momentum, eps, relu (max(0, y) "
          "fused); updates the running statistics in place when training)";
  d.num_inputs = -1;  // 5, or 6 with a residual
  d.forward = [](const ForwardContext& c) {
    const bool training = c.attrs.get_bool("training", false);
    const BnGeometry g = bn_geometry(c.inputs, c.attrs, training);
    return dispatch_float(c.in(0).dtype(), "batch_norm", [&]<class T>() {
      if (g.L == 16) return bn_forward<T, 16>(c, g, training);
      if (g.L == 8) return bn_forward<T, 8>(c, g, training);
      return bn_forward<T, 1>(c, g, training);
    });
  };
  d.backward = [](const BackwardContext& c) {
    const bool training = c.attrs.get_bool("training", false);
    const BnGeometry g = bn_geometry(c.inputs, c.attrs, false);
    const bool relu = c.attrs.get_bool("relu", false);
    return dispatch_float(c.in(0).dtype(), "batch_norm", [&]<class T>() {
      if (g.L == 16)
        return relu ? bn_backward<T, 16, true>(c, g, training) : bn_backward<T, 16, false>(c, g, training);
      if (g.L == 8)
        return relu ? bn_backward<T, 8, true>(c, g, training) : bn_backward<T, 8, false>(c, g, training);
      return relu ? bn_backward<T, 1, true>(c, g, training) : bn_backward<T, 1, false>(c, g, training);
    });
  };
  return d;
}

namespace ops {
Tensor batch_norm(const Tensor& x, const Tensor& weight, const Tensor& bias,
                  Tensor running_mean, Tensor running_var, bool training, double momentum,
                  double eps, const BatchNormExtras& extras) {
  const int64_t channel_block = extras.channel_block;
  if (!x.defined()) fail("batch_norm: x is undefined");
  // Undefined weight/bias act as 1 and 0; undefined running statistics (allowed only in
  // training, like track_running_stats=False) are scratch tensors nobody reads.
  const int64_t C = x.dim() >= 2 ? x.size(1) * channel_block : 1;
  const DType dt = x.dtype() == DType::I64 ? DType::F32 : x.dtype();
  if (!training && (!running_mean.defined() || !running_var.defined()))
    fail("batch_norm: eval mode needs running_mean and running_var; x ", describe(x));
  Attrs attrs{{"training", training}, {"momentum", momentum}, {"eps", eps}};
  if (channel_block != 1) attrs.set("channel_block", channel_block);
  if (extras.relu) attrs.set("relu", true);
  std::vector<Tensor> inputs{x, weight.defined() ? weight : Tensor::ones({C}, dt),
                             bias.defined() ? bias : Tensor::zeros({C}, dt),
                             running_mean.defined() ? running_mean : Tensor::zeros({C}, dt),
                             running_var.defined() ? running_var : Tensor::ones({C}, dt)};
  if (extras.residual.defined()) inputs.push_back(extras.residual);
  return apply("batch_norm", inputs, attrs);
}
}  // namespace ops

}  // namespace weft
