#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "graph/error.h"

namespace weft {

// Element types. F32 and F64 are the numeric types every op supports; I64 holds
// indices and counters (e.g. batch norm's num_batches_tracked) and is not
// differentiable.
enum class DType : uint8_t { F32, F64, I64 };

inline const char* dtype_name(DType d) {
  switch (d) {
    case DType::F32: return "float32";
    case DType::F64: return "float64";
    case DType::I64: return "int64";
  }
  return "?";
}

inline size_t dtype_size(DType d) { return d == DType::F32 ? 4 : 8; }

template <class T> constexpr DType dtype_of();
template <> constexpr DType dtype_of<float>() { return DType::F32; }
template <> constexpr DType dtype_of<double>() { return DType::F64; }
template <> constexpr DType dtype_of<int64_t>() { return DType::I64; }

// Calls fn.template operator()<T>() with T = float or double for the tensor's dtype.
// `what` names the op in the error for other dtypes.
template <class Fn>
decltype(auto) dispatch_float(DType d, const char* what, Fn&& fn) {
  switch (d) {
    case DType::F32: return fn.template operator()<float>();
    case DType::F64: return fn.template operator()<double>();
    default: fail(what, ": expected float32 or float64, got ", dtype_name(d));
  }
}

}  // namespace weft
