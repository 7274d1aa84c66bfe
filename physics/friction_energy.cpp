#include "physics/friction_energy.h"

#include <cmath>

#include "graph/error.h"

namespace weft::physics {

namespace {

// Orthonormal basis of the plane ⊥ n (n unit): the columns of a 3×2 matrix.
Eigen::Matrix<double, 3, 2> tangent_basis(const Eigen::Vector3d& n) {
  // Cross with the axis least aligned with n: never close to parallel.
  Eigen::Index k;
  n.cwiseAbs().minCoeff(&k);
  const Eigen::Vector3d t1 = n.cross(Eigen::Vector3d::Unit(k)).normalized();
  Eigen::Matrix<double, 3, 2> T;
  T.col(0) = t1;
  T.col(1) = n.cross(t1);
  return T;
}

// Barycentric coordinates of p (on the triangle's plane) in triangle (a, b, c); uniform
// thirds for a degenerate triangle.
Eigen::Vector3d barycentric(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                            const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e0 = b - a, e1 = c - a, r = p - a;
  const double d00 = e0.dot(e0), d01 = e0.dot(e1), d11 = e1.dot(e1);
  const double d20 = r.dot(e0), d21 = r.dot(e1);
  const double det = d00 * d11 - d01 * d01;
  if (!(std::abs(det) > 1e-30)) return Eigen::Vector3d::Constant(1.0 / 3.0);
  const double v = (d11 * d20 - d01 * d21) / det, w = (d00 * d21 - d01 * d20) / det;
  return Eigen::Vector3d(1.0 - v - w, v, w);
}

// A vertex in the collision band at the step's start is a contact with a normal force.
// One inside the obstacle is not: it is a start state the penalty is pushing out (a
// perturbed or predicted window start, or after a failed step), and its penalty force,
// thousands of times the vertex's weight, is no friction bound: friction from such
// starts held windows at the iteration cap. It gets friction once it is back in the band.
bool in_contact(double distance, double band) { return distance >= 0 && distance < band; }

}  // namespace

FrictionEnergy::FrictionEnergy(int num_vertices, const CollisionEnergy& collision,
                               double velocity_threshold, double time_step)
    : n_(num_vertices), collision_(collision), velocity_threshold_(velocity_threshold) {
  WEFT_CHECK(std::isfinite(velocity_threshold) && velocity_threshold > 0,
             "friction: velocity threshold must be > 0 m/s, got ", velocity_threshold);
  set_time_step(time_step);
}

void FrictionEnergy::set_time_step(double h) {
  WEFT_CHECK(std::isfinite(h) && h > 0, "friction: time step must be > 0 s, got ", h);
  h_ = h;
}

void FrictionEnergy::set_body_friction(std::vector<double> mu) {
  for (double m : mu)
    WEFT_CHECK(std::isfinite(m) && m >= 0, "friction: coefficient must be >= 0, got ", m);
  body_friction_ = std::move(mu);
}

void FrictionEnergy::add_contact(int i, const Eigen::Vector3d& x, const DistanceSample& s,
                                 double mu, const Eigen::Vector3d& motion) {
  const double lambda = collision_.normal_force(s.distance);
  if (!(mu > 0 && lambda > 0)) return;
  contacts_.push_back({i, mu * lambda, tangent_basis(s.gradient), x, motion});
}

void FrictionEnergy::lag(const Eigen::VectorXd& x_start, double body_motion_scale) {
  WEFT_CHECK(x_start.size() == 3 * n_, "friction: state has ", x_start.size(),
             " entries, expected ", 3 * n_);
  const auto& bodies = collision_.bodies();
  WEFT_CHECK(body_friction_.size() == bodies.size(), "friction: ", body_friction_.size(),
             " body coefficients for ", bodies.size(), " bodies");
  contacts_.clear();
  const double delta = collision_.thickness();
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d xi = x_start.segment<3>(3 * i);
    for (const auto& sphere : collision_.spheres()) {
      if (!(sphere.friction > 0)) continue;
      const DistanceSample s = signed_distance(sphere, xi);
      if (in_contact(s.distance, delta)) add_contact(i, xi, s, sphere.friction, Eigen::Vector3d::Zero());
    }
    for (size_t b = 0; b < bodies.size(); ++b) {
      if (!(body_friction_[b] > 0)) continue;
      const BodyMesh& body = *bodies[b];
      // The body has already moved to the step's end: query it there (within reach of the
      // band plus its motion), then take the distance back to the step's start.
      const ClosestPoint c = body.closest_point(xi);
      if (c.face < 0) continue;
      DistanceSample s = signed_distance(c, xi);
      // The surface point under the vertex moved with its face: barycentric weights of the
      // closest point on the face now, applied to the face vertices' displacement.
      const auto& f = body.faces()[c.face];
      const Eigen::MatrixX3d& v = body.vertices();
      const Eigen::MatrixX3d& v0 = body.previous_vertices();
      const Eigen::Vector3d w = barycentric(c.point, v.row(f[0]).transpose(),
                                            v.row(f[1]).transpose(), v.row(f[2]).transpose());
      Eigen::Vector3d motion = Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) motion += w[k] * (v.row(f[k]) - v0.row(f[k])).transpose();
      motion *= body_motion_scale;
      // Lagged means at the start of the step: the normal force of x_n against the body as
      // it was then. The surface has since moved by `motion`, so x_n's distance then was
      // d_now + n·motion. Against the moved body instead, a body stepping into the cloth
      // put x_n centimetres deep, and its penalty force (hundreds of newtons against a
      // weight of 1e-4 N) became the friction bound: the skirt on the walking body then
      // stalled at the iteration cap from the first frame.
      s.distance += s.gradient.dot(motion);
      if (!in_contact(s.distance, delta)) continue;
      add_contact(i, xi, s, body_friction_[b], motion);
    }
  }
}

double FrictionEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                                SparseHessian* H) const {
  const double eps = smoothing();
  const double inv_eps = 1.0 / eps, inv_eps2 = inv_eps * inv_eps;
  double energy = 0;
  for (const Contact& c : contacts_) {
    const Eigen::Vector3d slip = x.segment<3>(3 * c.vertex) - c.x_start - c.motion;
    const Eigen::Vector2d u = c.T.transpose() * slip;
    const double y = u.norm();
    // f0(y), f1(y)/y and the 2×2 Hessian of f0(‖u‖) in u.
    double f0, f1_over_y;
    Eigen::Matrix2d hu;
    if (y < eps) {
      f0 = y * y * (inv_eps - y * inv_eps2 / 3.0) + eps / 3.0;
      f1_over_y = 2.0 * inv_eps - y * inv_eps2;  // finite at y = 0: no division
      // (f1'y − f1)/y³ = −1/(ε² y), so the uuᵀ term is −uuᵀ/(ε² y), bounded by y/ε².
      hu = f1_over_y * Eigen::Matrix2d::Identity();
      if (y > 0) hu -= (inv_eps2 / y) * (u * u.transpose());
    } else {
      f0 = y;
      f1_over_y = 1.0 / y;
      hu = (Eigen::Matrix2d::Identity() - u * u.transpose() / (y * y)) / y;
    }
    energy += c.weight * f0;
    if (g) g->segment<3>(3 * c.vertex) += (c.weight * f1_over_y) * (c.T * u);
    if (H) H->add_diagonal_block(c.vertex, c.weight * (c.T * hu * c.T.transpose()));
  }
  return energy;
}

void FrictionEnergy::follow_obstacles(Eigen::VectorXd& dx) const {
  for (const Contact& c : contacts_) {
    const Eigen::Vector3d n = c.T.col(0).cross(c.T.col(1));  // outward normal at the step's start
    auto move = dx.segment<3>(3 * c.vertex);
    const double inertial = n.dot(move), body = n.dot(c.motion);  // m along n
    move += (std::max(inertial, body) - inertial) * n;
  }
}

void FrictionEnergy::limit_vertex_steps(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                        Eigen::VectorXd& limits) const {
  const double eps = smoothing();
  for (const Contact& c : contacts_) {
    const Eigen::Vector2d u0 = c.T.transpose() * (x.segment<3>(3 * c.vertex) - c.x_start - c.motion);
    if (!(u0.norm() > eps)) continue;  // already in the smooth regime
    const Eigen::Vector2d du = c.T.transpose() * dx.segment<3>(3 * c.vertex);
    if (!(u0.dot(u0 + du) < 0)) continue;  // no reversal along this move
    // u0 + t·du is closest to zero at t* = −u0·du/‖du‖² (in (0, 1) for a reversal).
    const double t = -u0.dot(du) / du.squaredNorm();
    if (t > 0 && t < limits[c.vertex]) limits[c.vertex] = t;
  }
}

}  // namespace weft::physics
