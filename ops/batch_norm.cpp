// batch_norm over axis 1 of x [N, C, ...] with PyTorch's semantics.
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
#include <cmath>
#include <vector>

#include "graph/threads.h"
#include "ops/ops.h"

namespace weft {
namespace {

struct BnGeometry {
  int64_t N, C, S;  // x viewed as [N, C, S]
  int64_t M() const { return N * S; }
};

BnGeometry bn_geometry(const std::vector<Tensor>& in, bool training) {
  if (in.size() != 5)
    fail("batch_norm: expected 5 inputs (x, weight, bias, running_mean, running_var), got ",
         in.size());
  const Tensor& x = in[0];
  if (x.dim() < 2) fail("batch_norm: expected x of rank >= 2 [N, C, ...], got ", describe(x));
  if (x.dtype() == DType::I64) fail("batch_norm: expected float32 or float64, got ", describe(x));
  BnGeometry g{x.size(0), x.size(1), 1};
  for (int64_t a = 2; a < x.dim(); ++a) g.S *= x.size(a);
  static const char* names[] = {"x", "weight", "bias", "running_mean", "running_var"};
  for (size_t i = 1; i < 5; ++i) {
    if (in[i].dtype() != x.dtype())
      fail("batch_norm: dtype mismatch: ", names[i], " ", describe(in[i]), " vs x ",
           describe(x));
    if (in[i].dim() != 1 || in[i].size(0) != g.C)
      fail("batch_norm: ", names[i], " must be [", g.C, "] (one per channel of x); got ",
           names[i], " ", describe(in[i]), ", x ", describe(x));
  }
  if (training && g.M() < 2)
    fail("batch_norm: training needs more than one value per channel; x ", describe(x));
  return g;
}

template <class T>
Tensor bn_forward(const ForwardContext& c, const BnGeometry& g, bool training) {
  const Tensor& x = c.in(0);
  const double momentum = c.attrs.get_float("momentum", 0.1);
  const double eps = c.attrs.get_float("eps", 1e-5);
  const T* px = x.data<T>();
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

#pragma omp parallel for num_threads(num_threads()) if (x.numel() > 32768)
  for (int64_t ch = 0; ch < g.C; ++ch) {
    double mu, var;
    if (training) {
      double s = 0;
      for (int64_t n = 0; n < g.N; ++n) {
        const T* p = px + (n * g.C + ch) * g.S;
        for (int64_t i = 0; i < g.S; ++i) s += p[i];
      }
      mu = s / M;
      double ss = 0;  // two-pass variance: no cancellation
      for (int64_t n = 0; n < g.N; ++n) {
        const T* p = px + (n * g.C + ch) * g.S;
        for (int64_t i = 0; i < g.S; ++i) ss += (p[i] - mu) * (p[i] - mu);
      }
      var = ss / M;
      prm[ch] = static_cast<T>((1 - momentum) * prm[ch] + momentum * mu);
      prv[ch] = static_cast<T>((1 - momentum) * prv[ch] + momentum * var * M / (M - 1));
    } else {
      mu = prm[ch];
      var = prv[ch];
    }
    const double inv = 1.0 / std::sqrt(var + eps);
    pmean[ch] = mu;
    pinv[ch] = inv;
    // y = x · a + b'  with a = inv · w, b' = b − μ · a, in double and rounded once: in
    // float32 the rounded a and b' and the cancellation of x · a against b' (|μ| ≫ σ)
    // cost up to a few ulps of y.
    const double a = inv * pw[ch];
    const double shift = pb[ch] - mu * a;
    for (int64_t n = 0; n < g.N; ++n) {
      const T* p = px + (n * g.C + ch) * g.S;
      T* q = py + (n * g.C + ch) * g.S;
      for (int64_t i = 0; i < g.S; ++i) q[i] = static_cast<T>(p[i] * a + shift);
    }
  }
  c.saved.push_back(mean);
  c.saved.push_back(invstd);
  return y;
}

template <class T>
std::vector<Tensor> bn_backward(const BackwardContext& c, const BnGeometry& g, bool training) {
  const Tensor& x = c.in(0);
  const T* px = x.data<T>();
  const T* pw = c.in(1).data<T>();
  const T* pgy = c.grad_output.data<T>();
  const double* pmean = c.saved.at(0).data<double>();
  const double* pinv = c.saved.at(1).data<double>();
  const bool want_x = c.needs_grad[0], want_w = c.needs_grad[1], want_b = c.needs_grad[2];
  Tensor gx, gw, gb;
  if (want_x) gx = Tensor::empty(x.shape(), x.dtype());
  if (want_w) gw = Tensor::empty({g.C}, x.dtype());
  if (want_b) gb = Tensor::empty({g.C}, x.dtype());
  T* pgx = want_x ? gx.data<T>() : nullptr;
  T* pgw = want_w ? gw.data<T>() : nullptr;
  T* pgb = want_b ? gb.data<T>() : nullptr;
  const double M = static_cast<double>(g.M());

#pragma omp parallel for num_threads(num_threads()) if (x.numel() > 32768)
  for (int64_t ch = 0; ch < g.C; ++ch) {
    const double mu = pmean[ch], inv = pinv[ch];
    // Σ dy and Σ dy · x̂ over the channel, x̂ = (x − μ) · inv
    double sum_dy = 0, sum_dy_xhat = 0;
    for (int64_t n = 0; n < g.N; ++n) {
      const T* p = px + (n * g.C + ch) * g.S;
      const T* d = pgy + (n * g.C + ch) * g.S;
      for (int64_t i = 0; i < g.S; ++i) {
        sum_dy += d[i];
        sum_dy_xhat += d[i] * (p[i] - mu) * inv;
      }
    }
    if (pgw) pgw[ch] = static_cast<T>(sum_dy_xhat);
    if (pgb) pgb[ch] = static_cast<T>(sum_dy);
    if (!pgx) continue;
    const double scale = inv * pw[ch];
    for (int64_t n = 0; n < g.N; ++n) {
      const T* p = px + (n * g.C + ch) * g.S;
      const T* d = pgy + (n * g.C + ch) * g.S;
      T* q = pgx + (n * g.C + ch) * g.S;
      if (training) {
        // dx = w·inv · (dy − mean(dy) − x̂ · mean(dy · x̂))
        const double mdy = sum_dy / M, mdyx = sum_dy_xhat / M;
        for (int64_t i = 0; i < g.S; ++i)
          q[i] = static_cast<T>(scale * (d[i] - mdy - (p[i] - mu) * inv * mdyx));
      } else {
        for (int64_t i = 0; i < g.S; ++i) q[i] = static_cast<T>(scale * d[i]);
      }
    }
  }
  return {gx, gw, gb, Tensor(), Tensor()};
}

}  // namespace

WEFT_REGISTER_OP(batch_norm) {
  OpDef d;
  d.name = "batch_norm";
  d.doc = "batch normalisation over axis 1 (PyTorch semantics; attrs training, momentum, eps; "
          "updates the running statistics in place when training)";
  d.num_inputs = 5;
  d.forward = [](const ForwardContext& c) {
    const bool training = c.attrs.get_bool("training", false);
    const BnGeometry g = bn_geometry(c.inputs, training);
    return dispatch_float(c.in(0).dtype(), "batch_norm",
                          [&]<class T>() { return bn_forward<T>(c, g, training); });
  };
  d.backward = [](const BackwardContext& c) {
    const bool training = c.attrs.get_bool("training", false);
    const BnGeometry g = bn_geometry(c.inputs, false);
    return dispatch_float(c.in(0).dtype(), "batch_norm",
                          [&]<class T>() { return bn_backward<T>(c, g, training); });
  };
  return d;
}

namespace ops {
Tensor batch_norm(const Tensor& x, const Tensor& weight, const Tensor& bias,
                  Tensor running_mean, Tensor running_var, bool training, double momentum,
                  double eps) {
  if (!x.defined()) fail("batch_norm: x is undefined");
  // Undefined weight/bias act as 1 and 0; undefined running statistics (allowed only in
  // training, like track_running_stats=False) are scratch tensors nobody reads.
  const int64_t C = x.dim() >= 2 ? x.size(1) : 1;
  const DType dt = x.dtype() == DType::I64 ? DType::F32 : x.dtype();
  if (!training && (!running_mean.defined() || !running_var.defined()))
    fail("batch_norm: eval mode needs running_mean and running_var; x ", describe(x));
  Attrs attrs{{"training", training}, {"momentum", momentum}, {"eps", eps}};
  return apply("batch_norm",
               {x, weight.defined() ? weight : Tensor::ones({C}, dt),
                bias.defined() ? bias : Tensor::zeros({C}, dt),
                running_mean.defined() ? running_mean : Tensor::zeros({C}, dt),
                running_var.defined() ? running_var : Tensor::ones({C}, dt)},
               attrs);
}
}  // namespace ops

}  // namespace weft
