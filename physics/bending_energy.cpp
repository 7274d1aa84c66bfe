#include "physics/bending_energy.h"

#include <Eigen/Geometry>
#include <cmath>

#include "physics/second_order_jet.h"

namespace weft::physics {

namespace {

// tan θ = ((n1 × n2)·â) / (n1·n2) with n1 = a × b, n2 = c × a the (unnormalised)
// normals of triangles (x0, x1, x2) and (x1, x0, x3); a = x1−x0, b = x2−x0, c = x3−x0.
template <class T, class V>
T angle_from_edges(const V& a, const V& b, const V& c) {
  auto cross = [](const V& p, const V& q) {
    return V{p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2], p[0] * q[1] - p[1] * q[0]};
  };
  auto dot = [](const V& p, const V& q) { return p[0] * q[0] + p[1] * q[1] + p[2] * q[2]; };
  const V n1 = cross(a, b), n2 = cross(c, a);
  const T y = dot(cross(n1, n2), a) * inverse(sqrt(dot(a, a)));
  return atan2(y, dot(n1, n2));
}

// Scatters a gradient in (a, b, c) = (x1−x0, x2−x0, x3−x0) onto the hinge's vertices.
template <class El>
void add_edge_gradient(const El& el, const Eigen::Matrix<double, 9, 1>& ge, Eigen::VectorXd& g) {
  for (int k = 0; k < 3; ++k) {
    const Vec3 gk = ge.segment<3>(3 * k);
    g.segment<3>(3 * el.v[k + 1]) += gk;
    g.segment<3>(3 * el.v[0]) -= gk;
  }
}

}  // namespace

double dihedral_angle(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3) {
  const Vec3 a = x1 - x0, b = x2 - x0, c = x3 - x0;
  const Vec3 n1 = a.cross(b), n2 = c.cross(a);
  return std::atan2(n1.cross(n2).dot(a) / a.norm(), n1.dot(n2));
}

BendingEnergy::BendingEnergy(const ClothMesh& mesh, const ClothMaterial& m) {
  elements_.reserve(mesh.hinges.size());
  for (const auto& hinge : mesh.hinges) {
    const auto& v = hinge.v;
    const Vec3 x0 = mesh.rest_vertex(v[0]), x1 = mesh.rest_vertex(v[1]);
    const Vec3 x2 = mesh.rest_vertex(v[2]), x3 = mesh.rest_vertex(v[3]);
    const double a1 = 0.5 * (x1 - x0).cross(x2 - x0).norm();
    const double a2 = 0.5 * (x3 - x0).cross(x1 - x0).norm();
    Element el;
    el.v = v;
    el.rest_angle = dihedral_angle(x0, x1, x2, x3);
    el.weight = 0.5 * m.bending_stiffness * 3.0 * (x1 - x0).squaredNorm() / (a1 + a2);
    elements_.push_back(el);
  }
}

void BendingEnergy::add_pattern(std::vector<std::array<int, 2>>& pairs) const {
  for (const auto& el : elements_)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) pairs.push_back({el.v[a], el.v[b]});
}

void BendingEnergy::add_weak_pairs(std::vector<std::array<int, 2>>& pairs) const {
  for (const auto& el : elements_) pairs.push_back({el.v[2], el.v[3]});
}

double BendingEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                               SparseHessian* H) const {
  using J = Jet2<9>;
  using JV = std::array<J, 3>;
  double energy = 0;
  for (const auto& el : elements_) {
    if (el.weight == 0) continue;
    const Vec3 x0 = x.segment<3>(3 * el.v[0]);
    const Vec3 a = x.segment<3>(3 * el.v[1]) - x0;
    const Vec3 b = x.segment<3>(3 * el.v[2]) - x0;
    const Vec3 c = x.segment<3>(3 * el.v[3]) - x0;
    const Vec3 n1 = a.cross(b), n2 = c.cross(a);
    // A collapsed triangle has no normal: the hinge exerts no force until it reopens.
    if (n1.squaredNorm() < 1e-30 || n2.squaredNorm() < 1e-30 || a.squaredNorm() < 1e-30) continue;
    if (!g && !H) {
      const double d = std::atan2(n1.cross(n2).dot(a) / a.norm(), n1.dot(n2)) - el.rest_angle;
      energy += el.weight * d * d;
      continue;
    }
    if (!H || project_hessian_) {
      // The gradient in closed form: a wing vertex moves θ at 1/h along its triangle's
      // normal (h its distance from the hinge edge, |n|/|a|), and the edge's end points
      // take each wing's share by where the wing projects onto the edge (s = b·a/|a|²,
      // c·a/|a|²), so the four sum to zero. Checked against a first-order jet (1e-15) and
      // by the gradient checks; several times cheaper. With the projection on, the
      // Hessian is the Gauss-Newton term 2w ∇θ∇θᵀ: PSD by construction, and it differs
      // from the exact Hessian only by 2w (θ − θ̄) ∇²θ, small while the hinge is near its
      // rest angle.
      const double a2 = a.squaredNorm(), a_len = std::sqrt(a2);
      const double theta = std::atan2(n1.cross(n2).dot(a) / a_len, n1.dot(n2));
      const Vec3 g2 = (-a_len / n1.squaredNorm()) * n1;
      const Vec3 g3 = (-a_len / n2.squaredNorm()) * n2;
      const double s2 = b.dot(a) / a2, s3 = c.dot(a) / a2;
      Eigen::Matrix<double, 12, 1> gx;  // ∇θ over (x0, x1, x2, x3)
      gx << -(1 - s2) * g2 - (1 - s3) * g3, -s2 * g2 - s3 * g3, g2, g3;
      const double d = theta - el.rest_angle;
      energy += el.weight * d * d;
      if (g)
        for (int k = 0; k < 4; ++k) g->segment<3>(3 * el.v[k]) += (2.0 * el.weight * d) * gx.segment<3>(3 * k);
      if (H) {
        const Eigen::Matrix<double, 12, 12> hx = (2.0 * el.weight) * gx * gx.transpose();
        H->add<4>(el.v, hx);
      }
      continue;
    }
    JV ja, jb, jc;
    for (int k = 0; k < 3; ++k) {
      ja[k] = J::variable(a[k], k);
      jb[k] = J::variable(b[k], 3 + k);
      jc[k] = J::variable(c[k], 6 + k);
    }
    const J theta = angle_from_edges<J, JV>(ja, jb, jc);
    const double d = theta.v - el.rest_angle;
    energy += el.weight * d * d;
    if (g) add_edge_gradient(el, 2.0 * el.weight * d * theta.g, *g);
    if (H) {
      // The exact Hessian (projection off: for derivative checks).
      const Eigen::Matrix<double, 9, 9> he =
          2.0 * el.weight * (theta.g * theta.g.transpose() + d * theta.h);
      // x = P (a, b, c) with rows for x0 = −(a+b+c) contributions: H_x = Pᵀ H_e P.
      Eigen::Matrix<double, 12, 12> hx;
      Eigen::Matrix3d s0 = Eigen::Matrix3d::Zero();
      for (int p = 0; p < 3; ++p) {
        Eigen::Matrix3d sp = Eigen::Matrix3d::Zero();
        for (int q = 0; q < 3; ++q) {
          const Eigen::Matrix3d blk = he.block<3, 3>(3 * p, 3 * q);
          hx.block<3, 3>(3 * (p + 1), 3 * (q + 1)) = blk;
          sp += blk;
        }
        hx.block<3, 3>(3 * (p + 1), 0) = -sp;
        hx.block<3, 3>(0, 3 * (p + 1)) = -sp.transpose();
        s0 += sp;
      }
      hx.block<3, 3>(0, 0) = s0;
      H->add<4>(el.v, hx);
    }
  }
  return energy;
}

}  // namespace weft::physics
