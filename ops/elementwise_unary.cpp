// Elementwise unary ops (and `where`, which selects elementwise). Each forward is one
// functor over the elements; each backward is one fused pass g·f'(x) (or g·f'(y) from the
// saved output where that is cheaper), so the activations of a network cost one sweep.
#include <cmath>
#include <cstdint>
#include <vector>

#include "ops/broadcast.h"
#include "ops/ops.h"

namespace weft {
namespace {

// Below this many elements a thread team costs more than it saves.
constexpr int64_t kParallelThreshold = 1 << 15;

void check_float(const char* op, const Tensor& x) {
  if (x.dtype() != DType::F32 && x.dtype() != DType::F64)
    fail(op, ": expected float32 or float64, got ", describe(x));
}

template <class F>
Tensor unary_forward(const char* op, const Tensor& x, F f) {
  check_float(op, x);
  Tensor out = Tensor::empty(x.shape(), x.dtype());
  dispatch_float(x.dtype(), op, [&]<class T>() {
    const T* px = x.data<T>();
    T* po = out.data<T>();
    const int64_t n = x.numel();
#pragma omp parallel for simd if (n > kParallelThreshold)
    for (int64_t i = 0; i < n; ++i) po[i] = f(px[i]);
  });
  return out;
}

// g ⊙ f(v) for the gradient g and a same-shaped tensor v (the input or the output).
template <class F>
Tensor unary_backward(const char* op, const Tensor& g, const Tensor& v, F f) {
  if (g.shape() != v.shape() || g.dtype() != v.dtype())
    fail(op, " backward: gradient ", describe(g), " vs ", describe(v));
  Tensor out = Tensor::empty(v.shape(), v.dtype());
  dispatch_float(v.dtype(), op, [&]<class T>() {
    const T* pg = g.data<T>();
    const T* pv = v.data<T>();
    T* po = out.data<T>();
    const int64_t n = v.numel();
#pragma omp parallel for simd if (n > kParallelThreshold)
    for (int64_t i = 0; i < n; ++i) po[i] = pg[i] * f(pv[i]);
  });
  return out;
}

OpDef unary_op(const char* name, const char* doc) {
  OpDef d;
  d.name = name;
  d.doc = doc;
  d.num_inputs = 1;
  return d;
}

template <class T>
T stable_sigmoid(T v) {
  // Split by sign so exp never overflows.
  if (v >= T(0)) return T(1) / (T(1) + std::exp(-v));
  const T e = std::exp(v);
  return e / (T(1) + e);
}

}  // namespace

WEFT_REGISTER_OP(neg) {
  OpDef d = unary_op("neg", "-x");
  d.forward = [](const ForwardContext& c) {
    return unary_forward("neg", c.in(0), [](auto v) { return -v; });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {ops::neg(c.grad_output)};
  };
  return d;
}

WEFT_REGISTER_OP(exp) {
  OpDef d = unary_op("exp", "e^x");
  d.saves_output = true;  // d/dx e^x = e^x
  d.forward = [](const ForwardContext& c) {
    return unary_forward("exp", c.in(0), [](auto v) { return std::exp(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("exp", c.grad_output, c.output, [](auto y) { return y; })};
  };
  return d;
}

WEFT_REGISTER_OP(log) {
  OpDef d = unary_op("log", "natural logarithm");
  d.forward = [](const ForwardContext& c) {
    return unary_forward("log", c.in(0), [](auto v) { return std::log(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("log", c.grad_output, c.in(0),
                           [](auto x) { return decltype(x)(1) / x; })};
  };
  return d;
}

WEFT_REGISTER_OP(sqrt) {
  OpDef d = unary_op("sqrt", "square root");
  d.saves_output = true;  // d/dx √x = 1 / (2√x)
  d.forward = [](const ForwardContext& c) {
    return unary_forward("sqrt", c.in(0), [](auto v) { return std::sqrt(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("sqrt", c.grad_output, c.output,
                           [](auto y) { return decltype(y)(0.5) / y; })};
  };
  return d;
}

WEFT_REGISTER_OP(pow) {
  OpDef d = unary_op("pow", "x^p for a constant exponent p (attr 'exponent')");
  d.forward = [](const ForwardContext& c) {
    const double p = c.attrs.get_float("exponent");
    return unary_forward("pow", c.in(0), [p](auto v) {
      using T = decltype(v);
      return static_cast<T>(std::pow(v, static_cast<T>(p)));
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const double p = c.attrs.get_float("exponent");
    return {unary_backward("pow", c.grad_output, c.in(0), [p](auto x) {
      using T = decltype(x);
      if (p == 0) return T(0);  // constant: avoid 0·x^-1 = NaN at x = 0
      return static_cast<T>(p * std::pow(x, static_cast<T>(p - 1)));
    })};
  };
  return d;
}

WEFT_REGISTER_OP(abs) {
  OpDef d = unary_op("abs", "|x| (gradient 0 at 0)");
  d.forward = [](const ForwardContext& c) {
    return unary_forward("abs", c.in(0), [](auto v) { return std::abs(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("abs", c.grad_output, c.in(0), [](auto x) {
      using T = decltype(x);
      return x > T(0) ? T(1) : (x < T(0) ? T(-1) : T(0));
    })};
  };
  return d;
}

WEFT_REGISTER_OP(sin) {
  OpDef d = unary_op("sin", "sine (radians)");
  d.forward = [](const ForwardContext& c) {
    return unary_forward("sin", c.in(0), [](auto v) { return std::sin(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("sin", c.grad_output, c.in(0), [](auto x) { return std::cos(x); })};
  };
  return d;
}

WEFT_REGISTER_OP(cos) {
  OpDef d = unary_op("cos", "cosine (radians)");
  d.forward = [](const ForwardContext& c) {
    return unary_forward("cos", c.in(0), [](auto v) { return std::cos(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("cos", c.grad_output, c.in(0), [](auto x) { return -std::sin(x); })};
  };
  return d;
}

WEFT_REGISTER_OP(clamp) {
  OpDef d = unary_op("clamp", "min(max(x, lo), hi) (attrs 'lo', 'hi'); gradient where lo < x < hi");
  d.forward = [](const ForwardContext& c) {
    const double lo = c.attrs.get_float("lo"), hi = c.attrs.get_float("hi");
    if (!(lo <= hi)) fail("clamp: lo ", lo, " > hi ", hi, " for ", describe(c.in(0)));
    return unary_forward("clamp", c.in(0), [lo, hi](auto v) {
      using T = decltype(v);
      return v < T(lo) ? T(lo) : (v > T(hi) ? T(hi) : v);
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const double lo = c.attrs.get_float("lo"), hi = c.attrs.get_float("hi");
    return {unary_backward("clamp", c.grad_output, c.in(0), [lo, hi](auto x) {
      using T = decltype(x);
      return x > T(lo) && x < T(hi) ? T(1) : T(0);
    })};
  };
  return d;
}

WEFT_REGISTER_OP(relu) {
  OpDef d = unary_op("relu", "max(x, 0)");
  d.forward = [](const ForwardContext& c) {
    return unary_forward("relu", c.in(0), [](auto v) { return v > decltype(v)(0) ? v : decltype(v)(0); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("relu", c.grad_output, c.in(0),
                           [](auto x) { return x > decltype(x)(0) ? decltype(x)(1) : decltype(x)(0); })};
  };
  return d;
}

WEFT_REGISTER_OP(sigmoid) {
  OpDef d = unary_op("sigmoid", "1 / (1 + e^-x)");
  d.saves_output = true;  // σ' = σ(1 − σ)
  d.forward = [](const ForwardContext& c) {
    return unary_forward("sigmoid", c.in(0), [](auto v) { return stable_sigmoid(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("sigmoid", c.grad_output, c.output,
                           [](auto y) { return y * (decltype(y)(1) - y); })};
  };
  return d;
}

WEFT_REGISTER_OP(tanh) {
  OpDef d = unary_op("tanh", "hyperbolic tangent");
  d.saves_output = true;  // tanh' = 1 − tanh²
  d.forward = [](const ForwardContext& c) {
    return unary_forward("tanh", c.in(0), [](auto v) { return std::tanh(v); });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {unary_backward("tanh", c.grad_output, c.output,
                           [](auto y) { return decltype(y)(1) - y * y; })};
  };
  return d;
}

WEFT_REGISTER_OP(softplus) {
  OpDef d = unary_op("softplus",
                     "log(1 + e^(beta x)) / beta, x where beta x > threshold (attrs 'beta', "
                     "'threshold')");
  d.forward = [](const ForwardContext& c) {
    const double beta = c.attrs.get_float("beta", 1.0);
    const double threshold = c.attrs.get_float("threshold", 20.0);
    if (!(beta > 0)) fail("softplus: beta must be > 0, got ", beta, " for ", describe(c.in(0)));
    return unary_forward("softplus", c.in(0), [beta, threshold](auto v) {
      using T = decltype(v);
      const T bx = static_cast<T>(beta) * v;
      // Above the threshold the curve equals x to working precision (PyTorch's rule).
      if (bx > static_cast<T>(threshold)) return v;
      return std::log1p(std::exp(bx)) / static_cast<T>(beta);
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const double beta = c.attrs.get_float("beta", 1.0);
    const double threshold = c.attrs.get_float("threshold", 20.0);
    return {unary_backward("softplus", c.grad_output, c.in(0), [beta, threshold](auto x) {
      using T = decltype(x);
      const T bx = static_cast<T>(beta) * x;
      return bx > static_cast<T>(threshold) ? T(1) : stable_sigmoid(bx);
    })};
  };
  return d;
}

// --- where ---
namespace {

// Per element of the broadcast output: is cond nonzero there? cond may be any dtype.
std::vector<uint8_t> where_mask(const Tensor& cond, const Shape& out_shape) {
  std::vector<uint8_t> mask(static_cast<size_t>(shape_numel(out_shape)));
  auto fill = [&]<class C>(const C* pc) {
    for_each_broadcast(out_shape, cond.shape(), cond.shape(),
                       [&](int64_t i, int64_t ic, int64_t) { mask[i] = pc[ic] != C(0); });
  };
  if (cond.dtype() == DType::I64)
    fill(cond.data<int64_t>());
  else
    dispatch_float(cond.dtype(), "where", [&]<class C>() { fill(cond.data<C>()); });
  return mask;
}

Shape where_shape(const Tensor& cond, const Tensor& a, const Tensor& b) {
  const Shape ab = broadcast_shapes(a.shape(), b.shape(), "where");
  const Shape s = broadcast_shapes(cond.shape(), ab, "where");
  return s;
}

// The part of g (shaped like the output) where mask == keep, summed down to `shape`.
Tensor where_grad(const Tensor& g, const std::vector<uint8_t>& mask, bool keep,
                  const Shape& shape) {
  Tensor masked = Tensor::empty(g.shape(), g.dtype());
  dispatch_float(g.dtype(), "where", [&]<class T>() {
    const T* pg = g.data<T>();
    T* pm = masked.data<T>();
    const int64_t n = g.numel();
    for (int64_t i = 0; i < n; ++i) pm[i] = (mask[i] != 0) == keep ? pg[i] : T(0);
  });
  return sum_to_shape(masked, shape);
}

}  // namespace

WEFT_REGISTER_OP(where) {
  OpDef d;
  d.name = "where";
  d.doc = "cond != 0 ? a : b, the three broadcast together; no gradient to cond";
  d.num_inputs = 3;
  d.forward = [](const ForwardContext& c) {
    const Tensor &cond = c.in(0), &a = c.in(1), &b = c.in(2);
    if (a.dtype() != b.dtype())
      fail("where: dtype mismatch: a ", describe(a), " vs b ", describe(b));
    check_float("where", a);
    const Shape out_shape = where_shape(cond, a, b);
    const std::vector<uint8_t> mask = where_mask(cond, out_shape);
    Tensor out = Tensor::empty(out_shape, a.dtype());
    dispatch_float(a.dtype(), "where", [&]<class T>() {
      const T* pa = a.data<T>();
      const T* pb = b.data<T>();
      T* po = out.data<T>();
      for_each_broadcast(out_shape, a.shape(), b.shape(), [&](int64_t i, int64_t ia, int64_t ib) {
        po[i] = mask[i] ? pa[ia] : pb[ib];
      });
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor &cond = c.in(0), &a = c.in(1), &b = c.in(2);
    const std::vector<uint8_t> mask = where_mask(cond, c.grad_output.shape());
    Tensor ga, gb;
    if (c.needs_grad[1]) ga = where_grad(c.grad_output, mask, true, a.shape());
    if (c.needs_grad[2]) gb = where_grad(c.grad_output, mask, false, b.shape());
    return {Tensor(), ga, gb};
  };
  return d;
}

namespace ops {
Tensor neg(const Tensor& x) { return apply("neg", {x}); }
Tensor exp(const Tensor& x) { return apply("exp", {x}); }
Tensor log(const Tensor& x) { return apply("log", {x}); }
Tensor sqrt(const Tensor& x) { return apply("sqrt", {x}); }
Tensor pow(const Tensor& x, double exponent) {
  return apply("pow", {x}, {{"exponent", exponent}});
}
Tensor abs(const Tensor& x) { return apply("abs", {x}); }
Tensor sin(const Tensor& x) { return apply("sin", {x}); }
Tensor cos(const Tensor& x) { return apply("cos", {x}); }
Tensor clamp(const Tensor& x, double lo, double hi) {
  return apply("clamp", {x}, {{"lo", lo}, {"hi", hi}});
}
Tensor where(const Tensor& cond, const Tensor& a, const Tensor& b) {
  return apply("where", {cond, a, b});
}
Tensor relu(const Tensor& x) { return apply("relu", {x}); }
Tensor sigmoid(const Tensor& x) { return apply("sigmoid", {x}); }
Tensor tanh(const Tensor& x) { return apply("tanh", {x}); }
Tensor softplus(const Tensor& x, double beta, double threshold) {
  return apply("softplus", {x}, {{"beta", beta}, {"threshold", threshold}});
}
}  // namespace ops

}  // namespace weft
