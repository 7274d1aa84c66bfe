// Forward kinematics of a chain of 1-dof joints, differentiable in the joint parameters.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "ops/geometry.h"
#include "ops/ops.h"

namespace weft {
namespace {

constexpr const char* kOp = "forward_kinematics";
using Mat4 = Eigen::Matrix4d;
using Vec3 = Eigen::Vector3d;

struct Chain {
  std::vector<int64_t> parents, prismatic;
  std::vector<double> offsets, axes, bind_inverse;
  int64_t J = 0;
};

Chain chain_from(const Attrs& a) {
  Chain c;
  c.parents = a.get_ints("parents");
  c.prismatic = a.get_ints("prismatic");
  c.offsets = a.get_floats("offsets");
  c.axes = a.get_floats("axes");
  if (a.has("bind_inverse")) c.bind_inverse = a.get_floats("bind_inverse");
  c.J = static_cast<int64_t>(c.parents.size());
  return c;
}

void validate(const Chain& c) {
  const size_t J = static_cast<size_t>(c.J);
  if (c.prismatic.size() != J || c.offsets.size() != 3 * J || c.axes.size() != 3 * J ||
      (!c.bind_inverse.empty() && c.bind_inverse.size() != 12 * J))
    fail(kOp, ": chain arrays disagree on the joint count ", J);
  for (int64_t j = 0; j < c.J; ++j)
    if (c.parents[j] >= j || c.parents[j] < -1)
      fail(kOp, ": joint ", j, " has parent ", c.parents[j], "; parents must precede children");
}

Mat4 translation(const Vec3& t) {
  Mat4 m = Mat4::Identity();
  m.block<3, 1>(0, 3) = t;
  return m;
}

// M_j(p) and dM_j/dp.
void joint_motion(const Chain& c, int64_t j, double p, Mat4& M, Mat4& dM) {
  const Vec3 a(c.axes[3 * j], c.axes[3 * j + 1], c.axes[3 * j + 2]);
  M.setIdentity();
  dM.setZero();
  if (c.prismatic[j]) {
    M.block<3, 1>(0, 3) = p * a;
    dM.block<3, 1>(0, 3) = a;
  } else {
    const Eigen::Matrix3d R = Eigen::AngleAxisd(p, a).toRotationMatrix();
    Eigen::Matrix3d K;
    K << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
    M.block<3, 3>(0, 0) = R;
    dM.block<3, 3>(0, 0) = K * R;  // d/dp exp(pK) = K exp(pK)
  }
}

Mat4 bind_inverse(const Chain& c, int64_t j) {
  Mat4 m = Mat4::Identity();
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k) m(r, k) = c.bind_inverse[12 * j + 4 * r + k];
  return m;
}

// Global transforms of one frame.
void frame_globals(const Chain& c, const double* p, std::vector<Mat4>& G) {
  G.resize(c.J);
  Mat4 M, dM;
  for (int64_t j = 0; j < c.J; ++j) {
    joint_motion(c, j, p[j], M, dM);
    const Mat4 L = translation(Vec3(c.offsets[3 * j], c.offsets[3 * j + 1], c.offsets[3 * j + 2])) * M;
    G[j] = c.parents[j] < 0 ? L : G[c.parents[j]] * L;
  }
}

template <class T>
std::vector<double> frame_parameters(const T* p, int64_t J) {
  return std::vector<double>(p, p + J);
}

}  // namespace

WEFT_REGISTER_OP(forward_kinematics) {
  OpDef d;
  d.name = kOp;
  d.doc = "joint parameters [B,J] -> global (or skinning) transforms [B,J,3,4]";
  d.num_inputs = 1;
  d.forward = [](const ForwardContext& ctx) {
    const Chain c = chain_from(ctx.attrs);
    validate(c);
    const Tensor& p = ctx.in(0);
    if (p.dim() != 2 || p.size(1) != c.J)
      fail(kOp, ": joint parameters must be [B, ", c.J, "], got ", shape_str(p.shape()));
    const int64_t B = p.size(0);
    Tensor out = Tensor::empty({B, c.J, 3, 4}, p.dtype());
    dispatch_float(p.dtype(), kOp, [&]<class T>() {
      const T* pp = p.data<T>();
      T* po = out.data<T>();
#pragma omp parallel for schedule(static)
      for (int64_t b = 0; b < B; ++b) {
        const std::vector<double> params = frame_parameters(pp + b * c.J, c.J);
        std::vector<Mat4> G;
        frame_globals(c, params.data(), G);
        for (int64_t j = 0; j < c.J; ++j) {
          const Mat4 S = c.bind_inverse.empty() ? G[j] : Mat4(G[j] * bind_inverse(c, j));
          for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 4; ++k) po[((b * c.J + j) * 3 + r) * 4 + k] = static_cast<T>(S(r, k));
        }
      }
    });
    return out;
  };
  d.backward = [](const BackwardContext& ctx) -> std::vector<Tensor> {
    const Chain c = chain_from(ctx.attrs);
    const Tensor& p = ctx.in(0);
    const int64_t B = p.size(0);
    Tensor gp = Tensor::empty(p.shape(), p.dtype());
    dispatch_float(p.dtype(), kOp, [&]<class T>() {
      const T* pp = p.data<T>();
      const T* go = ctx.grad_output.data<T>();
      T* pg = gp.data<T>();
#pragma omp parallel for schedule(static)
      for (int64_t b = 0; b < B; ++b) {
        const std::vector<double> params = frame_parameters(pp + b * c.J, c.J);
        std::vector<Mat4> G;
        frame_globals(c, params.data(), G);
        // dL/dG_j as 4×4 (bottom row zero), starting from the output gradient.
        std::vector<Mat4> dG(c.J);
        for (int64_t j = 0; j < c.J; ++j) {
          Mat4 dS = Mat4::Zero();
          for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 4; ++k) dS(r, k) = go[((b * c.J + j) * 3 + r) * 4 + k];
          dG[j] = c.bind_inverse.empty() ? dS : Mat4(dS * bind_inverse(c, j).transpose());
        }
        // Children come after parents: walk backwards, pushing gradients to parents.
        Mat4 M, dM;
        for (int64_t j = c.J - 1; j >= 0; --j) {
          joint_motion(c, j, params[j], M, dM);
          const Mat4 T0 = translation(Vec3(c.offsets[3 * j], c.offsets[3 * j + 1], c.offsets[3 * j + 2]));
          const Mat4 L = T0 * M;
          const int64_t parent = c.parents[j];
          const Mat4 dL = parent < 0 ? dG[j] : Mat4(G[parent].transpose() * dG[j]);
          if (parent >= 0) dG[parent] += dG[j] * L.transpose();
          pg[b * c.J + j] = static_cast<T>((dL.array() * (T0 * dM).array()).sum());
        }
      }
    });
    return {gp};
  };
  return d;
}

namespace ops {
Tensor forward_kinematics(const Tensor& joint_parameters, const KinematicChain& chain) {
  Attrs a;
  a.set("parents", chain.parents);
  a.set("prismatic", chain.prismatic);
  a.set("offsets", chain.offsets);
  a.set("axes", chain.axes);
  if (!chain.bind_inverse.empty()) a.set("bind_inverse", chain.bind_inverse);
  return apply(kOp, {joint_parameters}, a);
}
}  // namespace ops

}  // namespace weft
