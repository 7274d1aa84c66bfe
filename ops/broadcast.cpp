#include "ops/broadcast.h"

namespace weft {

std::vector<int64_t> broadcast_strides(const Shape& in, const Shape& out) {
  const std::vector<int64_t> st = contiguous_strides(in);
  std::vector<int64_t> res(out.size(), 0);
  const size_t lead = out.size() - in.size();
  for (size_t i = 0; i < in.size(); ++i) res[lead + i] = in[i] == 1 ? 0 : st[i];
  return res;
}

Tensor sum_to_shape(const Tensor& g, const Shape& shape) {
  if (g.shape() == shape) return g;
  Tensor out = Tensor::zeros(shape, g.dtype());
  dispatch_float(g.dtype(), "sum_to_shape", [&]<class T>() {
    const T* pg = g.data<T>();
    T* po = out.data<T>();
    for_each_broadcast(g.shape(), shape, shape,
                       [&](int64_t i, int64_t io, int64_t) { po[io] += pg[i]; });
  });
  return out;
}

}  // namespace weft
