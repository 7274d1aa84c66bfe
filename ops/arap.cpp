// The as-rigid-as-possible regulariser of embedded graphs.
#include <Eigen/Core>

#include "ops/geometry.h"
#include "ops/geometry_checks.h"
#include "ops/ops.h"

namespace weft {
namespace {

constexpr const char* kOp = "arap_energy";
template <class T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <class T>
using Mat3 = Eigen::Matrix<T, 3, 3, Eigen::RowMajor>;

void check(const std::vector<Tensor>& in) {
  using namespace geometry_checks;
  const Tensor &nodes = in[0], &rot = in[1], &trans = in[2], &edges = in[3], &w = in[4];
  expect_shape(kOp, "nodes", nodes, {-1, 3});
  const int64_t K = nodes.size(0);
  expect_shape(kOp, "rotations", rot, {-1, K, 3, 3});
  expect_shape(kOp, "translations", trans, {rot.size(0), K, 3});
  expect_same_float_dtype(kOp, {&nodes, &rot, &trans, &w});
  if (edges.dtype() != DType::I64) fail(kOp, ": edges must be int64, got ", describe(edges));
  expect_shape(kOp, "edges", edges, {-1, 2});
  expect_shape(kOp, "edge weights", w, {edges.size(0)});
  const int64_t* e = edges.data<int64_t>();
  for (int64_t i = 0; i < edges.numel(); ++i)
    if (e[i] < 0 || e[i] >= K) fail(kOp, ": edge node ", e[i], " out of range [0, ", K, ")");
}

// Calls f(b, edge, j, k, w, residual) for every frame and both directions of each edge.
template <class T, class F>
void for_each_residual(const std::vector<Tensor>& in, F&& f) {
  const T* g = in[0].data<T>();
  const T* R = in[1].data<T>();
  const T* t = in[2].data<T>();
  const int64_t* e = in[3].data<int64_t>();
  const T* w = in[4].data<T>();
  const int64_t B = in[1].size(0), K = in[0].size(0), E = in[3].size(0);
  for (int64_t b = 0; b < B; ++b)
    for (int64_t i = 0; i < E; ++i)
      for (int dir = 0; dir < 2; ++dir) {
        const int64_t j = e[2 * i + dir], k = e[2 * i + 1 - dir];
        const Eigen::Map<const Vec3<T>> gj(g + 3 * j), gk(g + 3 * k);
        const Eigen::Map<const Mat3<T>> Rj(R + 9 * (b * K + j));
        const Eigen::Map<const Vec3<T>> tj(t + 3 * (b * K + j)), tk(t + 3 * (b * K + k));
        const Vec3<T> r = Rj * (gk - gj) + gj + tj - (gk + tk);
        f(b, i, j, k, w[i], r);
      }
}

}  // namespace

WEFT_REGISTER_OP(arap_energy) {
  OpDef d;
  d.name = kOp;
  d.doc = "ARAP energy of embedded-graph edges, weighted, summed over frames";
  d.num_inputs = 5;
  d.forward = [](const ForwardContext& c) {
    check(c.inputs);
    Tensor out = Tensor::empty({}, c.in(0).dtype());
    dispatch_float(out.dtype(), kOp, [&]<class T>() {
      double e = 0;
      for_each_residual<T>(c.inputs, [&](int64_t, int64_t, int64_t, int64_t, T w, const Vec3<T>& r) {
        e += w * r.squaredNorm();
      });
      out.data<T>()[0] = static_cast<T>(e);
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const DType dt = c.in(0).dtype();
    Tensor gg = Tensor::zeros(c.in(0).shape(), dt), gR = Tensor::zeros(c.in(1).shape(), dt),
           gt = Tensor::zeros(c.in(2).shape(), dt), gw = Tensor::zeros(c.in(4).shape(), dt);
    dispatch_float(dt, kOp, [&]<class T>() {
      const T go = c.grad_output.data<T>()[0];
      const T* g = c.in(0).data<T>();
      const T* R = c.in(1).data<T>();
      const int64_t K = c.in(0).size(0);
      T* pg = gg.data<T>();
      T* pR = gR.data<T>();
      T* pt = gt.data<T>();
      T* pw = gw.data<T>();
      for_each_residual<T>(c.inputs, [&](int64_t b, int64_t edge, int64_t j, int64_t k, T w,
                                         const Vec3<T>& r) {
        pw[edge] += go * r.squaredNorm();
        const Vec3<T> d = 2 * go * w * r;  // dE/dr
        const Eigen::Map<const Vec3<T>> gj(g + 3 * j), gk(g + 3 * k);
        const Eigen::Map<const Mat3<T>> Rj(R + 9 * (b * K + j));
        Eigen::Map<Mat3<T>>(pR + 9 * (b * K + j)) += d * (gk - gj).transpose();
        Eigen::Map<Vec3<T>>(pt + 3 * (b * K + j)) += d;
        Eigen::Map<Vec3<T>>(pt + 3 * (b * K + k)) -= d;
        // r = R_j g_k − R_j g_j + g_j − g_k + ...
        const Vec3<T> RtD = Rj.transpose() * d;
        Eigen::Map<Vec3<T>>(pg + 3 * k) += RtD - d;
        Eigen::Map<Vec3<T>>(pg + 3 * j) += d - RtD;
      });
    });
    return {c.needs_grad[0] ? gg : Tensor(), c.needs_grad[1] ? gR : Tensor(),
            c.needs_grad[2] ? gt : Tensor(), Tensor(), c.needs_grad[4] ? gw : Tensor()};
  };
  return d;
}

namespace ops {
Tensor arap_energy(const Tensor& nodes, const Tensor& rotations, const Tensor& translations,
                   const Tensor& edges, const Tensor& edge_weights) {
  return apply(kOp, {nodes, rotations, translations, edges, edge_weights});
}
}  // namespace ops

}  // namespace weft
