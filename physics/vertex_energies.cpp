#include "physics/vertex_energies.h"

#include "graph/error.h"

namespace weft::physics {

InertiaEnergy::InertiaEnergy(Eigen::VectorXd mass, double time_step)
    : mass_(std::move(mass)), x_hat_(Eigen::VectorXd::Zero(3 * mass_.size())), h_(time_step) {
  WEFT_CHECK(time_step > 0, "inertia: time step must be > 0 s, got ", time_step);
}

double InertiaEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                               SparseHessian* H) const {
  const double inv_h2 = 1.0 / (h_ * h_);
  double e = 0;
  for (int i = 0; i < mass_.size(); ++i) {
    const Eigen::Vector3d d = x.segment<3>(3 * i) - x_hat_.segment<3>(3 * i);
    const double w = mass_[i] * inv_h2;
    e += 0.5 * w * d.squaredNorm();
    if (g) g->segment<3>(3 * i) += w * d;
    if (H) H->add_diagonal_block(i, w * Eigen::Matrix3d::Identity());
  }
  return e;
}

GravityEnergy::GravityEnergy(Eigen::VectorXd mass, const Eigen::Vector3d& gravity)
    : mass_(std::move(mass)), gravity_(gravity) {}

double GravityEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                               SparseHessian*) const {
  double e = 0;
  for (int i = 0; i < mass_.size(); ++i) {
    e -= mass_[i] * gravity_.dot(x.segment<3>(3 * i));
    if (g) g->segment<3>(3 * i) -= mass_[i] * gravity_;
  }
  return e;
}

PinEnergy::PinEnergy(std::vector<int> vertices, std::vector<Eigen::Vector3d> targets,
                     double stiffness)
    : vertices_(std::move(vertices)), k_(stiffness) {
  WEFT_CHECK(stiffness > 0, "pins: stiffness must be > 0 N/m, got ", stiffness);
  set_targets(std::move(targets));
}

void PinEnergy::set_targets(std::vector<Eigen::Vector3d> targets) {
  WEFT_CHECK(targets.size() == vertices_.size(), "pins: ", vertices_.size(), " vertices but ",
             targets.size(), " targets");
  targets_ = std::move(targets);
}

double PinEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const {
  double e = 0;
  for (size_t p = 0; p < vertices_.size(); ++p) {
    const int i = vertices_[p];
    const Eigen::Vector3d d = x.segment<3>(3 * i) - targets_[p];
    e += 0.5 * k_ * d.squaredNorm();
    if (g) g->segment<3>(3 * i) += k_ * d;
    if (H) H->add_diagonal_block(i, k_ * Eigen::Matrix3d::Identity());
  }
  return e;
}

RayConstraintEnergy::RayConstraintEnergy(std::vector<RayTarget> targets, double stiffness)
    : targets_(std::move(targets)), k_(stiffness) {
  WEFT_CHECK(stiffness >= 0, "ray constraint: stiffness must be >= 0 N/m, got ", stiffness);
  for (auto& t : targets_) {
    const double len = t.direction.norm();
    WEFT_CHECK(len > 0 && std::isfinite(len), "ray constraint: vertex ", t.vertex,
               " has a zero or non-finite ray direction");
    t.direction /= len;
  }
}

double RayConstraintEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                                     SparseHessian* H) const {
  double e = 0;
  for (const auto& t : targets_) {
    const Eigen::Matrix3d P = Eigen::Matrix3d::Identity() - t.direction * t.direction.transpose();
    const Eigen::Vector3d r = P * (x.segment<3>(3 * t.vertex) - t.origin);
    e += 0.5 * k_ * r.squaredNorm();
    if (g) g->segment<3>(3 * t.vertex) += k_ * r;  // Pᵀ P = P
    if (H) H->add_diagonal_block(t.vertex, k_ * P);
  }
  return e;
}

}  // namespace weft::physics
