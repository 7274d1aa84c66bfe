#pragma once
// Energies that act on single vertices: implicit-Euler inertia, gravity, soft pins and
// the silhouette constraint E_cons (pull toward 3D rays). Their Hessians are 3×3
// diagonal blocks, so they add nothing to the sparsity pattern.
#include <vector>

#include "physics/energy.h"

namespace weft::physics {

// ½ (x − x̂)ᵀ M (x − x̂) / h², x̂ = x_n + h v_n (the predicted position), M lumped masses.
class InertiaEnergy : public Energy {
 public:
  InertiaEnergy(Eigen::VectorXd mass, double time_step);
  void set_prediction(const Eigen::VectorXd& x_hat) { x_hat_ = x_hat; }
  void set_time_step(double h) { h_ = h; }
  const Eigen::VectorXd& prediction() const { return x_hat_; }
  std::string name() const override { return "inertia"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;

 private:
  Eigen::VectorXd mass_;
  Eigen::VectorXd x_hat_;
  double h_;
};

// −Σ m_i g·x_i, g the gravitational acceleration in m/s².
class GravityEnergy : public Energy {
 public:
  GravityEnergy(Eigen::VectorXd mass, const Eigen::Vector3d& gravity);
  std::string name() const override { return "gravity"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;

 private:
  Eigen::VectorXd mass_;
  Eigen::Vector3d gravity_;
};

// Soft pins / attachments: ½ k Σ ‖x_i − target_i‖², k in N/m.
class PinEnergy : public Energy {
 public:
  PinEnergy(std::vector<int> vertices, std::vector<Eigen::Vector3d> targets, double stiffness);
  void set_targets(std::vector<Eigen::Vector3d> targets);
  const std::vector<int>& vertices() const { return vertices_; }
  std::string name() const override { return "pins"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;

 private:
  std::vector<int> vertices_;
  std::vector<Eigen::Vector3d> targets_;
  double k_;
};

// The silhouette constraint E_cons: ½ k Σ ‖(I − d dᵀ)(x_i − o_i)‖², the squared distance
// of vertex i to the line through o_i with unit direction d_i (a camera ray through a
// silhouette pixel), k in N/m.
struct RayTarget {
  int vertex;
  Eigen::Vector3d origin;
  Eigen::Vector3d direction;  // normalised on construction
};

class RayConstraintEnergy : public Energy {
 public:
  RayConstraintEnergy(std::vector<RayTarget> targets, double stiffness);
  std::string name() const override { return "ray_constraint"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;

 private:
  std::vector<RayTarget> targets_;
  double k_;
};

}  // namespace weft::physics
