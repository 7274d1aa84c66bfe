// Broadcasting binary arithmetic: add, sub, mul, div, and the scalar forms scale and
// add_scalar.
#include "ops/broadcast.h"
#include "ops/ops.h"

namespace weft {
namespace {

void check_same_dtype(const char* op, const Tensor& a, const Tensor& b) {
  if (a.dtype() != b.dtype())
    fail(op, ": dtype mismatch: ", describe(a), " vs ", describe(b));
}

template <class F>
Tensor binary_forward(const char* op, const Tensor& a, const Tensor& b, F f) {
  check_same_dtype(op, a, b);
  const Shape out_shape = broadcast_shapes(a.shape(), b.shape(), op);
  Tensor out = Tensor::empty(out_shape, a.dtype());
  dispatch_float(a.dtype(), op, [&]<class T>() {
    const T* pa = a.data<T>();
    const T* pb = b.data<T>();
    T* po = out.data<T>();
    const int64_t n = out.numel();
    if (a.shape() == out_shape && b.shape() == out_shape) {
#pragma omp parallel for simd if (n > (1 << 15))
      for (int64_t i = 0; i < n; ++i) po[i] = f(pa[i], pb[i]);
    } else if (a.shape() == out_shape && b.numel() == 1) {
      const T s = pb[0];
#pragma omp parallel for simd if (n > (1 << 15))
      for (int64_t i = 0; i < n; ++i) po[i] = f(pa[i], s);
    } else {
      for_each_broadcast(out_shape, a.shape(), b.shape(),
                         [&](int64_t i, int64_t ia, int64_t ib) { po[i] = f(pa[ia], pb[ib]); });
    }
  });
  return out;
}

OpDef binary_op(const char* name, const char* doc) {
  OpDef d;
  d.name = name;
  d.doc = doc;
  d.num_inputs = 2;
  return d;
}

}  // namespace

WEFT_REGISTER_OP(add) {
  OpDef d = binary_op("add", "a + b, broadcasting");
  d.forward = [](const ForwardContext& c) {
    return binary_forward("add", c.in(0), c.in(1), [](auto x, auto y) { return x + y; });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {c.needs_grad[0] ? sum_to_shape(c.grad_output, c.in(0).shape()) : Tensor(),
            c.needs_grad[1] ? sum_to_shape(c.grad_output, c.in(1).shape()) : Tensor()};
  };
  return d;
}

WEFT_REGISTER_OP(sub) {
  OpDef d = binary_op("sub", "a - b, broadcasting");
  d.forward = [](const ForwardContext& c) {
    return binary_forward("sub", c.in(0), c.in(1), [](auto x, auto y) { return x - y; });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {c.needs_grad[0] ? sum_to_shape(c.grad_output, c.in(0).shape()) : Tensor(),
            c.needs_grad[1] ? sum_to_shape(ops::neg(c.grad_output), c.in(1).shape())
                            : Tensor()};
  };
  return d;
}

WEFT_REGISTER_OP(mul) {
  OpDef d = binary_op("mul", "a * b elementwise, broadcasting");
  d.forward = [](const ForwardContext& c) {
    return binary_forward("mul", c.in(0), c.in(1), [](auto x, auto y) { return x * y; });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& g = c.grad_output;
    return {c.needs_grad[0] ? sum_to_shape(ops::mul(g, c.in(1)), c.in(0).shape()) : Tensor(),
            c.needs_grad[1] ? sum_to_shape(ops::mul(g, c.in(0)), c.in(1).shape()) : Tensor()};
  };
  return d;
}

WEFT_REGISTER_OP(div) {
  OpDef d = binary_op("div", "a / b elementwise, broadcasting");
  d.forward = [](const ForwardContext& c) {
    return binary_forward("div", c.in(0), c.in(1), [](auto x, auto y) { return x / y; });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& g = c.grad_output;
    const Tensor& a = c.in(0);
    const Tensor& b = c.in(1);
    Tensor ga, gb;
    if (c.needs_grad[0]) ga = sum_to_shape(ops::div(g, b), a.shape());
    if (c.needs_grad[1])  // d(a/b)/db = -a/b²
      gb = sum_to_shape(ops::neg(ops::div(ops::mul(g, a), ops::mul(b, b))), b.shape());
    return {ga, gb};
  };
  return d;
}

WEFT_REGISTER_OP(scale) {
  OpDef d;
  d.name = "scale";
  d.doc = "x * s for a constant s (attr 's')";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& x = c.in(0);
    return binary_forward("scale", x, Tensor::scalar(c.attrs.get_float("s"), x.dtype()),
                          [](auto a, auto s) { return a * s; });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {ops::scale(c.grad_output, c.attrs.get_float("s"))};
  };
  return d;
}

WEFT_REGISTER_OP(add_scalar) {
  OpDef d;
  d.name = "add_scalar";
  d.doc = "x + s for a constant s (attr 's')";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& x = c.in(0);
    return binary_forward("add_scalar", x, Tensor::scalar(c.attrs.get_float("s"), x.dtype()),
                          [](auto a, auto s) { return a + s; });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> { return {c.grad_output}; };
  return d;
}

namespace ops {
Tensor add(const Tensor& a, const Tensor& b) { return apply("add", {a, b}); }
Tensor sub(const Tensor& a, const Tensor& b) { return apply("sub", {a, b}); }
Tensor mul(const Tensor& a, const Tensor& b) { return apply("mul", {a, b}); }
Tensor div(const Tensor& a, const Tensor& b) { return apply("div", {a, b}); }
Tensor scale(const Tensor& x, double s) { return apply("scale", {x}, {{"s", s}}); }
Tensor add_scalar(const Tensor& x, double s) { return apply("add_scalar", {x}, {{"s", s}}); }
}  // namespace ops

}  // namespace weft
