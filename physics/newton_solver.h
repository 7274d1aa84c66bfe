#pragma once
// Minimises a sum of energies by Newton's method: a fixed-pattern sparse Hessian, a
// CHOLMOD solve (symbolic analysis once), the exact Hessian's Newton direction reached by
// CG preconditioned with the factor of the PSD-corrected Hessian (the energies'
// Energy::add_hessian_correction; truncated where the exact Hessian has negative
// curvature), then adaptive regularisation H + δI (δ grows when
// the factorisation fails, the direction is not a descent direction or the line search
// fails, and shrinks after a success); a step filter (Energy::max_step), an Armijo
// back-tracking line search, then a search along CG's direction of negative curvature
// when it met one. Converged when every
// vertex's residual is below the tolerance relative to its force scale. The solver never
// leaves x non-finite: a failed iteration keeps the last accepted iterate, which has the
// lowest energy reached.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "physics/cholmod_solver.h"
#include "physics/energy.h"
#include "physics/sparse_hessian.h"

namespace weft::physics {

enum class StepStatus { converged, max_iterations, line_search_failed, non_finite };
const char* to_string(StepStatus status);

enum class LinearSolverKind {
  direct,         // a fresh Cholesky factorisation every Newton iteration (of the
                  // corrected Hessian; see precondition_exact_hessian)
  reused_factor,  // CG on the current Hessian, preconditioned by the last factorisation;
                  // refactorised when CG needs more than cg_max_iterations
};

struct NewtonOptions {
  int max_iterations = 50;
  // Converged when every vertex's force residual is small next to its force scale:
  //   max_i ‖∇_i E‖ / f_i ≤ tolerance,
  // f_i from set_force_scale (the cloth simulator uses the vertex weight m_i·g₀, so the
  // tolerance bounds the out-of-balance force as a fraction of each vertex's weight);
  // f_i = 1 N when unset, and the tolerance is then in newtons.
  double tolerance = 1e-3;
  double armijo = 1e-4;        // sufficient-decrease constant
  int max_backtracks = 40;
  LinearSolverKind linear_solver = LinearSolverKind::direct;
  CholeskyKind cholesky = CholeskyKind::automatic;  // CHOLMOD's choice by flop count
  // Nested dissection by METIS: 16 % fewer flops per factorisation than AMD at 4k
  // vertices, 28 % at 16k (drape); deterministic (see CholmodSolver).
  CholeskyOrdering ordering = CholeskyOrdering::metis;
  SupernodeAmalgamation amalgamation;
  // direct: factorise the PSD-corrected Hessian and reach the exact Newton direction by
  // CG preconditioned with that factor (truncated at negative curvature), instead of
  // trying to factorise the exact Hessian first (which failed in most contact iterations).
  // Measured on the 4k drape: 28 Newton iterations and 28 factorisations per frame
  // instead of 39 and 74 (docs/BENCHMARKS.md).
  bool precondition_exact_hessian = true;
  // direct: factorise, instead of the corrected Hessian itself, its upper bound on the
  // pattern without the energies' weak pairs (Energy::add_weak_pairs: the vertices
  // opposite across a bending hinge; SparseHessian::bound_into), and reach the Newton
  // direction by CG preconditioned with that factor. The hinges' cross coupling widens
  // the separators of nested dissection: on the 64×64 grid, 3.2e8 flops and 1.51e6
  // nonzeros per factorisation with it, 7.0e7 and 6.1e5 without.
  bool factor_without_weak_pairs = true;
  int cg_max_iterations = 25;
  // CG's stop, the residual relative to ‖∇E‖: an inexact Newton direction. Convergence is
  // still judged by the force residual above. 1e-2 instead of 1e-4 (issue 41): the same
  // Newton iterations within ±8 %, 2.4–3× fewer CG iterations (4k drape 230 → 97 per frame,
  // 3k skirt 530 → 197), 0.70–0.81× the CPU time (docs/BENCHMARKS.md).
  double cg_relative_tolerance = 1e-2;
  // With adaptive_cg_tolerance, CG's stop per Newton iteration follows how well the last
  // step's linear model predicted the new gradient (Eisenstat and Walker 1996, choice 1:
  // η = |‖∇E_k‖ − ‖∇E_{k−1} + H s‖| / ‖∇E_{k−1}‖, safeguarded by η_{k−1}^φ), kept within
  // [cg_min_relative_tolerance, cg_relative_tolerance]: loose where Newton's model is poor
  // (contact, buckling), tight where it is good, so the end of a solve converges as with
  // an exact direction; a step that has used half of max_iterations gets the tight stop.
  // A fixed 1e-2 left two steps of the 16k drape at the cap of 50.
  bool adaptive_cg_tolerance = true;
  double cg_min_relative_tolerance = 1e-4;
  // direct: when CG stopped at non-positive curvature, also search along that direction
  // from the accepted point (energy evaluations only; see search_negative_curvature).
  bool negative_curvature_search = true;
  // The step filter per vertex instead of over the whole step: each vertex's move is cut
  // by the energies in turn (Energy::clip_vertex_steps: its approach to an obstacle's
  // closest-point plane to half the collision thickness from it, a friction slip
  // reversal) and the line search starts from the full, so limited, step; one vertex near
  // a leg no longer holds back the whole garment. Falls back to the global filter (the
  // smallest limit for every vertex) when the limited move is not a descent direction.
  // On by default (issue 41, decision 1; weft synth already had it): with the whole move
  // scaled, on the 4k drape 77 → 47 Newton iterations in the worst frame, on the 1k skirt
  // 95 → 73 per frame (docs/notes/2026-12-06-contact-crawl-levers.md).
  bool per_vertex_step_limits = true;
  // With per_vertex_step_limits: when the filter cut some vertices' moves, the rest of the
  // direction is solved again with those cuts held, instead of being left as if the cut
  // vertices had moved in full. The part the filter removed from each cut vertex's move
  // fixes that vertex's move along it; the other components minimise Newton's quadratic
  // model by projected CG (preconditioned with this iteration's factor, at most
  // cg_max_iterations, to 1e-2 of the projected residual), from the cut direction, so the
  // model falls at least as far as with the cut direction alone. Without it a vertex
  // stopped at an obstacle stretched the cloth toward its freely moving neighbours, and
  // the next iterations spent themselves undoing that (issue 41: Newton iterations per
  // frame, 4k drape 23.2 → 21.3, 1k skirt 38.5 → 29.2, 3k skirt 51.0 → 39.8; 40 perturbed
  // 448-vertex windows 92 → 78 per window, docs/notes/2026-12-07-contact-starts-and-known-side.md).
  bool refine_limited_steps = true;
};

struct NewtonReport {
  StepStatus status = StepStatus::max_iterations;
  int iterations = 0;
  double gradient_norm = 0;   // ‖∇E‖∞ at the returned x, N
  double residual = 0;        // max_i ‖∇_i E‖ / f_i at the returned x (see tolerance)
  double energy = 0;          // J
  int factorizations = 0;
  int corrections = 0;        // iterations that fell back to PSD-projected element Hessians
  int cg_iterations = 0;
  int curvature_steps = 0;    // iterations that also moved along negative curvature
  double regularization = 0;  // δ after the step, N/m
  std::vector<double> accepted_energies;  // E after each accepted iteration (first: start)
  // The residual (as `residual`) at the start and after each accepted iteration, and the
  // wall time since minimize() began when each was known (ms): the time the step would
  // have taken to a looser tolerance along the same path.
  std::vector<double> residual_history;
  std::vector<double> residual_ms;
  // Wall time split, milliseconds: energies' evaluate (by energy, values and derivatives),
  // numeric factorisation + solves, everything.
  std::vector<double> energy_ms;
  double linear_solve_ms = 0;
  double total_ms = 0;
};

class NewtonSolver {
 public:
  // Energies are not owned and must outlive the solver.
  NewtonSolver(int num_vertices, std::vector<Energy*> energies, NewtonOptions options = {});
  NewtonReport minimize(Eigen::VectorXd& x);
  // Per-vertex force scales f_i (N, > 0) of the convergence test; see NewtonOptions.
  void set_force_scale(Eigen::VectorXd per_vertex);
  // max_i ‖g_i‖ / f_i.
  double residual(const Eigen::VectorXd& g) const;

