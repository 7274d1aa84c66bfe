#include "physics/collision_energy.h"

#include <Eigen/Eigenvalues>
#include <cmath>

#include "graph/error.h"

namespace weft::physics {

DistanceSample signed_distance(const SphereObstacle& sphere, const Eigen::Vector3d& x) {
  DistanceSample s;
  const Eigen::Vector3d r = x - sphere.center;
  const double len = r.norm();
  s.distance = len - sphere.radius;
  if (len > 1e-12) {
    s.gradient = r / len;
    s.hessian = (Eigen::Matrix3d::Identity() - s.gradient * s.gradient.transpose()) / len;
  } else {
    s.gradient = Eigen::Vector3d::UnitY();  // any direction out of the centre
  }
  return s;
}

DistanceSample signed_distance(const BodyMesh& body, const Eigen::Vector3d& x) {
  return signed_distance(body.closest_point(x), x);
}

DistanceSample signed_distance(const ClosestPoint& c, const Eigen::Vector3d& x) {
  DistanceSample s;
  if (c.face < 0) return s;
  s.distance = c.distance;
  const Eigen::Vector3d r = x - c.point;
  const double len = r.norm();
  if (c.face_interior || len < 1e-12) {
    s.gradient = c.normal;  // d = n·(x − p) is linear in x inside a face
  } else {
    const double sign = c.distance < 0 ? -1.0 : 1.0;
    const Eigen::Vector3d u = r / len;
    s.gradient = sign * u;
    // Curvature of the distance: none along an edge the closest point slides on.
    Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - u * u.transpose();
    if (c.on_edge) p -= c.edge_direction * c.edge_direction.transpose();
    s.hessian = sign * p / len;
  }
  return s;
}

CollisionEnergy::CollisionEnergy(int num_vertices, double thickness, double stiffness)
    : n_(num_vertices), thickness_(thickness), k_(stiffness) {
  WEFT_CHECK(thickness > 0, "collision: thickness must be > 0 m, got ", thickness);
  WEFT_CHECK(stiffness > 0, "collision: stiffness must be > 0 N/m, got ", stiffness);
}

void CollisionEnergy::set_second_sheet_angle(double degrees) {
  WEFT_CHECK(std::isfinite(degrees) && degrees >= 0 && degrees < 180,
             "collision: second_sheet_angle must be in [0, 180) degrees (0: off), got ", degrees);
  second_sheet_deg_ = degrees;
  second_sheet_cos_ = degrees > 0 ? std::cos(degrees * M_PI / 180.0) : 2.0;
}

void CollisionEnergy::set_bodies(std::vector<const BodyMesh*> bodies) {
  bodies_ = std::move(bodies);
  invalidate_cache();
}

void CollisionEnergy::invalidate_cache() {
  cache_.assign(bodies_.size(), std::vector<CacheEntry>(n_));
}

double CollisionEnergy::add_penalty(int i, const DistanceSample& s, Eigen::VectorXd* g,
                                    SparseHessian* H) const {
  if (!(s.distance < thickness_)) return 0.0;
  // E = k/(6δ)·gap³ with gap = δ − d: dE/dgap = k/(2δ)·gap², d²E/dgap² = k/δ·gap, and
  // ∂gap/∂x = −∇d.
  const double gap = thickness_ - s.distance;
  const double c = k_ / thickness_;
  const double de = 0.5 * c * gap * gap;
  if (g) g->segment<3>(3 * i) -= de * s.gradient;
  if (H) {
    Eigen::Matrix3d h = c * gap * (s.gradient * s.gradient.transpose()) - de * s.hessian;
    if (project_hessian_) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(h);
      h = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() *
          eig.eigenvectors().transpose();
    }
    H->add_diagonal_block(i, h);
  }
  return c / 6.0 * gap * gap * gap;
}

double CollisionEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                                 SparseHessian* H) const {
  double energy = 0;
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d xi = x.segment<3>(3 * i);
    for (const auto& sphere : spheres_) energy += add_penalty(i, signed_distance(sphere, xi), g, H);
    for (size_t b = 0; b < bodies_.size(); ++b) {
      CacheEntry& c = cache_[b][i];
      if (c.d_ref > thickness_ && (xi - c.x_ref).norm() < c.d_ref - thickness_) continue;
      const ClosestPoint cp = bodies_[b]->closest_point(xi);
      const DistanceSample s = signed_distance(cp, xi);
      c.x_ref = xi;
      c.d_ref = s.distance;
      energy += add_penalty(i, s, g, H);
      if (second_sheet_cos_ <= 1 && cp.face >= 0 && s.distance < thickness_) {
        const ClosestPoint other = bodies_[b]->closest_point_facing_away(
            xi, thickness_, bodies_[b]->face_normal(cp.face), second_sheet_cos_);
        if (other.face >= 0) energy += add_penalty(i, signed_distance(other, xi), g, H);
      }
    }
  }
  return energy;
}

void CollisionEnergy::limit_vertex_steps(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                         Eigen::VectorXd& limits) const {
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d xi = x.segment<3>(3 * i), step = dx.segment<3>(3 * i);
    double& alpha = limits[i];
    auto limit = [&](const DistanceSample& s) {
      // Inside the band the penalty's own Hessian already shapes the Newton step.
      if (!(s.distance >= thickness_)) return;
      const double target = 0.5 * thickness_;
      const double approach = -s.gradient.dot(step);
      if (approach > 0 && s.distance - approach < target)
        alpha = std::min(alpha, (s.distance - target) / approach);
    };
    const double reach = step.norm();
    for (const auto& sphere : spheres_) limit(signed_distance(sphere, xi));
    for (size_t b = 0; b < bodies_.size(); ++b) {
      CacheEntry& c = cache_[b][i];
      // 1-Lipschitz: a vertex that cannot get within ½δ of the body needs no query.
      if (c.d_ref - (xi - c.x_ref).norm() - reach >= 0.5 * thickness_) continue;
      const DistanceSample s = signed_distance(*bodies_[b], xi);
      c.x_ref = xi;
      c.d_ref = s.distance;
      limit(s);
    }
  }
}

double CollisionEnergy::min_signed_distance(const Eigen::Vector3d& x) const {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& sphere : spheres_) d = std::min(d, signed_distance(sphere, x).distance);
  for (const BodyMesh* body : bodies_) d = std::min(d, signed_distance(*body, x).distance);
  return d;
}

}  // namespace weft::physics
