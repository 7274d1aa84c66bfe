#pragma once
// Broadcasting helpers shared by the elementwise ops.
#include <cstdint>
#include <vector>

#include "graph/tensor.h"

namespace weft {

// Strides (in elements) of `in` viewed with `out`'s shape: 0 on broadcast axes.
std::vector<int64_t> broadcast_strides(const Shape& in, const Shape& out);

// Sums `g` (shaped like a broadcast result) down to `shape`: the gradient of a
// broadcast input. Returns g itself when the shapes already match.
Tensor sum_to_shape(const Tensor& g, const Shape& shape);

// Calls f(out_index, a_index, b_index) for every element of `out` (row-major), with the
// flat indices of the broadcast inputs a and b.
template <class F>
void for_each_broadcast(const Shape& out, const Shape& a, const Shape& b, F&& f) {
  const int64_t n = shape_numel(out);
  if (a == out && b == out) {
    for (int64_t i = 0; i < n; ++i) f(i, i, i);
    return;
  }
  const std::vector<int64_t> sa = broadcast_strides(a, out), sb = broadcast_strides(b, out);
  const size_t rank = out.size();
  std::vector<int64_t> idx(rank, 0);
  int64_t ia = 0, ib = 0;
  for (int64_t i = 0; i < n; ++i) {
    f(i, ia, ib);
    for (size_t d = rank; d-- > 0;) {
      if (++idx[d] < out[d]) {
        ia += sa[d];
        ib += sb[d];
        break;
      }
      ia -= sa[d] * (out[d] - 1);
      ib -= sb[d] * (out[d] - 1);
      idx[d] = 0;
    }
  }
}

}  // namespace weft
