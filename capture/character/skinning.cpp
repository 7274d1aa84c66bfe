#include "capture/character/skinning.h"

#include <cmath>

#include "graph/error.h"

namespace weft::capture {

int SkinningWeights::max_influences() const {
  size_t k = 0;
  for (const auto& v : vertices) k = std::max(k, v.size());
  return static_cast<int>(k);
}

Eigen::MatrixXd SkinningWeights::dense() const {
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(num_vertices(), num_joints);
  for (int v = 0; v < num_vertices(); ++v)
    for (const SkinInfluence& inf : vertices[v]) W(v, inf.joint) += inf.weight;
  return W;
}

SkinningWeights::Csr SkinningWeights::csr() const {
  Csr c;
  c.offsets.reserve(vertices.size() + 1);
  c.offsets.push_back(0);
  for (const auto& v : vertices) {
    for (const SkinInfluence& inf : v) {
      c.joints.push_back(inf.joint);
      c.weights.push_back(inf.weight);
    }
    c.offsets.push_back(static_cast<int>(c.joints.size()));
  }
  return c;
}

void SkinningWeights::padded(
    Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& joints,
    Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& weights) const {
  const int k = max_influences();
  joints.setZero(num_vertices(), k);
  weights.setZero(num_vertices(), k);
  for (int v = 0; v < num_vertices(); ++v)
    for (size_t i = 0; i < vertices[v].size(); ++i) {
      joints(v, i) = vertices[v][i].joint;
      weights(v, i) = vertices[v][i].weight;
    }
}

void normalize_weights(SkinningWeights& w, const std::string& what) {
  for (int v = 0; v < w.num_vertices(); ++v) {
    double sum = 0;
    for (const SkinInfluence& inf : w.vertices[v]) {
      if (inf.joint < 0 || inf.joint >= w.num_joints)
        fail(what, ": vertex ", v, " has joint index ", inf.joint, " out of range (", w.num_joints, " joints)");
      if (!std::isfinite(inf.weight) || inf.weight < 0)
        fail(what, ": vertex ", v, " has an invalid weight ", inf.weight);
      sum += inf.weight;
    }
    if (!(sum > 0)) fail(what, ": vertex ", v, " has no positive skinning weight");
    for (SkinInfluence& inf : w.vertices[v]) inf.weight /= sum;
  }
}

namespace {
void check_sizes(const Vertices& rest, const SkinningWeights& w, size_t num_transforms, const char* fn) {
  if (rest.rows() != w.num_vertices())
    fail(fn, ": ", rest.rows(), " vertices but weights for ", w.num_vertices());
  if (static_cast<int>(num_transforms) != w.num_joints)
    fail(fn, ": ", num_transforms, " transforms but weights over ", w.num_joints, " joints");
  for (int v = 0; v < w.num_vertices(); ++v) {
    if (w.vertices[v].empty()) fail(fn, ": vertex ", v, " has no skinning influence");
    for (const SkinInfluence& inf : w.vertices[v])
      if (inf.joint < 0 || inf.joint >= w.num_joints)
        fail(fn, ": vertex ", v, " has joint index ", inf.joint, " out of range");
  }
}
}  // namespace

Vertices linear_blend_skinning(const Vertices& rest, const SkinningWeights& w, const Transforms& S) {
  check_sizes(rest, w, S.size(), "linear_blend_skinning");
  Vertices out(rest.rows(), 3);
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    Eigen::Matrix<double, 3, 4> M = Eigen::Matrix<double, 3, 4>::Zero();
    for (const SkinInfluence& inf : w.vertices[v]) M += inf.weight * S[inf.joint].affine();
    out.row(v) = (M.leftCols<3>() * rest.row(v).transpose() + M.col(3)).transpose();
  }
  return out;
}

DualQuaternion to_dual_quaternion(const Eigen::Isometry3d& T) {
  DualQuaternion dq;
  dq.real = Eigen::Quaterniond(T.linear());
  dq.real.normalize();
  const Eigen::Vector3d t = T.translation();
  const Eigen::Quaterniond tq(0, t.x(), t.y(), t.z());
  dq.dual.coeffs() = 0.5 * (tq * dq.real).coeffs();
  return dq;
}

Vertices dual_quaternion_skinning(const Vertices& rest, const SkinningWeights& w, const Transforms& S) {
  std::vector<DualQuaternion> q(S.size());
  for (size_t j = 0; j < S.size(); ++j) q[j] = to_dual_quaternion(S[j]);
  return dual_quaternion_skinning(rest, w, q);
}

Vertices dual_quaternion_skinning(const Vertices& rest, const SkinningWeights& w,
                                  const std::vector<DualQuaternion>& q) {
  check_sizes(rest, w, q.size(), "dual_quaternion_skinning");
  Vertices out(rest.rows(), 3);
  for (Eigen::Index v = 0; v < rest.rows(); ++v) {
    const auto& infl = w.vertices[v];
    const Eigen::Vector4d ref = q[infl.front().joint].real.coeffs();
    Eigen::Vector4d b0 = Eigen::Vector4d::Zero(), be = Eigen::Vector4d::Zero();
    for (const SkinInfluence& inf : infl) {
      const DualQuaternion& d = q[inf.joint];
      const double s = d.real.coeffs().dot(ref) < 0 ? -inf.weight : inf.weight;
      b0 += s * d.real.coeffs();
      be += s * d.dual.coeffs();
    }
    const double norm = b0.norm();
    const Eigen::Quaterniond r(b0 / norm);  // coeffs order x,y,z,w
    Eigen::Quaterniond e;
    e.coeffs() = be / norm;
    const Eigen::Quaterniond t = e * r.conjugate();  // translation = 2 vec(be b0*)
    const Eigen::Vector3d p = r.toRotationMatrix() * rest.row(v).transpose() + 2.0 * t.vec();
    out.row(v) = p.transpose();
  }
  return out;
}

}  // namespace weft::capture
