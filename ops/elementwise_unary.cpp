// Elementwise unary ops. Each is a forward functor and a backward in terms of other
// ops (run without recording).
#include <cmath>

#include "ops/ops.h"

namespace weft {
namespace {

template <class F>
Tensor unary_forward(const char* op, const Tensor& x, F f) {
  Tensor out = Tensor::empty(x.shape(), x.dtype());
  dispatch_float(x.dtype(), op, [&]<class T>() {
    const T* px = x.data<T>();
    T* po = out.data<T>();
    const int64_t n = x.numel();
#pragma omp parallel for simd if (n > (1 << 15))
    for (int64_t i = 0; i < n; ++i) po[i] = f(px[i]);
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

namespace ops {
Tensor neg(const Tensor& x) { return apply("neg", {x}); }
}  // namespace ops

}  // namespace weft
