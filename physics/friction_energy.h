#pragma once
// Coulomb friction between cloth vertices and obstacles as a lagged, smoothed dissipative
// potential in the incremental potential (IPC's lagged friction: Li et al. 2020,
// "Incremental Potential Contact", §5). At the start of each step (begin_step, x_start)
// every vertex i within the collision band of an obstacle becomes a contact with
//   λ   the collision penalty's normal force there, k/(2δ)(δ − d)² (N),
//   T   a 3×2 orthonormal basis of the tangent plane ⊥ ∇d,
//   μ   the obstacle's friction coefficient,
//   Δo  the obstacle's displacement over the step at the contact point (m; 0 if static).
// All four stay fixed during the step; the energy is
//   D(x) = Σ μ λ f0(‖u‖),   u = Tᵀ((x_i − x_start,i) − Δo)   (tangential slip, m)
// with IPC's C² smoothing of ‖u‖: f0(y) = −y³/(3ε²) + y²/ε + ε/3 for y < ε, y beyond,
// ε = ε_v·h (ε_v a slip-velocity threshold, m/s; h the step, s). Its force −∇D has
// magnitude μλ·f0'(‖u‖): exactly μλ when the vertex slips faster than ε_v against the
// obstacle (kinetic friction), falling linearly to 0 at no slip (static friction becomes a
// stiff viscous force 2μλ/ε per metre of slip, so a stuck vertex creeps at < ε_v).
// Its Hessian μλ T[(f1'y − f1)/y³ uuᵀ + f1/y I₂]Tᵀ (f1 = f0') is PSD in both regimes
// (eigenvalues 2/ε − 2y/ε² and 2/ε − y/ε² below ε; 0 and 1/y beyond), so needs no
// projection. Friction is dissipative: it is not part of ClothSimulator::total_force.
#include <vector>

#include "physics/collision_energy.h"
#include "physics/energy.h"

namespace weft::physics {

class FrictionEnergy : public Energy {
 public:
  // collision: the obstacles with their band δ and stiffness k (non-owning; must outlive
  // the energy). velocity_threshold: ε_v in m/s. time_step: h in s.
  FrictionEnergy(int num_vertices, const CollisionEnergy& collision, double velocity_threshold,
                 double time_step);
  void set_time_step(double h);
  // μ of each body of the collision energy, in its order (spheres carry their own).
  void set_body_friction(std::vector<double> mu);
  const std::vector<double>& body_friction() const { return body_friction_; }

  std::string name() const override { return "friction"; }
  void begin_step(const Eigen::VectorXd& x_start) override { lag(x_start); }
  // Records the contacts at x_start (see above). The bodies' displacement over the step is
  // vertices() − previous_vertices(), times body_motion_scale (e.g. the number of
  // sub-steps, for a frame whose sub-steps moved the body linearly).
  void lag(const Eigen::VectorXd& x_start, double body_motion_scale = 1.0);
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;
  // Slip-reversal clamp: a contact slipping faster than ε whose move dx_i would carry its
  // slip u through zero (u at x and at x + dx_i pointing apart) may go only as far as the
  // point of the move closest to zero slip. Past it the force flips by 2μλ across a kink
  // only ε wide; stopping there leaves the vertex in the smooth static regime, where the
  // next Newton step sees the right curvature, instead of an overshoot the global line
  // search pays for on every vertex.
  void limit_vertex_steps(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                          Eigen::VectorXd& limits) const override;
  // The clamp is a per-vertex device only: as a cap on the whole step it would stop the
  // whole garment at one vertex's reversal.
  double max_step(const Eigen::VectorXd&, const Eigen::VectorXd&) const override { return 1.0; }

  // A warm start that follows the obstacles (SimulationSettings::start_following_body):
  // replaces each contact vertex's move dx_i (m, over the step) by its tangential part
  // plus the normal part of its obstacle point's displacement Δo, so a vertex on a body
  // that pushes into the cloth starts where the body carries it instead of where its
  // old velocity would (a body pulling away leaves it at its inertial move's normal part
  // if that is larger: never into the body further than before).
  void follow_obstacles(Eigen::VectorXd& dx) const;
  int num_contacts() const { return static_cast<int>(contacts_.size()); }
  double smoothing() const { return velocity_threshold_ * h_; }  // ε, m

 private:
  struct Contact {
    int vertex;
    double weight;                  // μλ, N
    Eigen::Matrix<double, 3, 2> T;  // tangent basis
    Eigen::Vector3d x_start;        // vertex position at the step's start, m
    Eigen::Vector3d motion;         // obstacle displacement at the contact point, m
  };
  void add_contact(int i, const Eigen::Vector3d& x, const DistanceSample& s, double mu,
                   const Eigen::Vector3d& motion);

  int n_;
  const CollisionEnergy& collision_;
  double velocity_threshold_, h_;
  std::vector<double> body_friction_;
  std::vector<Contact> contacts_;
};

}  // namespace weft::physics
