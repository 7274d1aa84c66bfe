// Shape ops: reshape and contiguous slices alias the input's storage; permute, transpose,
// strided slices, concat and stack copy. Copies walk the input with explicit strides, so
// one kernel serves permute, transpose and slice in both directions (forward gathers,
// backward scatters).
#include <cstring>
#include <numeric>
#include <vector>

#include "ops/ops.h"

namespace weft {
namespace {

// Calls f(flat_out_index, in_offset) for every element of a row-major array of `shape`,
// where in_offset = Σ idx[d]·strides[d]. The last axis is the inner loop.
template <class F>
void for_each_strided(const Shape& shape, const std::vector<int64_t>& strides, F&& f) {
  const int64_t n = shape_numel(shape);
  if (n == 0) return;
  const size_t rank = shape.size();
  if (rank == 0) {
    f(int64_t{0}, int64_t{0});
    return;
  }
  const int64_t last = shape[rank - 1], last_stride = strides[rank - 1];
  std::vector<int64_t> idx(rank, 0);
  int64_t off = 0;
  for (int64_t i = 0; i < n; i += last) {
    for (int64_t j = 0; j < last; ++j) f(i + j, off + j * last_stride);
    for (size_t d = rank - 1; d-- > 0;) {
      if (++idx[d] < shape[d]) {
        off += strides[d];
        break;
      }
      off -= strides[d] * (shape[d] - 1);
      idx[d] = 0;
    }
  }
}

// Splits a strided walk over the first axis so large copies run on all threads: calls
// f(flat offset of block i, strided offset of block i, shape[1:], strides[1:]) for each
// index i of axis 0 (or once for the whole array when it is small). Blocks touch
// disjoint elements, so they may run concurrently.
template <class F>
void for_each_outer_block(const Shape& shape, const std::vector<int64_t>& strides, F&& f) {
  const int64_t n = shape_numel(shape);
  if (shape.size() < 2 || shape[0] < 2 || n < (1 << 16)) {
    f(int64_t{0}, int64_t{0}, shape, strides);
    return;
  }
  const Shape sub(shape.begin() + 1, shape.end());
  const std::vector<int64_t> sub_strides(strides.begin() + 1, strides.end());
  const int64_t block = shape_numel(sub);
#pragma omp parallel for
  for (int64_t i = 0; i < shape[0]; ++i) f(i * block, i * strides[0], sub, sub_strides);
}

// out (contiguous, `shape`) = in read at base + strided offsets.
Tensor gather_strided(const char* op, const Tensor& in, const Shape& shape,
                      const std::vector<int64_t>& strides, int64_t base) {
  Tensor out = Tensor::empty(shape, in.dtype());
  auto run = [&]<class T>() {
    const T* pi = in.data<T>() + base;
    T* po = out.data<T>();
    for_each_outer_block(shape, strides, [&](int64_t out0, int64_t in0, const Shape& sub,
                                             const std::vector<int64_t>& sub_strides) {
      for_each_strided(sub, sub_strides,
                       [&](int64_t i, int64_t off) { po[out0 + i] = pi[in0 + off]; });
    });
  };
  if (in.dtype() == DType::I64)
    run.template operator()<int64_t>();
  else
    dispatch_float(in.dtype(), op, run);
  return out;
}

// The reverse: a zero tensor of `target` with g (contiguous, `shape`) written at base +
// strided offsets. Each target element receives at most one value (the maps are
// injective), so plain assignment is enough.
Tensor scatter_strided(const char* op, const Tensor& g, const Shape& target, const Shape& shape,
                       const std::vector<int64_t>& strides, int64_t base) {
  Tensor out = Tensor::zeros(target, g.dtype());
  dispatch_float(g.dtype(), op, [&]<class T>() {
    const T* pg = g.data<T>();
    T* po = out.data<T>() + base;
    for_each_outer_block(shape, strides, [&](int64_t out0, int64_t in0, const Shape& sub,
                                             const std::vector<int64_t>& sub_strides) {
      for_each_strided(sub, sub_strides,
                       [&](int64_t i, int64_t off) { po[in0 + off] = pg[out0 + i]; });
    });
  });
  return out;
}

std::vector<int> check_permutation(const char* op, const Tensor& x,
                                   const std::vector<int64_t>& dims) {
  const Shape& s = x.shape();
  if (dims.size() != s.size())
    fail(op, ": ", dims.size(), " dims ", shape_str(dims), " for shape ", shape_str(s));
  std::vector<int> perm;
  std::vector<bool> used(s.size(), false);
  for (int64_t d : dims) {
    const int a = normalise_axis(d, s.size(), op, s);
    if (used[a]) fail(op, ": dims ", shape_str(dims), " repeat an axis of shape ", shape_str(s));
    used[a] = true;
    perm.push_back(a);
  }
  return perm;
}

// Shape and input strides of x permuted by perm.
void permuted(const Tensor& x, const std::vector<int>& perm, Shape& shape,
              std::vector<int64_t>& strides) {
  const std::vector<int64_t> st = contiguous_strides(x.shape());
  shape.clear();
  strides.clear();
  for (int a : perm) {
    shape.push_back(x.shape()[a]);
    strides.push_back(st[a]);
  }
}

Tensor permute_forward(const char* op, const Tensor& x, const std::vector<int>& perm) {
  Shape shape;
  std::vector<int64_t> strides;
  permuted(x, perm, shape, strides);
  return gather_strided(op, x, shape, strides, 0);
}

Tensor permute_backward(const char* op, const Tensor& x, const Tensor& g,
                        const std::vector<int>& perm) {
  Shape shape;
  std::vector<int64_t> strides;
  permuted(x, perm, shape, strides);
  return scatter_strided(op, g, x.shape(), shape, strides, 0);
}

std::vector<int> transpose_perm(const Tensor& x, const Attrs& attrs) {
  const Shape& s = x.shape();
  const int a = normalise_axis(attrs.get_int("dim0"), s.size(), "transpose", s);
  const int b = normalise_axis(attrs.get_int("dim1"), s.size(), "transpose", s);
  std::vector<int> perm(s.size());
  std::iota(perm.begin(), perm.end(), 0);
  std::swap(perm[a], perm[b]);
  return perm;
}

struct SlicePlan {
  int axis = 0;
  int64_t start = 0, end = 0, step = 1, len = 0;
  Shape shape;                   // of the result
  std::vector<int64_t> strides;  // into the input
  int64_t base = 0;              // input offset of the first element
  bool aliases = false;          // a contiguous block: share storage
};

SlicePlan plan_slice(const Tensor& x, const Attrs& attrs) {
  const Shape& s = x.shape();
  SlicePlan p;
  p.axis = normalise_axis(attrs.get_int("axis"), s.size(), "slice", s);
  const int64_t n = s[p.axis];
  p.start = attrs.get_int("start");
  p.end = attrs.get_int("end");
  p.step = attrs.get_int("step", 1);
  // Negative bounds count from the end, like Python; anything else outside the axis
  // is an error rather than silently clamped.
  if (p.start < 0) p.start += n;
  if (p.end < 0) p.end += n;
  if (p.step < 1) fail("slice: step ", p.step, " must be >= 1 (shape ", shape_str(s), ")");
  if (p.start < 0 || p.end > n || p.start > p.end)
    fail("slice: range [", attrs.get_int("start"), ", ", attrs.get_int("end"),
         ") is out of bounds for axis ", p.axis, " of shape ", shape_str(s));
  p.len = (p.end - p.start + p.step - 1) / p.step;
  p.shape = s;
  p.shape[p.axis] = p.len;
  p.strides = contiguous_strides(s);
  p.base = p.start * p.strides[p.axis];
  p.strides[p.axis] *= p.step;
  p.aliases = p.step == 1 || p.len <= 1;
  for (int i = 0; i < p.axis; ++i)
    if (s[i] != 1) p.aliases = false;
  return p;
}

// --- concat / stack: the output is [outer, Σ lens, inner]; input i fills lens[i] rows ---
struct JoinPlan {
  Shape out_shape;
  int64_t outer = 1, inner = 1, total = 0;
  std::vector<int64_t> lens;
};

JoinPlan plan_concat(const std::vector<Tensor>& xs, const Attrs& attrs) {
  const Tensor& x0 = xs[0];
  const Shape& s0 = x0.shape();
  const int axis = normalise_axis(attrs.get_int("axis"), s0.size(), "concat", s0);
  JoinPlan p;
  for (size_t i = 0; i < xs.size(); ++i) {
    const Shape& s = xs[i].shape();
    if (xs[i].dtype() != x0.dtype())
      fail("concat: dtype mismatch: input 0 ", describe(x0), " vs input ", i, " ",
           describe(xs[i]));
    bool ok = s.size() == s0.size();
    for (size_t d = 0; ok && d < s.size(); ++d)
      if (static_cast<int>(d) != axis && s[d] != s0[d]) ok = false;
    if (!ok)
      fail("concat: along axis ", axis, " input 0 ", shape_str(s0), " and input ", i, " ",
           shape_str(s), " differ in another axis");
    p.lens.push_back(s[axis]);
    p.total += s[axis];
  }
  for (int d = 0; d < axis; ++d) p.outer *= s0[d];
  for (size_t d = axis + 1; d < s0.size(); ++d) p.inner *= s0[d];
  p.out_shape = s0;
  p.out_shape[axis] = p.total;
  return p;
}

JoinPlan plan_stack(const std::vector<Tensor>& xs, const Attrs& attrs) {
  const Tensor& x0 = xs[0];
  const Shape& s0 = x0.shape();
  const int64_t r = static_cast<int64_t>(s0.size());
  int64_t axis = attrs.get_int("axis");
  if (axis < -(r + 1) || axis > r)
    fail("stack: axis ", axis, " is out of range for inputs of shape ", shape_str(s0));
  if (axis < 0) axis += r + 1;
  JoinPlan p;
  for (size_t i = 0; i < xs.size(); ++i) {
    if (xs[i].dtype() != x0.dtype())
      fail("stack: dtype mismatch: input 0 ", describe(x0), " vs input ", i, " ",
           describe(xs[i]));
    if (xs[i].shape() != s0)
      fail("stack: input 0 ", shape_str(s0), " and input ", i, " ", shape_str(xs[i].shape()),
           " differ in shape");
    p.lens.push_back(1);
  }
  p.total = static_cast<int64_t>(xs.size());
  for (int64_t d = 0; d < axis; ++d) p.outer *= s0[d];
  for (int64_t d = axis; d < r; ++d) p.inner *= s0[d];
  p.out_shape = s0;
  p.out_shape.insert(p.out_shape.begin() + axis, p.total);
  return p;
}

Tensor join_forward(const std::vector<Tensor>& xs, const JoinPlan& p) {
  Tensor out = Tensor::empty(p.out_shape, xs[0].dtype());
  const size_t es = dtype_size(out.dtype());
  auto* po = static_cast<char*>(out.raw_data());
  int64_t offset = 0;  // rows before input i within one outer block
  for (size_t i = 0; i < xs.size(); ++i) {
    const auto* pi = static_cast<const char*>(xs[i].raw_data());
    const int64_t chunk = p.lens[i] * p.inner;
    for (int64_t o = 0; o < p.outer; ++o)
      std::memcpy(po + (o * p.total * p.inner + offset * p.inner) * es, pi + o * chunk * es,
                  static_cast<size_t>(chunk) * es);
    offset += p.lens[i];
  }
  return out;
}

std::vector<Tensor> join_backward(const BackwardContext& c, const JoinPlan& p) {
  std::vector<Tensor> grads(c.inputs.size());
  const Tensor& g = c.grad_output;
  const size_t es = dtype_size(g.dtype());
  const auto* pg = static_cast<const char*>(g.raw_data());
  int64_t offset = 0;
  for (size_t i = 0; i < c.inputs.size(); ++i) {
    const int64_t chunk = p.lens[i] * p.inner;
    if (c.needs_grad[i]) {
      Tensor gi = Tensor::empty(c.inputs[i].shape(), g.dtype());
      auto* pi = static_cast<char*>(gi.raw_data());
      for (int64_t o = 0; o < p.outer; ++o)
        std::memcpy(pi + o * chunk * es, pg + (o * p.total * p.inner + offset * p.inner) * es,
                    static_cast<size_t>(chunk) * es);
      grads[i] = gi;
    }
    offset += p.lens[i];
  }
  return grads;
}

}  // namespace

WEFT_REGISTER_OP(reshape) {
  OpDef d;
  d.name = "reshape";
  d.doc = "same elements in a new shape (attr 'shape', one -1 inferred); shares storage";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& x = c.in(0);
    return x.view(infer_reshape(c.attrs.get_ints("shape"), x.numel(), "reshape", x.shape()));
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {c.grad_output.view(c.in(0).shape())};
  };
  return d;
}

