// Regression losses, each the mean over all elements of a pointwise penalty of
// d = pred − target. Forward and backward are single fused passes; the sum is kept in
// double so float32 losses over large batches do not drift.
#include <cmath>
#include <vector>

#include "ops/ops.h"

namespace weft {
namespace {

constexpr int64_t kParallelThreshold = 1 << 15;

void check_pair(const char* op, const Tensor& pred, const Tensor& target) {
  if (pred.dtype() != target.dtype())
    fail(op, ": dtype mismatch: pred ", describe(pred), " vs target ", describe(target));
  if (pred.dtype() != DType::F32 && pred.dtype() != DType::F64)
    fail(op, ": expected float32 or float64, got pred ", describe(pred));
  if (pred.shape() != target.shape())
    fail(op, ": shapes must match exactly: pred ", shape_str(pred.shape()), " vs target ",
         shape_str(target.shape()));
}

// mean over i of penalty(pred_i − target_i), as a scalar tensor.
template <class P>
Tensor loss_forward(const char* op, const Tensor& pred, const Tensor& target, P penalty) {
  check_pair(op, pred, target);
  const int64_t n = pred.numel();
  return dispatch_float(pred.dtype(), op, [&]<class T>() {
    const T* pp = pred.data<T>();
    const T* pt = target.data<T>();
    double s = 0;
#pragma omp parallel for reduction(+ : s) if (n > kParallelThreshold)
    for (int64_t i = 0; i < n; ++i) s += penalty(static_cast<double>(pp[i]) - pt[i]);
    return Tensor::scalar(s / static_cast<double>(n), pred.dtype());
  });
}

// Gradients to pred (+g·penalty'(d)/n) and target (the negative) for the scalar g.
template <class D>
std::vector<Tensor> loss_backward(const BackwardContext& c, D dpenalty) {
  const Tensor &pred = c.in(0), &target = c.in(1);
  const int64_t n = pred.numel();
  Tensor gp = Tensor::empty(pred.shape(), pred.dtype());
  dispatch_float(pred.dtype(), "loss backward", [&]<class T>() {
    const T* pp = pred.data<T>();
    const T* pt = target.data<T>();
    T* pg = gp.data<T>();
    const T scale = static_cast<T>(c.grad_output.item() / static_cast<double>(n));
#pragma omp parallel for simd if (n > kParallelThreshold)
    for (int64_t i = 0; i < n; ++i) pg[i] = scale * dpenalty(pp[i] - pt[i]);
  });
  Tensor gt;
  if (c.needs_grad[1]) gt = ops::neg(gp);
  return {c.needs_grad[0] ? gp : Tensor(), gt};
}

OpDef loss_op(const char* name, const char* doc) {
  OpDef d;
  d.name = name;
  d.doc = doc;
  d.num_inputs = 2;
  return d;
}

double huber_beta(const Attrs& attrs, const Tensor& pred) {
  const double beta = attrs.get_float("beta", 1.0);
  if (!(beta >= 0))
    fail("smooth_l1_loss: beta must be >= 0, got ", beta, " for pred ", describe(pred));
  return beta;
}

}  // namespace

WEFT_REGISTER_OP(mse_loss) {
  OpDef d = loss_op("mse_loss", "mean of (pred - target)^2");
  d.forward = [](const ForwardContext& c) {
    return loss_forward("mse_loss", c.in(0), c.in(1), [](double v) { return v * v; });
  };
  d.backward = [](const BackwardContext& c) {
    return loss_backward(c, [](auto v) { return decltype(v)(2) * v; });
  };
  return d;
}

WEFT_REGISTER_OP(l1_loss) {
  OpDef d = loss_op("l1_loss", "mean of |pred - target| (gradient 0 where equal)");
  d.forward = [](const ForwardContext& c) {
    return loss_forward("l1_loss", c.in(0), c.in(1), [](double v) { return std::abs(v); });
  };
  d.backward = [](const BackwardContext& c) {
    return loss_backward(c, [](auto v) {
      using T = decltype(v);
      return v > T(0) ? T(1) : (v < T(0) ? T(-1) : T(0));
    });
  };
  return d;
}

WEFT_REGISTER_OP(smooth_l1_loss) {
  OpDef d = loss_op("smooth_l1_loss",
                    "mean Huber penalty: 0.5 d^2 / beta where |d| < beta, else |d| - 0.5 beta "
                    "(attr 'beta'; beta 0 is l1)");
  d.forward = [](const ForwardContext& c) {
    const double beta = huber_beta(c.attrs, c.in(0));
    return loss_forward("smooth_l1_loss", c.in(0), c.in(1), [beta](double v) {
      const double a = std::abs(v);
      return a < beta ? 0.5 * v * v / beta : a - 0.5 * beta;
    });
  };
  d.backward = [](const BackwardContext& c) {
    const double beta = huber_beta(c.attrs, c.in(0));
    return loss_backward(c, [beta](auto v) {
      using T = decltype(v);
      if (std::abs(v) < T(beta)) return v / T(beta);
      return v > T(0) ? T(1) : (v < T(0) ? T(-1) : T(0));
    });
  };
  return d;
}

namespace ops {
Tensor mse_loss(const Tensor& pred, const Tensor& target) {
  return apply("mse_loss", {pred, target});
}
Tensor l1_loss(const Tensor& pred, const Tensor& target) {
  return apply("l1_loss", {pred, target});
}
Tensor smooth_l1_loss(const Tensor& pred, const Tensor& target, double beta) {
  return apply("smooth_l1_loss", {pred, target}, {{"beta", beta}});
}
}  // namespace ops

}  // namespace weft
