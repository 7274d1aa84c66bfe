// Skinning: linear blend (LBS) and dual quaternion (DQS) skinning of vertices by joint
// transforms, batched over frames.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ops/geometry.h"
#include "ops/geometry_checks.h"
#include "ops/ops.h"

namespace weft {
namespace {

using namespace geometry_checks;

template <class T>
using Vec3 = Eigen::Matrix<T, 3, 1>;
template <class T>
using Vec4 = Eigen::Matrix<T, 4, 1>;
template <class T>
using Mat34 = Eigen::Matrix<T, 3, 4, Eigen::RowMajor>;

constexpr int64_t kMaxInfluences = 64;  // joints per vertex

struct Sizes {
  int64_t B, V, J, m;
  bool shared_vertices;  // vertices [V,3] used by every frame
};

// inputs: vertices, per-joint parameters [B, J, per_joint...], index, weights.
Sizes check_skinning(const char* op, const std::vector<Tensor>& in, const Shape& per_joint) {
  const Tensor &verts = in[0], &joints = in[1], &index = in[2], &weights = in[3];
  if (joints.dim() != static_cast<int64_t>(2 + per_joint.size()))
    fail(op, ": joint parameters must be [B, J, ", shape_str(per_joint).substr(1), " got ",
         shape_str(joints.shape()));
  Shape want = {-1, -1};
  want.insert(want.end(), per_joint.begin(), per_joint.end());
  expect_shape(op, "joint parameters", joints, want);
  const int64_t B = joints.size(0), J = joints.size(1);
  const bool shared = verts.dim() == 2;
  if (shared)
    expect_shape(op, "vertices", verts, {-1, 3});
  else
    expect_shape(op, "vertices", verts, {B, -1, 3});
  const int64_t V = verts.size(-2);
  expect_same_float_dtype(op, {&verts, &joints, &weights});
  expect_index(op, index, weights, V, J);
  if (index.size(1) > kMaxInfluences)
    fail(op, ": at most ", kMaxInfluences, " joints per vertex, got index ",
         shape_str(index.shape()));
  return {B, V, J, index.size(1), shared};
}

// Sums per-frame gradients [B, ...] over frames when the input was shared by all frames.
Tensor reduce_frames(const Tensor& per_frame, bool shared) {
  return shared ? ops::sum(per_frame, {0}) : per_frame;
}

constexpr const char* kLbs = "linear_blend_skinning";
constexpr const char* kDqs = "dual_quaternion_skinning";

// Per vertex and frame, the normalised blended dual quaternion of DQS.
template <class T>
struct DqsBlend {
  Vec4<T> b0, be;  // blended, before normalisation
  T norm;          // ‖b0‖
  Vec4<T> c0, ce;  // normalised
};

template <class T>
DqsBlend<T> dqs_blend(const T* dq_frame, const int64_t* idx, const T* w, int64_t m, T* signs) {
  DqsBlend<T> r;
  r.b0.setZero();
  r.be.setZero();
  const Eigen::Map<const Vec4<T>> ref(dq_frame + 8 * idx[0]);
  for (int64_t j = 0; j < m; ++j) {
    const T* q = dq_frame + 8 * idx[j];
    const T s = Eigen::Map<const Vec4<T>>(q).dot(ref) < 0 ? T(-1) : T(1);
    signs[j] = s;
    r.b0 += (s * w[j]) * Eigen::Map<const Vec4<T>>(q);
    r.be += (s * w[j]) * Eigen::Map<const Vec4<T>>(q + 4);
  }
  r.norm = std::max(r.b0.norm(), T(1e-12));
  r.c0 = r.b0 / r.norm;
  r.ce = r.be / r.norm;
  return r;
}

// The forward (frame, vertex) loop of both skinnings: out[b, v] = skin(b, v, x).
template <class T, class Skin>
Tensor skin_vertices(const Tensor& vertices, const Sizes& s, Skin skin) {
  Tensor out = Tensor::empty({s.B, s.V, 3}, vertices.dtype());
  const T* verts = vertices.data<T>();
  T* po = out.data<T>();
#pragma omp parallel for collapse(2) schedule(static)
  for (int64_t b = 0; b < s.B; ++b)
    for (int64_t v = 0; v < s.V; ++v) {
      const Vec3<T> x = Eigen::Map<const Vec3<T>>(verts + 3 * (s.shared_vertices ? v : b * s.V + v));
      Eigen::Map<Vec3<T>>(po + 3 * (b * s.V + v)) = skin(b, v, x);
    }
  return out;
}

// The backward shell of both skinnings: gradient buffers, the loop over frames (in
// parallel: a frame's joint gradients belong to one thread) and vertices, and the sums over
// frames of shared inputs. vertex(b, v, x, g, grad_joints_of_frame_b, grad_weights_of_v)
// adds the vertex's joint gradients, writes its m weight gradients and returns dL/dx.
template <class T, class VertexGrad>
std::vector<Tensor> skin_backward(const BackwardContext& c, const Sizes& s, VertexGrad vertex) {
  const DType dt = c.in(0).dtype();
  Tensor gv = Tensor::zeros({s.B, s.V, 3}, dt), gj = Tensor::zeros(c.in(1).shape(), dt),
         gw = Tensor::zeros({s.B, s.V, s.m}, dt);
  const int64_t per_joint = c.in(1).numel() / std::max<int64_t>(1, s.B * s.J);
  const T* verts = c.in(0).data<T>();
  const T* go = c.grad_output.data<T>();
  T* pv = gv.data<T>();
  T* pj = gj.data<T>();
  T* pw = gw.data<T>();
#pragma omp parallel for schedule(static)
  for (int64_t b = 0; b < s.B; ++b)
    for (int64_t v = 0; v < s.V; ++v) {
      const Vec3<T> x = Eigen::Map<const Vec3<T>>(verts + 3 * (s.shared_vertices ? v : b * s.V + v));
      const Vec3<T> g = Eigen::Map<const Vec3<T>>(go + 3 * (b * s.V + v));
      Eigen::Map<Vec3<T>>(pv + 3 * (b * s.V + v)) =
          vertex(b, v, x, g, pj + per_joint * b * s.J, pw + (b * s.V + v) * s.m);
    }
  return {c.needs_grad[0] ? reduce_frames(gv, s.shared_vertices) : Tensor(), c.needs_grad[1] ? gj : Tensor(),
          Tensor(), c.needs_grad[3] ? ops::sum(gw, {0}) : Tensor()};
}

}  // namespace

WEFT_REGISTER_OP(linear_blend_skinning) {
  OpDef d;
  d.name = kLbs;
  d.doc = "v' = sum_j w_j (A_j v + b_j) with transforms [B,J,3,4]";
  d.num_inputs = 4;
  d.forward = [](const ForwardContext& c) {
    const Sizes s = check_skinning(kLbs, c.inputs, {3, 4});
    return dispatch_float(c.in(0).dtype(), kLbs, [&]<class T>() {
      const T* tf = c.in(1).data<T>();
      const int64_t* idx = c.in(2).data<int64_t>();
      const T* w = c.in(3).data<T>();
      return skin_vertices<T>(c.in(0), s, [&](int64_t b, int64_t v, const Vec3<T>& x) -> Vec3<T> {
        Mat34<T> blend = Mat34<T>::Zero();
        for (int64_t j = 0; j < s.m; ++j)
          blend += w[v * s.m + j] * Eigen::Map<const Mat34<T>>(tf + 12 * (b * s.J + idx[v * s.m + j]));
        return blend.template leftCols<3>() * x + blend.col(3);
      });
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Sizes s = check_skinning(kLbs, c.inputs, {3, 4});
    return dispatch_float(c.in(0).dtype(), kLbs, [&]<class T>() {
      const T* tf = c.in(1).data<T>();
      const int64_t* idx = c.in(2).data<int64_t>();
      const T* w = c.in(3).data<T>();
      return skin_backward<T>(c, s, [&](int64_t b, int64_t v, const Vec3<T>& x, const Vec3<T>& g, T* gt,
                                        T* gw) -> Vec3<T> {
        Vec3<T> gx = Vec3<T>::Zero();
        for (int64_t j = 0; j < s.m; ++j) {
          const int64_t k = idx[v * s.m + j];
          const T wj = w[v * s.m + j];
          const Eigen::Map<const Mat34<T>> A(tf + 12 * (b * s.J + k));
          gx += wj * (A.template leftCols<3>().transpose() * g);
          Eigen::Map<Mat34<T>> gA(gt + 12 * k);
          gA.template leftCols<3>() += (wj * g) * x.transpose();
          gA.col(3) += wj * g;
          gw[j] = g.dot(A.template leftCols<3>() * x + A.col(3));
        }
        return gx;
      });
    });
  };
  return d;
}

WEFT_REGISTER_OP(dual_quaternion_skinning) {
  OpDef d;
  d.name = kDqs;
  d.doc = "dual quaternion skinning with antipodality fix, dual quaternions [B,J,8]";
  d.num_inputs = 4;
  d.forward = [](const ForwardContext& c) {
    const Sizes s = check_skinning(kDqs, c.inputs, {8});
    return dispatch_float(c.in(0).dtype(), kDqs, [&]<class T>() {
      const T* dq = c.in(1).data<T>();
      const int64_t* idx = c.in(2).data<int64_t>();
      const T* w = c.in(3).data<T>();
      return skin_vertices<T>(c.in(0), s, [&](int64_t b, int64_t v, const Vec3<T>& x) -> Vec3<T> {
        T signs[kMaxInfluences];
        const DqsBlend<T> q = dqs_blend(dq + 8 * b * s.J, idx + v * s.m, w + v * s.m, s.m, signs);
        const T qw = q.c0[0], ew = q.ce[0];
        const Vec3<T> u = q.c0.template tail<3>(), ev = q.ce.template tail<3>();
        const Vec3<T> k = u.cross(x) + qw * x;
        const Vec3<T> rotated = x + 2 * u.cross(k);
        const Vec3<T> translation = 2 * (qw * ev - ew * u + u.cross(ev));
        return rotated + translation;
      });
    });
  };
  d.backward = [](const BackwardContext& c) -> std::vector<Tensor> {
    const Sizes s = check_skinning(kDqs, c.inputs, {8});
    return dispatch_float(c.in(0).dtype(), kDqs, [&]<class T>() {
      const T* dq = c.in(1).data<T>();
      const int64_t* idx = c.in(2).data<int64_t>();
      const T* w = c.in(3).data<T>();
      return skin_backward<T>(c, s, [&](int64_t b, int64_t v, const Vec3<T>& x, const Vec3<T>& g, T* gq,
                                        T* gw) -> Vec3<T> {
        T signs[kMaxInfluences];
        const T* dq_frame = dq + 8 * b * s.J;
        const DqsBlend<T> q = dqs_blend(dq_frame, idx + v * s.m, w + v * s.m, s.m, signs);
        const T qw = q.c0[0], ew = q.ce[0];
        const Vec3<T> u = q.c0.template tail<3>(), ev = q.ce.template tail<3>();
        const Vec3<T> k = u.cross(x) + qw * x;
        // d/d(c0, ce) of rotated + translation.
        Vec4<T> g0, ge;
        g0[0] = 2 * g.dot(u.cross(x)) + 2 * g.dot(ev);
        g0.template tail<3>() = 2 * k.cross(g) + 2 * x.cross(g.cross(u)) + 2 * (-ew * g + ev.cross(g));
        ge[0] = -2 * g.dot(u);
        ge.template tail<3>() = 2 * (qw * g + g.cross(u));
        // Through the normalisation c0 = b0/‖b0‖, ce = be/‖b0‖.
        const Vec4<T> gb_e = ge / q.norm;
        const Vec4<T> gb_0 = (g0 - q.c0 * q.c0.dot(g0) - q.c0 * ge.dot(q.ce)) / q.norm;
        for (int64_t j = 0; j < s.m; ++j) {
          const int64_t jt = idx[v * s.m + j];
          const T sw = signs[j] * w[v * s.m + j];
          Eigen::Map<Vec4<T>>(gq + 8 * jt) += sw * gb_0;
          Eigen::Map<Vec4<T>>(gq + 8 * jt + 4) += sw * gb_e;
          gw[j] = signs[j] * (gb_0.dot(Eigen::Map<const Vec4<T>>(dq_frame + 8 * jt)) +
                              gb_e.dot(Eigen::Map<const Vec4<T>>(dq_frame + 8 * jt + 4)));
        }
        // d/dx: Rᵀ g, the rotation by the conjugate quaternion.
        const Vec3<T> kc = (-u).cross(g) + qw * g;
        return g + 2 * (-u).cross(kc);
      });
    });
  };
  return d;
}

namespace ops {
Tensor linear_blend_skinning(const Tensor& vertices, const Tensor& transforms,
                             const Tensor& index, const Tensor& weights) {
  return apply(kLbs, {vertices, transforms, index, weights});
}
Tensor dual_quaternion_skinning(const Tensor& vertices, const Tensor& dual_quaternions,
                                const Tensor& index, const Tensor& weights) {
  return apply(kDqs, {vertices, dual_quaternions, index, weights});
}
}  // namespace ops

}  // namespace weft