WEFT_REGISTER_OP(permute) {
  OpDef d;
  d.name = "permute";
  d.doc = "reorders axes: output axis i is input axis dims[i] (attr 'dims'); copies";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& x = c.in(0);
    return permute_forward("permute", x, check_permutation("permute", x, c.attrs.get_ints("dims")));
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& x = c.in(0);
    return {permute_backward("permute", x, c.grad_output,
                             check_permutation("permute", x, c.attrs.get_ints("dims")))};
  };
  return d;
}

WEFT_REGISTER_OP(transpose) {
  OpDef d;
  d.name = "transpose";
  d.doc = "swaps two axes (attrs 'dim0', 'dim1'); copies";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    return permute_forward("transpose", c.in(0), transpose_perm(c.in(0), c.attrs));
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return {permute_backward("transpose", c.in(0), c.grad_output,
                             transpose_perm(c.in(0), c.attrs))};
  };
  return d;
}

WEFT_REGISTER_OP(slice) {
  OpDef d;
  d.name = "slice";
  d.doc = "[start, end) with step along an axis (attrs 'axis', 'start', 'end', 'step'); shares "
          "storage when the block is contiguous, else copies";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& c) {
    const Tensor& x = c.in(0);
    const SlicePlan p = plan_slice(x, c.attrs);
    if (p.aliases) return x.slice_view(p.axis, p.start, p.start + p.len);
    return gather_strided("slice", x, p.shape, p.strides, p.base);
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const SlicePlan p = plan_slice(c.in(0), c.attrs);
    return {scatter_strided("slice", c.grad_output, c.in(0).shape(), p.shape, p.strides, p.base)};
  };
  return d;
}

