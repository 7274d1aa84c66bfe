// matmul and linear on Eigen's GEMM, summed in depth blocks (ops/depth_blocked_gemm.h).
// Tensors are mapped in place as row-major matrices (no copies); transposes are expressed
// through the maps, so a backward costs two GEMMs.
#include <Eigen/Core>
#include <vector>

#include "ops/depth_blocked_gemm.h"
#include "ops/ops.h"

namespace weft {
namespace {

template <class T>
using RowMat = Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
template <class T>
using CMap = Eigen::Map<const RowMat<T>>;
template <class T>
using MMap = Eigen::Map<RowMat<T>>;

// C[n,m] = op(A)·op(B) where op(A) is [n,k] and op(B) is [k,m]; A is stored [k,n] when
// ta, B is stored [m,k] when tb.
template <class T>
void gemm(const T* a, bool ta, const T* b, bool tb, T* c, int64_t n, int64_t k, int64_t m) {
  MMap<T> C(c, n, m);
  if (!ta && !tb)
    gemm_in_depth_blocks(C, CMap<T>(a, n, k), CMap<T>(b, k, m), false);
  else if (!ta && tb)
    gemm_in_depth_blocks(C, CMap<T>(a, n, k), CMap<T>(b, m, k).transpose(), false);
  else if (ta && !tb)
    gemm_in_depth_blocks(C, CMap<T>(a, k, n).transpose(), CMap<T>(b, k, m), false);
  else
    gemm_in_depth_blocks(C, CMap<T>(a, k, n).transpose(), CMap<T>(b, m, k).transpose(), false);
}

// Many small products are faster split over threads one matrix each than with Eigen
// threading inside every tiny GEMM (Eigen runs single-threaded inside a parallel region).
constexpr int64_t kSmallGemmFlops = 32 * 32 * 32;

template <class T>
void batched_gemm(int64_t batch, const T* a, int64_t a_step, bool ta, const T* b, int64_t b_step,
                  bool tb, T* c, int64_t n, int64_t k, int64_t m) {
  const bool split = batch > 1 && n * k * m < kSmallGemmFlops;
#pragma omp parallel for if (split && batch * n * k * m > (1 << 15))
  for (int64_t i = 0; i < batch; ++i)
    gemm(a + i * a_step, ta, b + i * b_step, tb, c + i * n * m, n, k, m);
}

enum class MatmulKind { Plain, Batched, BatchedShared };

struct MatmulPlan {
  MatmulKind kind = MatmulKind::Plain;
  int64_t batch = 1, n = 0, k = 0, m = 0;
  Shape out_shape;
};

MatmulPlan plan_matmul(const Tensor& a, const Tensor& b) {
  if (a.dtype() != b.dtype())
    fail("matmul: dtype mismatch: ", describe(a), " vs ", describe(b));
  if (a.dtype() != DType::F32 && a.dtype() != DType::F64)
    fail("matmul: expected float32 or float64, got ", describe(a), " and ", describe(b));
  const Shape &sa = a.shape(), &sb = b.shape();
  auto bad = [&](const char* why) {
    fail("matmul: cannot multiply ", shape_str(sa), " by ", shape_str(sb), ": ", why);
  };
  MatmulPlan p;
  if (sa.size() == 2 && sb.size() == 2) {
    p.kind = MatmulKind::Plain;
    p.n = sa[0], p.k = sa[1], p.m = sb[1];
    if (sb[0] != p.k) bad("inner sizes differ");
    p.out_shape = {p.n, p.m};
  } else if (sa.size() == 3 && sb.size() == 3) {
    p.kind = MatmulKind::Batched;
    p.batch = sa[0], p.n = sa[1], p.k = sa[2], p.m = sb[2];
    if (sb[0] != p.batch) bad("batch sizes differ");
    if (sb[1] != p.k) bad("inner sizes differ");
    p.out_shape = {p.batch, p.n, p.m};
  } else if (sa.size() == 3 && sb.size() == 2) {
    // [b,n,k]@[k,m] is one [b·n,k]@[k,m] GEMM on the same memory.
    p.kind = MatmulKind::BatchedShared;
    p.batch = sa[0], p.n = sa[1], p.k = sa[2], p.m = sb[1];
    if (sb[0] != p.k) bad("inner sizes differ");
    p.out_shape = {p.batch, p.n, p.m};
  } else {
    bad("supported are [n,k]@[k,m], [b,n,k]@[b,k,m] and [b,n,k]@[k,m]");
  }
  return p;
}

struct LinearPlan {
  int64_t rows = 0, in = 0, out = 0;
  Shape out_shape;
};

LinearPlan plan_linear(const std::vector<Tensor>& inputs) {
  if (inputs.size() != 2 && inputs.size() != 3)
    fail("linear: expected inputs x, w and optionally b, got ", inputs.size(), " inputs");
  const Tensor &x = inputs[0], &w = inputs[1];
  if (x.dtype() != DType::F32 && x.dtype() != DType::F64)
    fail("linear: expected float32 or float64, got x ", describe(x));
  if (w.dtype() != x.dtype())
    fail("linear: dtype mismatch: x ", describe(x), " vs w ", describe(w));
  if (x.dim() < 1 || w.dim() != 2 || w.shape()[1] != x.shape().back())
    fail("linear: x ", shape_str(x.shape()), " needs weight [out, ", x.dim() < 1 ? 0 : x.shape().back(),
         "], got w ", shape_str(w.shape()));
  LinearPlan p;
  p.in = w.shape()[1];
  p.out = w.shape()[0];
  p.rows = x.numel() / p.in;
  p.out_shape = x.shape();
  p.out_shape.back() = p.out;
  if (inputs.size() == 3) {
    const Tensor& b = inputs[2];
    if (b.dtype() != x.dtype())
      fail("linear: dtype mismatch: x ", describe(x), " vs b ", describe(b));
    if (b.shape() != Shape{p.out})
      fail("linear: bias ", shape_str(b.shape()), " should be [", p.out, "] for w ",
           shape_str(w.shape()));
  }
  return p;
}

}  // namespace

WEFT_REGISTER_OP(matmul) {
  OpDef d;
  d.name = "matmul";
  d.doc = "matrix product [n,k]@[k,m], [b,n,k]@[b,k,m], [b,n,k]@[k,m] (Eigen GEMM)";
  d.num_inputs = 2;
  d.forward = [](const ForwardContext& c) {
    const Tensor &a = c.in(0), &b = c.in(1);
    const MatmulPlan p = plan_matmul(a, b);
    Tensor out = Tensor::empty(p.out_shape, a.dtype());
    dispatch_float(a.dtype(), "matmul", [&]<class T>() {
      const T* pa = a.data<T>();
      const T* pb = b.data<T>();
      T* po = out.data<T>();
      switch (p.kind) {
        case MatmulKind::Plain: gemm(pa, false, pb, false, po, p.n, p.k, p.m); break;
        case MatmulKind::BatchedShared:
          gemm(pa, false, pb, false, po, p.batch * p.n, p.k, p.m);
          break;
        case MatmulKind::Batched:
          batched_gemm(p.batch, pa, p.n * p.k, false, pb, p.k * p.m, false, po, p.n, p.k, p.m);
          break;
      }
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor &a = c.in(0), &b = c.in(1), &g = c.grad_output;
    const MatmulPlan p = plan_matmul(a, b);
    Tensor ga, gb;
    if (c.needs_grad[0]) ga = Tensor::empty(a.shape(), a.dtype());
    if (c.needs_grad[1]) gb = Tensor::empty(b.shape(), b.dtype());
    dispatch_float(a.dtype(), "matmul", [&]<class T>() {
      const T* pa = a.data<T>();
      const T* pb = b.data<T>();
      const T* pg = g.data<T>();
      if (p.kind == MatmulKind::Batched) {
        // dA_i = G_i B_iᵀ, dB_i = A_iᵀ G_i
        if (ga.defined())
          batched_gemm(p.batch, pg, p.n * p.m, false, pb, p.k * p.m, true, ga.data<T>(), p.n,
                       p.m, p.k);
        if (gb.defined())
          batched_gemm(p.batch, pa, p.n * p.k, true, pg, p.n * p.m, false, gb.data<T>(), p.k,
                       p.n, p.m);
      } else {
        const int64_t rows = p.batch * p.n;  // the shared-B case folds the batch into rows
        if (ga.defined()) gemm(pg, false, pb, true, ga.data<T>(), rows, p.m, p.k);
        if (gb.defined()) gemm(pa, true, pg, false, gb.data<T>(), p.k, rows, p.m);
      }
    });
    return {ga, gb};
  };
  return d;
}

WEFT_REGISTER_OP(linear) {
  OpDef d;
  d.name = "linear";
  d.doc = "x [.., in] · wᵀ [out, in] + b [out] (b optional: 2 or 3 inputs)";
  d.num_inputs = -1;
  d.forward = [](const ForwardContext& c) {
    const LinearPlan p = plan_linear(c.inputs);
    const Tensor &x = c.in(0), &w = c.in(1);
    Tensor out = Tensor::empty(p.out_shape, x.dtype());
    dispatch_float(x.dtype(), "linear", [&]<class T>() {
      MMap<T> Y(out.data<T>(), p.rows, p.out);
      gemm_in_depth_blocks(Y, CMap<T>(x.data<T>(), p.rows, p.in),
                           CMap<T>(w.data<T>(), p.out, p.in).transpose(), false);
      if (c.inputs.size() == 3)
        Y.rowwise() += Eigen::Map<const Eigen::Matrix<T, 1, Eigen::Dynamic>>(c.in(2).data<T>(), p.out);
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const LinearPlan p = plan_linear(c.inputs);
    const Tensor &x = c.in(0), &w = c.in(1), &g = c.grad_output;
    std::vector<Tensor> grads(c.inputs.size());
    dispatch_float(x.dtype(), "linear", [&]<class T>() {
      const T* pg = g.data<T>();
      if (c.needs_grad[0]) {  // dX = G W
        grads[0] = Tensor::empty(x.shape(), x.dtype());
        gemm(pg, false, w.data<T>(), false, grads[0].data<T>(), p.rows, p.out, p.in);
      }
      if (c.needs_grad[1]) {  // dW = Gᵀ X
        grads[1] = Tensor::empty(w.shape(), w.dtype());
        gemm(pg, true, x.data<T>(), false, grads[1].data<T>(), p.out, p.rows, p.in);
      }
      if (c.inputs.size() == 3 && c.needs_grad[2]) {  // db = column sums of G
        grads[2] = Tensor::empty({p.out}, x.dtype());
        Eigen::Map<Eigen::Matrix<T, 1, Eigen::Dynamic>>(grads[2].data<T>(), p.out) =
            CMap<T>(pg, p.rows, p.out).colwise().sum();
      }
    });
    return grads;
  };
  return d;
}

namespace ops {
Tensor matmul(const Tensor& a, const Tensor& b) { return apply("matmul", {a, b}); }
Tensor linear(const Tensor& x, const Tensor& w, const Tensor& b) {
  if (b.defined()) return apply("linear", {x, w, b});
  return apply("linear", {x, w});
}
}  // namespace ops

}  // namespace weft
