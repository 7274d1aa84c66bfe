// Reductions over a set of axes: sum, mean, max and the L2 norm.
//
// When the reduced axes are one contiguous run (the common case: all axes, the last
// axes, the batch axis) the input is seen as [outer, reduced, inner] and reduced with
// plain loops; other axis sets walk the input once with broadcast strides. Sums are
// accumulated in double so float32 keeps its precision over long reductions.
#include <cmath>
#include <vector>

#include "ops/broadcast.h"
#include "ops/ops.h"

namespace weft {
namespace {

constexpr int64_t kParallelThreshold = 1 << 15;

struct ReducePlan {
  Shape keep_shape;  // the input shape with reduced axes set to 1
  Shape out_shape;   // keep_shape, or without the reduced axes when !keepdim
  int64_t count = 1;  // elements reduced into each output
  bool blocked = false;  // reduced axes form one run: [outer, count, inner]
  int64_t outer = 1, inner = 1;
};

ReducePlan plan_reduce(const char* op, const Tensor& x, const Attrs& attrs) {
  if (x.dtype() != DType::F32 && x.dtype() != DType::F64)
    fail(op, ": expected float32 or float64, got ", describe(x));
  const Shape& s = x.shape();
  const std::vector<int> axes = normalise_axes(attrs.get_ints("axes"), s.size(), op, s);
  const bool keepdim = attrs.get_bool("keepdim");
  ReducePlan p;
  p.keep_shape = s;
  std::vector<bool> reduced(s.size(), false);
  for (int a : axes) {
    reduced[a] = true;
    p.keep_shape[a] = 1;
    p.count *= s[a];
  }
  for (size_t i = 0; i < s.size(); ++i)
    if (!reduced[i] || keepdim) p.out_shape.push_back(p.keep_shape[i]);
  // Blocked layout: size-1 axes do not break a run, so ignore them when looking for one.
  int first = -1, last = -1;
  for (int a : axes)
    if (s[a] != 1) {
      if (first < 0) first = a;
      last = a;
    }
  p.blocked = true;
  if (first >= 0)
    for (int i = first; i <= last; ++i)
      if (!reduced[i] && s[i] != 1) p.blocked = false;
  if (p.blocked) {
    for (int i = 0; i < first; ++i) p.outer *= s[i];
    for (size_t i = (first < 0 ? 0 : last + 1); i < s.size(); ++i)
      p.inner *= s[i];
    if (first < 0) p.inner = x.numel();  // nothing of size > 1 is reduced
  }
  return p;
}

// The input's axes with size-1 axes dropped and neighbours of the same kind (reduced or
// kept) merged: [N,C,H,W] over axes 0, 2, 3 becomes [N, C, H·W] with flags r, k, r.
void compact_axes(const Shape& in, const Shape& keep, std::vector<int64_t>& sizes,
                  std::vector<bool>& reduced) {
  for (size_t i = 0; i < in.size(); ++i) {
    if (in[i] == 1) continue;
    const bool r = keep[i] == 1;
    if (!sizes.empty() && reduced.back() == r)
      sizes.back() *= in[i];
    else {
      sizes.push_back(in[i]);
      reduced.push_back(r);
    }
  }
}

// out[j] = Σ over the reduced elements of f(x) for output j, in double.
template <class T, class F>
std::vector<double> reduce_sum(const Tensor& x, const ReducePlan& p, F f) {
  const T* px = x.data<T>();
  const int64_t n_out = shape_numel(p.out_shape);
  std::vector<double> acc(static_cast<size_t>(n_out), 0.0);
  if (p.blocked) {
    const int64_t count = p.count, inner = p.inner, outer = p.outer;
    if (inner == 1 && outer == 1) {
      // One long reduction: split it over threads.
      double s = 0;
#pragma omp parallel for reduction(+ : s) if (count > kParallelThreshold)
      for (int64_t r = 0; r < count; ++r) s += f(px[r]);
      acc[0] = s;
    } else if (inner == 1) {
#pragma omp parallel for if (x.numel() > kParallelThreshold)
      for (int64_t o = 0; o < outer; ++o) {
        double s = 0;
        const T* row = px + o * count;
        for (int64_t r = 0; r < count; ++r) s += f(row[r]);
        acc[o] = s;
      }
    } else {
#pragma omp parallel for if (x.numel() > kParallelThreshold && outer > 1)
      for (int64_t o = 0; o < outer; ++o) {
        double* a = acc.data() + o * inner;
        for (int64_t r = 0; r < count; ++r) {
          const T* row = px + (o * count + r) * inner;
          for (int64_t i = 0; i < inner; ++i) a[i] += f(row[i]);
        }
      }
    }
  } else {
    // Several runs of reduced axes (e.g. axes 0, 2, 3 of NCHW): reduce one run per
    // pass, innermost first, each pass a blocked reduction of the previous result.
    std::vector<int64_t> sizes;
    std::vector<bool> reduced;
    compact_axes(x.shape(), p.keep_shape, sizes, reduced);
    std::vector<double> cur;
    bool first = true;
    for (size_t r = sizes.size(); r-- > 0;) {
      if (!reduced[r]) continue;
      int64_t outer = 1, inner = 1;
      for (size_t i = 0; i < r; ++i) outer *= sizes[i];
      for (size_t i = r + 1; i < sizes.size(); ++i) inner *= sizes[i];
      const int64_t count = sizes[r];
      std::vector<double> next(static_cast<size_t>(outer * inner), 0.0);
#pragma omp parallel for if (outer * count * inner > kParallelThreshold && outer > 1)
      for (int64_t o = 0; o < outer; ++o) {
        double* a = next.data() + o * inner;
        for (int64_t c = 0; c < count; ++c) {
          const int64_t base = (o * count + c) * inner;
          if (first)
            for (int64_t i = 0; i < inner; ++i) a[i] += f(px[base + i]);
          else
            for (int64_t i = 0; i < inner; ++i) a[i] += cur[base + i];
        }
      }
      cur = std::move(next);
      first = false;
      sizes.erase(sizes.begin() + static_cast<std::ptrdiff_t>(r));
    }
    acc = std::move(cur);
  }
  return acc;
}

template <class T>
Tensor from_acc(const std::vector<double>& acc, const Shape& shape, double factor) {
  Tensor out = Tensor::empty(shape, dtype_of<T>());
  T* po = out.data<T>();
  for (size_t i = 0; i < acc.size(); ++i) po[i] = static_cast<T>(acc[i] * factor);
  return out;
}

// Repeats g (shaped like the output) over the reduced axes, times `factor`.
Tensor expand_grad(const Tensor& g, const ReducePlan& p, const Shape& in_shape, double factor) {
  Tensor out = Tensor::empty(in_shape, g.dtype());
  dispatch_float(g.dtype(), "reduce backward", [&]<class T>() {
    const T* pg = g.data<T>();
    T* po = out.data<T>();
    const T f = static_cast<T>(factor);
    if (p.blocked) {
      const int64_t count = p.count, inner = p.inner;
#pragma omp parallel for if (out.numel() > kParallelThreshold && p.outer > 1)
      for (int64_t o = 0; o < p.outer; ++o)
        for (int64_t r = 0; r < count; ++r) {
          T* row = po + (o * count + r) * inner;
          const T* src = pg + o * inner;
          for (int64_t i = 0; i < inner; ++i) row[i] = src[i] * f;
        }
    } else {
      for_each_broadcast(in_shape, p.keep_shape, p.keep_shape,
                         [&](int64_t i, int64_t io, int64_t) { po[i] = pg[io] * f; });
    }
  });
  return out;
}

OpDef reduce_op(const char* name, const char* doc) {
  OpDef d;
  d.name = name;
  d.doc = doc;
  d.num_inputs = 1;
  return d;
}

}  // namespace

WEFT_REGISTER_OP(sum) {
  OpDef d = reduce_op("sum", "sum over axes (attrs 'axes', empty = all; 'keepdim')");
  d.forward = [](const ForwardContext& c) {
    const ReducePlan p = plan_reduce("sum", c.in(0), c.attrs);
    return dispatch_float(c.in(0).dtype(), "sum", [&]<class T>() {
      return from_acc<T>(reduce_sum<T>(c.in(0), p, [](T v) { return double(v); }), p.out_shape,
                         1.0);
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const ReducePlan p = plan_reduce("sum", c.in(0), c.attrs);
    return {expand_grad(c.grad_output, p, c.in(0).shape(), 1.0)};
  };
  return d;
}

WEFT_REGISTER_OP(mean) {
  OpDef d = reduce_op("mean", "mean over axes (attrs 'axes', empty = all; 'keepdim')");
  d.forward = [](const ForwardContext& c) {
    const ReducePlan p = plan_reduce("mean", c.in(0), c.attrs);
    return dispatch_float(c.in(0).dtype(), "mean", [&]<class T>() {
      return from_acc<T>(reduce_sum<T>(c.in(0), p, [](T v) { return double(v); }), p.out_shape,
                         1.0 / static_cast<double>(p.count));
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const ReducePlan p = plan_reduce("mean", c.in(0), c.attrs);
    return {expand_grad(c.grad_output, p, c.in(0).shape(), 1.0 / static_cast<double>(p.count))};
  };
  return d;
}

WEFT_REGISTER_OP(norm) {
  OpDef d = reduce_op("norm", "L2 norm over axes (attrs 'axes', empty = all; 'keepdim')");
  d.saves_output = true;  // ∂‖x‖/∂x = x / ‖x‖
  d.forward = [](const ForwardContext& c) {
    const ReducePlan p = plan_reduce("norm", c.in(0), c.attrs);
    return dispatch_float(c.in(0).dtype(), "norm", [&]<class T>() {
      std::vector<double> acc =
          reduce_sum<T>(c.in(0), p, [](T v) { return double(v) * double(v); });
      for (double& a : acc) a = std::sqrt(a);
      return from_acc<T>(acc, p.out_shape, 1.0);
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& x = c.in(0);
    const ReducePlan p = plan_reduce("norm", x, c.attrs);
    // g / ‖x‖ per output (0 where the norm is 0: the zero subgradient), spread, times x.
    Tensor ratio = Tensor::empty(c.output.shape(), x.dtype());
    dispatch_float(x.dtype(), "norm", [&]<class T>() {
      const T* pg = c.grad_output.data<T>();
      const T* py = c.output.data<T>();
      T* pr = ratio.data<T>();
      for (int64_t i = 0; i < ratio.numel(); ++i) pr[i] = py[i] > T(0) ? pg[i] / py[i] : T(0);
    });
    Tensor g = expand_grad(ratio, p, x.shape(), 1.0);
    dispatch_float(x.dtype(), "norm", [&]<class T>() {
      T* pg = g.data<T>();
      const T* px = x.data<T>();
      const int64_t n = g.numel();
#pragma omp parallel for simd if (n > kParallelThreshold)
      for (int64_t i = 0; i < n; ++i) pg[i] *= px[i];
    });
    return {g};
  };
  return d;
}

WEFT_REGISTER_OP(max) {
  OpDef d = reduce_op("max",
                      "max over axes (attrs 'axes', empty = all; 'keepdim'); gradient to the "
                      "first maximal element");
  d.forward = [](const ForwardContext& c) {
    const Tensor& x = c.in(0);
    const ReducePlan p = plan_reduce("max", x, c.attrs);
    const int64_t n_out = shape_numel(p.out_shape);
    Tensor out = Tensor::empty(p.out_shape, x.dtype());
    // Flat input index of each output's maximum, for the backward.
    Tensor argmax = Tensor::empty({n_out}, DType::I64);
    int64_t* pa = argmax.data<int64_t>();
    dispatch_float(x.dtype(), "max", [&]<class T>() {
      const T* px = x.data<T>();
      T* po = out.data<T>();
      if (p.blocked) {
        const int64_t count = p.count, inner = p.inner;
#pragma omp parallel for if (x.numel() > kParallelThreshold && p.outer > 1)
        for (int64_t o = 0; o < p.outer; ++o)
          for (int64_t i = 0; i < inner; ++i) {
            int64_t best = o * count * inner + i;
            for (int64_t r = 1; r < count; ++r) {
              const int64_t k = (o * count + r) * inner + i;
              if (px[k] > px[best]) best = k;  // strict: ties keep the first
            }
            po[o * inner + i] = px[best];
            pa[o * inner + i] = best;
          }
      } else {
        std::vector<bool> seen(static_cast<size_t>(n_out), false);
        for_each_broadcast(x.shape(), p.keep_shape, p.keep_shape,
                           [&](int64_t i, int64_t io, int64_t) {
                             if (!seen[io] || px[i] > po[io]) {
                               po[io] = px[i];
                               pa[io] = i;
                               seen[io] = true;
                             }
                           });
      }
    });
    c.saved.push_back(argmax);
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Tensor& x = c.in(0);
    Tensor gx = Tensor::zeros(x.shape(), x.dtype());
    const int64_t* pa = c.saved.at(0).data<int64_t>();
    dispatch_float(x.dtype(), "max", [&]<class T>() {
      const T* pg = c.grad_output.data<T>();
      T* po = gx.data<T>();
      for (int64_t j = 0; j < c.grad_output.numel(); ++j) po[pa[j]] += pg[j];
    });
    return {gx};
  };
  return d;
}

namespace ops {
namespace {
Attrs reduce_attrs(const std::vector<int64_t>& axes, bool keepdim) {
  return {{"axes", axes}, {"keepdim", keepdim}};
}
}  // namespace
Tensor sum(const Tensor& x, const std::vector<int64_t>& axes, bool keepdim) {
  return apply("sum", {x}, reduce_attrs(axes, keepdim));
}
Tensor mean(const Tensor& x, const std::vector<int64_t>& axes, bool keepdim) {
  return apply("mean", {x}, reduce_attrs(axes, keepdim));
}
Tensor max(const Tensor& x, const std::vector<int64_t>& axes, bool keepdim) {
  return apply("max", {x}, reduce_attrs(axes, keepdim));
}
Tensor norm(const Tensor& x, const std::vector<int64_t>& axes, bool keepdim) {
  return apply("norm", {x}, reduce_attrs(axes, keepdim));
}
}  // namespace ops

}  // namespace weft