WEFT_REGISTER_OP(concat) {
  OpDef d;
  d.name = "concat";
  d.doc = "joins tensors along an existing axis (attr 'axis'); variadic";
  d.num_inputs = -1;
  d.forward = [](const ForwardContext& c) {
    return join_forward(c.inputs, plan_concat(c.inputs, c.attrs));
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return join_backward(c, plan_concat(c.inputs, c.attrs));
  };
  return d;
}

WEFT_REGISTER_OP(stack) {
  OpDef d;
  d.name = "stack";
  d.doc = "joins same-shaped tensors along a new axis (attr 'axis'); variadic";
  d.num_inputs = -1;
  d.forward = [](const ForwardContext& c) {
    return join_forward(c.inputs, plan_stack(c.inputs, c.attrs));
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    return join_backward(c, plan_stack(c.inputs, c.attrs));
  };
  return d;
}

WEFT_REGISTER_OP(stop_gradient) {
  OpDef d;
  d.name = "stop_gradient";
  d.doc = "the input's values as an alias through which no gradient flows";
  d.num_inputs = 1;
  d.differentiable = false;
  d.forward = [](const ForwardContext& c) { return c.in(0).detach(); };
  return d;
}

namespace ops {
Tensor reshape(const Tensor& x, const Shape& shape) {
  return apply("reshape", {x}, {{"shape", shape}});
}
Tensor permute(const Tensor& x, const std::vector<int64_t>& dims) {
  return apply("permute", {x}, {{"dims", dims}});
}
Tensor transpose(const Tensor& x, int64_t dim0, int64_t dim1) {
  return apply("transpose", {x}, {{"dim0", dim0}, {"dim1", dim1}});
}
Tensor slice(const Tensor& x, int64_t axis, int64_t start, int64_t end, int64_t step) {
  return apply("slice", {x}, {{"axis", axis}, {"start", start}, {"end", end}, {"step", step}});
}
Tensor concat(const std::vector<Tensor>& xs, int64_t axis) {
  if (xs.empty()) fail("concat: no inputs");
  return apply("concat", xs, {{"axis", axis}});
}
Tensor stack(const std::vector<Tensor>& xs, int64_t axis) {
  if (xs.empty()) fail("stack: no inputs");
  return apply("stack", xs, {{"axis", axis}});
}
Tensor stop_gradient(const Tensor& x) { return apply("stop_gradient", {x}); }
}  // namespace ops

}  // namespace weft
