// Integer indexing: index_select, gather and scatter_add (PyTorch semantics, any axis).
// Every index is checked against its axis before any element is read or written, so a
// bad index is an Error, never an out-of-bounds access.
#include <cstring>
#include <vector>

#include "ops/ops.h"

namespace weft {
namespace {

void check_index_tensor(const char* op, const Tensor& index, const Tensor& x) {
  if (index.dtype() != DType::I64)
    fail(op, ": index must be int64, got ", describe(index), " (input ", describe(x), ")");
}

void check_float(const char* op, const Tensor& x) {
  if (x.dtype() != DType::F32 && x.dtype() != DType::F64)
    fail(op, ": expected float32 or float64, got ", describe(x));
}

// Every index value must lie in [0, n) for axis `axis` of x.
void check_index_range(const char* op, const Tensor& index, int axis, const Tensor& x) {
  const int64_t n = x.shape()[axis];
  const int64_t* pi = index.data<int64_t>();
  for (int64_t i = 0; i < index.numel(); ++i)
    if (pi[i] < 0 || pi[i] >= n)
      fail(op, ": index ", pi[i], " (at flat position ", i, " of index ",
           shape_str(index.shape()), ") is out of range for axis ", axis, " of shape ",
           shape_str(x.shape()));
}

// --- index_select: x viewed as [outer, n, inner]; output [outer, len(index), inner] ---
struct SelectPlan {
  int axis = 0;
  int64_t outer = 1, n = 0, inner = 1, k = 0;
  Shape out_shape;
};

SelectPlan plan_select(const Tensor& x, const Tensor& index, const Attrs& attrs) {
  check_float("index_select", x);
  check_index_tensor("index_select", index, x);
  if (index.dim() != 1)
    fail("index_select: index must be 1-D, got ", shape_str(index.shape()), " for input ",
         shape_str(x.shape()));
  SelectPlan p;
  const Shape& s = x.shape();
  p.axis = normalise_axis(attrs.get_int("axis"), s.size(), "index_select", s);
  check_index_range("index_select", index, p.axis, x);
  for (int d = 0; d < p.axis; ++d) p.outer *= s[d];
  for (size_t d = p.axis + 1; d < s.size(); ++d) p.inner *= s[d];
  p.n = s[p.axis];
  p.k = index.numel();
  p.out_shape = s;
  p.out_shape[p.axis] = p.k;
  return p;
}

// --- gather / scatter_add: walk the index array; for each position p the "x side"
// offset replaces p's coordinate on `axis` by index[p], the "dense side" offset is p
// itself in a possibly larger array (src of scatter_add) ---
struct WalkPlan {
  int axis = 0;
  Shape walk_shape;                 // the index's shape
  std::vector<int64_t> x_strides;   // of the indexed tensor
  std::vector<int64_t> d_strides;   // of the dense tensor (out of gather, src of scatter)
};

// Calls f(x_offset, dense_offset) for every index position.
template <class F>
void walk_index(const WalkPlan& p, const int64_t* index, F&& f) {
  const size_t rank = p.walk_shape.size();
  const int64_t n = shape_numel(p.walk_shape);
  std::vector<int64_t> idx(rank, 0);
  int64_t xo = 0, dof = 0;  // offsets excluding the axis coordinate
  for (int64_t i = 0; i < n; ++i) {
    f(xo + index[i] * p.x_strides[p.axis], dof);
    for (size_t d = rank; d-- > 0;) {
      const int64_t xs = static_cast<int>(d) == p.axis ? 0 : p.x_strides[d];
      if (++idx[d] < p.walk_shape[d]) {
        xo += xs;
        dof += p.d_strides[d];
        break;
      }
      xo -= xs * (p.walk_shape[d] - 1);
      dof -= p.d_strides[d] * (p.walk_shape[d] - 1);
      idx[d] = 0;
    }
  }
}

// PyTorch's rule: index has x's rank, fits inside x on every other axis and inside the
// dense tensor (src) on every axis; every value is a valid position on `axis`.
WalkPlan plan_walk(const char* op, const Tensor& x, const Tensor& index, const Shape& dense,
                   const Attrs& attrs) {
  check_float(op, x);
  check_index_tensor(op, index, x);
  const Shape& s = x.shape();
  const Shape& is = index.shape();
  WalkPlan p;
  p.axis = normalise_axis(attrs.get_int("axis"), s.size(), op, s);
  if (is.size() != s.size())
    fail(op, ": index ", shape_str(is), " must have the rank of input ", shape_str(s));
  for (size_t d = 0; d < s.size(); ++d) {
    if (static_cast<int>(d) != p.axis && is[d] > s[d])
      fail(op, ": index ", shape_str(is), " is larger than input ", shape_str(s), " on axis ",
           d);
    if (is[d] > dense[d])
      fail(op, ": index ", shape_str(is), " is larger than src ", shape_str(dense), " on axis ",
           d);
  }
  check_index_range(op, index, p.axis, x);
  p.walk_shape = is;
  p.x_strides = contiguous_strides(s);
  p.d_strides = contiguous_strides(dense);
  return p;
}

}  // namespace

WEFT_REGISTER_OP(index_select) {
  OpDef d;
  d.name = "index_select";
  d.doc = "entries index[i] along an axis (attr 'axis'; index int64 1-D, input 1)";
  d.num_inputs = 2;
  d.forward = [](const ForwardContext& c) {
    const Tensor &x = c.in(0), &index = c.in(1);
    const SelectPlan p = plan_select(x, index, c.attrs);
    Tensor out = Tensor::empty(p.out_shape, x.dtype());
    const int64_t* pi = index.data<int64_t>();
    dispatch_float(x.dtype(), "index_select", [&]<class T>() {
      const T* px = x.data<T>();
      T* po = out.data<T>();
#pragma omp parallel for if (out.numel() > (1 << 15) && p.outer > 1)
      for (int64_t o = 0; o < p.outer; ++o)
        for (int64_t j = 0; j < p.k; ++j)
          std::memcpy(po + (o * p.k + j) * p.inner, px + (o * p.n + pi[j]) * p.inner,
                      sizeof(T) * static_cast<size_t>(p.inner));
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor &x = c.in(0), &index = c.in(1);
    const SelectPlan p = plan_select(x, index, c.attrs);
    Tensor gx = Tensor::zeros(x.shape(), x.dtype());
    const int64_t* pi = index.data<int64_t>();
    dispatch_float(x.dtype(), "index_select", [&]<class T>() {
      const T* pg = c.grad_output.data<T>();
      T* po = gx.data<T>();
      // Repeated indices accumulate; parallel over `outer` only, where rows are disjoint.
#pragma omp parallel for if (gx.numel() > (1 << 15) && p.outer > 1)
      for (int64_t o = 0; o < p.outer; ++o)
        for (int64_t j = 0; j < p.k; ++j) {
          T* dst = po + (o * p.n + pi[j]) * p.inner;
          const T* src = pg + (o * p.k + j) * p.inner;
          for (int64_t i = 0; i < p.inner; ++i) dst[i] += src[i];
        }
    });
    return {gx, Tensor()};
  };
  return d;
}

WEFT_REGISTER_OP(gather) {
  OpDef d;
  d.name = "gather";
  d.doc = "out[p] = x[p with axis coordinate index[p]] (attr 'axis'; index int64, x's rank)";
  d.num_inputs = 2;
  d.forward = [](const ForwardContext& c) {
    const Tensor &x = c.in(0), &index = c.in(1);
    const WalkPlan p = plan_walk("gather", x, index, index.shape(), c.attrs);
    Tensor out = Tensor::empty(index.shape(), x.dtype());
    dispatch_float(x.dtype(), "gather", [&]<class T>() {
      const T* px = x.data<T>();
      T* po = out.data<T>();
      walk_index(p, index.data<int64_t>(), [&](int64_t xo, int64_t o) { po[o] = px[xo]; });
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor &x = c.in(0), &index = c.in(1);
    const WalkPlan p = plan_walk("gather", x, index, index.shape(), c.attrs);
    Tensor gx = Tensor::zeros(x.shape(), x.dtype());
    dispatch_float(x.dtype(), "gather", [&]<class T>() {
      const T* pg = c.grad_output.data<T>();
      T* po = gx.data<T>();
      walk_index(p, index.data<int64_t>(), [&](int64_t xo, int64_t o) { po[xo] += pg[o]; });
    });
    return {gx, Tensor()};
  };
  return d;
}

WEFT_REGISTER_OP(scatter_add) {
  OpDef d;
  d.name = "scatter_add";
  d.doc = "x, then out[p with axis coordinate index[p]] += src[p] (attr 'axis'; inputs x, "
          "index, src)";
  d.num_inputs = 3;
  d.forward = [](const ForwardContext& c) {
    const Tensor &x = c.in(0), &index = c.in(1), &src = c.in(2);
    if (src.dtype() != x.dtype() || src.dim() != x.dim())
      fail("scatter_add: src ", describe(src), " does not match input ", describe(x));
    const WalkPlan p = plan_walk("scatter_add", x, index, src.shape(), c.attrs);
    Tensor out = x.clone();
    dispatch_float(x.dtype(), "scatter_add", [&]<class T>() {
      const T* ps = src.data<T>();
      T* po = out.data<T>();
      walk_index(p, index.data<int64_t>(), [&](int64_t xo, int64_t so) { po[xo] += ps[so]; });
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor &x = c.in(0), &index = c.in(1), &src = c.in(2);
    Tensor gsrc;
    if (c.needs_grad[2]) {
      // d out[index[p]] / d src[p] = 1: src's gradient gathers g; positions of src
      // outside the index's extent were never added, so their gradient is 0.
      const WalkPlan p = plan_walk("scatter_add", x, index, src.shape(), c.attrs);
      gsrc = Tensor::zeros(src.shape(), src.dtype());
      dispatch_float(x.dtype(), "scatter_add", [&]<class T>() {
        const T* pg = c.grad_output.data<T>();
        T* ps = gsrc.data<T>();
        walk_index(p, index.data<int64_t>(), [&](int64_t xo, int64_t so) { ps[so] = pg[xo]; });
      });
    }
    return {c.needs_grad[0] ? c.grad_output : Tensor(), Tensor(), gsrc};
  };
  return d;
}

namespace ops {
Tensor index_select(const Tensor& x, int64_t axis, const Tensor& index) {
  return apply("index_select", {x, index}, {{"axis", axis}});
}
Tensor gather(const Tensor& x, int64_t axis, const Tensor& index) {
  return apply("gather", {x, index}, {{"axis", axis}});
}
Tensor scatter_add(const Tensor& x, int64_t axis, const Tensor& index, const Tensor& src) {
  return apply("scatter_add", {x, index, src}, {{"axis", axis}});
}
}  // namespace ops

}  // namespace weft
