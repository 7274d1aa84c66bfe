#pragma once
// Helpers for writing gradient-check cases.
#include "graph/gradcheck.h"
#include "graph/tensor.h"

namespace weft::testing {

// Random float64 tensor with entries uniform in [lo, hi].
inline Tensor uniform64(Generator& g, const Shape& s, double lo = -1.0, double hi = 1.0) {
  return Tensor::rand(s, g, DType::F64, lo, hi);
}

// Uniform in [lo, hi] with random sign: magnitudes kept away from 0 (for kinks at 0).
inline Tensor away_from_zero64(Generator& g, const Shape& s, double lo = 0.2, double hi = 1.0) {
  Tensor t = Tensor::rand(s, g, DType::F64, lo, hi);
  double* p = t.data<double>();
  for (int64_t i = 0; i < t.numel(); ++i)
    if (g.uniform() < 0.5) p[i] = -p[i];
  return t;
}

// A case whose inputs are float64 uniform tensors of the given shapes.
inline GradcheckCase uniform_case(const std::string& op, const std::string& name,
                                  std::vector<Shape> shapes, Attrs attrs = {},
                                  double lo = -1.0, double hi = 1.0) {
  GradcheckCase c;
  c.op = op;
  c.name = name;
  c.attrs = std::move(attrs);
  c.make_inputs = [shapes, lo, hi](Generator& g) {
    std::vector<Tensor> v;
    for (const Shape& s : shapes) v.push_back(uniform64(g, s, lo, hi));
    return v;
  };
  return c;
}

}  // namespace weft::testing
