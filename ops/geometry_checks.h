#pragma once
// Shape checks shared by the geometry ops; each error names the op and the shapes.
#include "graph/tensor.h"

namespace weft::geometry_checks {

// t must be [d0, d1, ...] where -1 means "any".
inline void expect_shape(const char* op, const char* what, const Tensor& t, const Shape& want) {
  bool ok = t.dim() == static_cast<int64_t>(want.size());
  for (size_t i = 0; ok && i < want.size(); ++i) ok = want[i] < 0 || t.shape()[i] == want[i];
  if (!ok) {
    std::string w = "[";
    for (size_t i = 0; i < want.size(); ++i)
      w += (i ? ", " : "") + (want[i] < 0 ? std::string("*") : std::to_string(want[i]));
    fail(op, ": ", what, " must be ", w, "], got ", shape_str(t.shape()));
  }
}

inline void expect_same_float_dtype(const char* op, const std::vector<const Tensor*>& ts) {
  for (const Tensor* t : ts)
    if (t->dtype() != ts[0]->dtype() || t->dtype() == DType::I64)
      fail(op, ": float inputs must share one float dtype, got ", describe(*ts[0]), " and ",
           describe(*t));
}

// index int64 [V, n] with entries in [0, count); weights [V, n].
inline void expect_index(const char* op, const Tensor& index, const Tensor& weights, int64_t rows,
                         int64_t count) {
  if (index.dtype() != DType::I64) fail(op, ": index must be int64, got ", describe(index));
  expect_shape(op, "index", index, {rows, -1});
  expect_shape(op, "weights", weights, index.shape());
  const int64_t* p = index.data<int64_t>();
  for (int64_t i = 0, n = index.numel(); i < n; ++i)
    if (p[i] < 0 || p[i] >= count)
      fail(op, ": index ", p[i], " at entry ", i, " is out of range [0, ", count, ")");
}

}  // namespace weft::geometry_checks
