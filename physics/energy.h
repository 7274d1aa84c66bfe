#pragma once
// One term of the incremental potential. Each energy computes its value and, when asked,
// adds its gradient and its (per-element positive semi-definite) Hessian; the Newton
// solver only sums energies. Positions are 3n vectors in metres; energies in joules.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "physics/sparse_hessian.h"

namespace weft::physics {

class Energy {
 public:
  virtual ~Energy() = default;
  virtual std::string name() const = 0;
  // Returns E(x); adds ∇E(x) to *gradient and the projected Hessian to *hessian when
  // they are not null.
  virtual double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient,
                          SparseHessian* hessian) const = 0;
  // Vertex pairs this energy couples (off-diagonal blocks of its Hessian).
  virtual void add_pattern(std::vector<std::array<int, 2>>& pairs) const { (void)pairs; }
  // Of those, the pairs coupled only weakly and by nothing else (the vertices opposite
  // across a bending hinge), which a preconditioner may drop
  // (NewtonOptions::factor_without_weak_pairs).
  virtual void add_weak_pairs(std::vector<std::array<int, 2>>& pairs) const { (void)pairs; }
  // Adds a PSD matrix C such that the energy's exact Hessian plus C is PSD, for energies
  // whose exact Hessian (projection off) can be indefinite; returns false if it added
  // nothing (no correction, or none needed at x). The Newton solver factorises the
  // corrected Hessian and uses it to precondition CG on the exact one.
  virtual bool add_hessian_correction(const Eigen::VectorXd& x, SparseHessian& c) const {
    (void)x;
    (void)c;
    return false;
  }
  // Called by the Newton solver once the Hessian H at x is assembled, with the total
  // gradient g at x (all energies): an energy may replace part of its own Hessian in H by
  // a stiffness that models its nonlinearity better along the step Newton is about to take
  // (the collision's secant stiffness, CollisionEnergy::set_secant_stiffness). What it
  // leaves in H must stay positive semi-definite where its own part was.
  virtual void adjust_hessian(const Eigen::VectorXd& x, const Eigen::VectorXd& g, SparseHessian& H) const {
    (void)x;
    (void)g;
    (void)H;
  }
  // Per-vertex step limits: lowers limits[i] (n entries, in (0, 1]) to the largest
  // fraction of its own move dx_i that vertex i may take from x (e.g. not closer than
  // half the collision thickness to an obstacle, not past a friction slip reversal).
  // Leaves limits unchanged where this energy does not restrict the step.
  virtual void limit_vertex_steps(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                  Eigen::VectorXd& limits) const {
    (void)x;
    (void)dx;
    (void)limits;
  }
  // The per-vertex step filter (NewtonOptions::per_vertex_step_limits): replaces each
  // vertex's move dx_i (m) by the part of it this energy admits from x. By default the
  // move is scaled by limit_vertex_steps' fraction; an energy whose bound is a half-space
  // (the collision's closest-point plane) instead clips only the component that crosses
  // it. The solver applies the energies in turn, each to what the previous ones left.
  virtual void clip_vertex_steps(const Eigen::VectorXd& x, Eigen::VectorXd& dx) const {
    Eigen::VectorXd limits = Eigen::VectorXd::Ones(x.size() / 3);
    limit_vertex_steps(x, dx, limits);
    for (Eigen::Index i = 0; i < limits.size(); ++i)
      if (limits[i] < 1.0) dx.segment<3>(3 * i) *= limits[i] > 0.0 ? limits[i] : 0.0;
  }
  // The largest α in (0, 1] this energy lets the whole step x + α·dx take: the smallest
  // of its per-vertex limits (a filter applied before the line search).
  virtual double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const {
    Eigen::VectorXd limits = Eigen::VectorXd::Ones(x.size() / 3);
    limit_vertex_steps(x, dx, limits);
    return limits.size() > 0 ? limits.minCoeff() : 1.0;
  }
  // What this energy sees at vertex i (for WEFT_NEWTON_TRACE, which prints it for the
  // vertex with the largest residual): e.g. the collision's closest face and feature.
  // Empty when there is nothing to say.
  virtual std::string describe_vertex(const Eigen::VectorXd& x, int i) const {
    (void)x;
    (void)i;
    return {};
  }
  // Called once at the start of each time step, before any evaluate().
  virtual void begin_step(const Eigen::VectorXd& x_start) { (void)x_start; }
  // Element Hessians are projected to PSD unless this is switched off (for checking the
  // exact Hessian against finite differences).
  void set_hessian_projection(bool on) { project_hessian_ = on; }

 protected:
  bool project_hessian_ = true;
};

}  // namespace weft::physics
