// Embedded deformation: vertices follow the rigid motions of nearby graph nodes.
#include <Eigen/Core>

#include "ops/geometry.h"
#include "ops/geometry_checks.h"
#include "ops/ops.h"

namespace weft {
namespace {

using namespace geometry_checks;
constexpr const char* kOp = "embedded_deformation";

template <class T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <class T>
using Mat3 = Eigen::Matrix<T, 3, 3, Eigen::RowMajor>;

struct Sizes {
  int64_t B, V, K, n;
};

Sizes check_inputs(const std::vector<Tensor>& in) {
  const Tensor &rest = in[0], &nodes = in[1], &rot = in[2], &trans = in[3], &index = in[4],
               &weights = in[5];
  expect_shape(kOp, "rest vertices", rest, {-1, 3});
  expect_shape(kOp, "nodes", nodes, {-1, 3});
  const int64_t K = nodes.size(0);
  expect_shape(kOp, "rotations", rot, {-1, K, 3, 3});
  const int64_t B = rot.size(0);
  expect_shape(kOp, "translations", trans, {B, K, 3});
  expect_same_float_dtype(kOp, {&rest, &nodes, &rot, &trans, &weights});
  expect_index(kOp, index, weights, rest.size(0), K);
  return {B, rest.size(0), K, index.size(1)};
}

}  // namespace

WEFT_REGISTER_OP(embedded_deformation) {
  OpDef d;
  d.name = kOp;
  d.doc = "v' = sum_k w [R_k (v - g_k) + g_k + t_k] over a vertex's graph nodes, batched";
  d.num_inputs = 6;
  d.forward = [](const ForwardContext& c) {
    const Sizes s = check_inputs(c.inputs);
    Tensor out = Tensor::empty({s.B, s.V, 3}, c.in(0).dtype());
    dispatch_float(out.dtype(), kOp, [&]<class T>() {
      const T* rest = c.in(0).data<T>();
      const T* nodes = c.in(1).data<T>();
      const T* rot = c.in(2).data<T>();
      const T* trans = c.in(3).data<T>();
      const int64_t* idx = c.in(4).data<int64_t>();
      const T* w = c.in(5).data<T>();
      T* po = out.data<T>();
#pragma omp parallel for collapse(2) schedule(static)
      for (int64_t b = 0; b < s.B; ++b)
        for (int64_t v = 0; v < s.V; ++v) {
          const Vec3<T> x = Eigen::Map<const Vec3<T>>(rest + 3 * v);
          Vec3<T> acc = Vec3<T>::Zero();
          for (int64_t j = 0; j < s.n; ++j) {
            const int64_t k = idx[v * s.n + j];
            const Eigen::Map<const Vec3<T>> g(nodes + 3 * k);
            const Eigen::Map<const Mat3<T>> R(rot + (b * s.K + k) * 9);
            const Eigen::Map<const Vec3<T>> t(trans + (b * s.K + k) * 3);
            acc += w[v * s.n + j] * (R * (x - g) + g + t);
          }
          Eigen::Map<Vec3<T>>(po + (b * s.V + v) * 3) = acc;
        }
    });
    return out;
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Sizes s = check_inputs(c.inputs);
    const DType dt = c.in(0).dtype();
    std::vector<Tensor> grads(6);
    dispatch_float(dt, kOp, [&]<class T>() {
      const T* rest = c.in(0).data<T>();
      const T* nodes = c.in(1).data<T>();
      const T* rot = c.in(2).data<T>();
      const T* trans = c.in(3).data<T>();
      const int64_t* idx = c.in(4).data<int64_t>();
      const T* w = c.in(5).data<T>();
      const T* go = c.grad_output.data<T>();
      // Node rotations and translations: frames are independent, so threads split them.
      if (c.needs_grad[2] || c.needs_grad[3]) {
        Tensor gR = Tensor::zeros(c.in(2).shape(), dt), gt = Tensor::zeros(c.in(3).shape(), dt);
        T* pR = gR.data<T>();
        T* pt = gt.data<T>();
#pragma omp parallel for schedule(static)
        for (int64_t b = 0; b < s.B; ++b)
          for (int64_t v = 0; v < s.V; ++v) {
            const Vec3<T> g = Eigen::Map<const Vec3<T>>(go + (b * s.V + v) * 3);
            const Vec3<T> x = Eigen::Map<const Vec3<T>>(rest + 3 * v);
            for (int64_t j = 0; j < s.n; ++j) {
              const int64_t k = idx[v * s.n + j];
              const T wj = w[v * s.n + j];
              const Eigen::Map<const Vec3<T>> node(nodes + 3 * k);
              Eigen::Map<Mat3<T>>(pR + (b * s.K + k) * 9) += (wj * g) * (x - node).transpose();
              Eigen::Map<Vec3<T>>(pt + (b * s.K + k) * 3) += wj * g;
            }
          }
        if (c.needs_grad[2]) grads[2] = gR;
        if (c.needs_grad[3]) grads[3] = gt;
      }
      // Rest vertices and weights: per vertex, summed over frames.
      if (c.needs_grad[0] || c.needs_grad[5]) {
        Tensor grest = Tensor::zeros(c.in(0).shape(), dt), gw = Tensor::zeros(c.in(5).shape(), dt);
        T* pr = grest.data<T>();
        T* pw = gw.data<T>();
#pragma omp parallel for schedule(static)
        for (int64_t v = 0; v < s.V; ++v) {
          const Vec3<T> x = Eigen::Map<const Vec3<T>>(rest + 3 * v);
          Vec3<T> acc = Vec3<T>::Zero();
          for (int64_t b = 0; b < s.B; ++b) {
            const Vec3<T> g = Eigen::Map<const Vec3<T>>(go + (b * s.V + v) * 3);
            for (int64_t j = 0; j < s.n; ++j) {
              const int64_t k = idx[v * s.n + j];
              const Eigen::Map<const Vec3<T>> node(nodes + 3 * k);
              const Eigen::Map<const Mat3<T>> R(rot + (b * s.K + k) * 9);
              const Eigen::Map<const Vec3<T>> t(trans + (b * s.K + k) * 3);
              acc += w[v * s.n + j] * (R.transpose() * g);
              pw[v * s.n + j] += g.dot(R * (x - node) + node + t);
            }
          }
          Eigen::Map<Vec3<T>>(pr + 3 * v) = acc;
        }
        if (c.needs_grad[0]) grads[0] = grest;
        if (c.needs_grad[5]) grads[5] = gw;
      }
      // Node positions: d/dg_k = w (I − R_k)ᵀ g. Scatters across vertices: serial.
      if (c.needs_grad[1]) {
        Tensor gn = Tensor::zeros(c.in(1).shape(), dt);
        T* pn = gn.data<T>();
        for (int64_t b = 0; b < s.B; ++b)
          for (int64_t v = 0; v < s.V; ++v) {
            const Vec3<T> g = Eigen::Map<const Vec3<T>>(go + (b * s.V + v) * 3);
            for (int64_t j = 0; j < s.n; ++j) {
              const int64_t k = idx[v * s.n + j];
              const Eigen::Map<const Mat3<T>> R(rot + (b * s.K + k) * 9);
              Eigen::Map<Vec3<T>>(pn + 3 * k) += w[v * s.n + j] * (g - R.transpose() * g);
            }
          }
        grads[1] = gn;
      }
    });
    return grads;
  };
  return d;
}

namespace ops {
Tensor embedded_deformation(const Tensor& rest, const Tensor& nodes, const Tensor& rotations,
                            const Tensor& translations, const Tensor& index,
                            const Tensor& weights) {
  return apply(kOp, {rest, nodes, rotations, translations, index, weights});
}
}  // namespace ops

}  // namespace weft