  double energy(const Eigen::VectorXd& x) const;
  // Returns E and writes ∇E.
  double gradient(const Eigen::VectorXd& x, Eigen::VectorXd& g) const;
  // The projected Hessian at x (for tests).
  const SparseHessian& hessian(const Eigen::VectorXd& x);

  NewtonOptions& options() { return options_; }
  const CholmodSolver& cholmod() const { return *cholmod_; }
  const std::vector<Energy*>& energies() const { return energies_; }
  // The step filter: the largest α ≤ 1 that every energy admits for x + α·dx
  // (Energy::max_step).
  double max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx) const;
  // The per-vertex filter: each energy's Energy::clip_vertex_steps applied to dx in turn.
  void clip_vertex_steps(const Eigen::VectorXd& x, Eigen::VectorXd& dx) const;

 private:
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* h,
                  std::vector<double>* ms) const;
  // Direction d with (H + δI) d = −g; false if no descent direction was found.
  bool direction(const Eigen::VectorXd& x, const Eigen::VectorXd& g, Eigen::VectorXd& d,
                 NewtonReport& report);
  enum class CgOutcome { converged, negative_curvature, too_slow };
  CgOutcome preconditioned_cg(const SparseHessian& H, const Eigen::VectorXd& g, Eigen::VectorXd& d,
                              NewtonReport& report);
  // A vertex's move component held fixed: vertex index and unit direction.
  using HeldComponent = std::pair<int, Eigen::Vector3d>;
  // v projected onto the moves that keep the `held` components.
  static void project_onto_held(const std::vector<HeldComponent>& held, Eigen::VectorXd& v);
  // PCG on (H + δI) from d with residual r (both updated), preconditioned by the current
  // factor, every vector projected onto the moves that keep the `held` components (none:
  // plain PCG), until ‖r‖ ≤ target or cg_max_iterations; on non-positive curvature the
  // direction met is written to *curvature_direction (if given).
  CgOutcome projected_cg(const SparseHessian& H, Eigen::VectorXd& r, Eigen::VectorXd& d, double target,
                         const std::vector<HeldComponent>& held, Eigen::VectorXd* curvature_direction,
                         NewtonReport& report);
  // refine_limited_steps: `limited` (the filter's cut of d) replaced by the minimiser of
  // Newton's model with each cut vertex's move along its cut held; kept as it is when the
  // result is not a descent direction.
  void refine_limited_direction(const Eigen::VectorXd& x, const Eigen::VectorXd& g, const Eigen::VectorXd& d,
                                Eigen::VectorXd& limited, NewtonReport& report);
  // Truncated PCG on the exact Hessian with the corrected Hessian's factor (see direct).
  void exact_direction(const SparseHessian& H, const Eigen::VectorXd& g, Eigen::VectorXd& d,
                       NewtonReport& report);
  // Adds the energies' PSD corrections to the current Hessian (once per assembly); false
  // if it was corrected already or no energy has a correction.
  bool correct_hessian(const Eigen::VectorXd& x, NewtonReport& report);
  // Moves x_new (energy e_new) along CG's direction of non-positive curvature if the
  // energy falls there; returns the largest vertex move it added (m; 0 if none).
  double search_negative_curvature(const Eigen::VectorXd& g, double reach,
                                   Eigen::VectorXd& x_new, double& e_new, Eigen::VectorXd& x_trial,
                                   NewtonReport& report) const;
  struct IterationTrace {
    double filter = 1.0;       // the step filter's cap on α
    int limited_vertices = 0;  // per-vertex filter: vertices whose move was cut
    int backtracks = 0;
    double curvature_step = 0;  // m, from search_negative_curvature
    int cg_before = 0;
  };
  void print_trace(int it, const Eigen::VectorXd& x, const Eigen::VectorXd& g, double e,
                   const Eigen::VectorXd& x_new, const Eigen::VectorXd& d, double alpha,
                   const IterationTrace& t, const NewtonReport& report) const;

  int n_;
  std::vector<Energy*> energies_;
  NewtonOptions options_;
  Eigen::VectorXd inv_force_scale_;  // 1/f_i, n entries
  SparseHessian hessian_;
  SparseHessian coarse_;  // factor_without_weak_pairs: the factorised bound (else empty)
  std::unique_ptr<CholmodSolver> cholmod_;
  double delta_ = 0;
  double cg_forcing_ = 0;  // this iteration's CG stop relative to ‖∇E‖ (0: the option's)
  double delta_floor_ = 0;
  bool factor_stale_ = true;  // the reused factor must be refreshed before use
  bool hessian_corrected_ = false;  // hessian_ holds the corrections of this iteration
  SparseHessian exact_hessian_;     // the uncorrected Hessian of this iteration
  bool exact_differs_ = false;      // the corrections changed hessian_ from exact_hessian_
  CgOutcome last_cg_outcome_ = CgOutcome::converged;  // of this iteration's exact_direction
  Eigen::VectorXd negative_direction_;   // CG's direction of non-positive curvature
};

}  // namespace weft::physics
