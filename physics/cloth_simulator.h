#pragma once
// One cloth with its obstacles, advanced by fully implicit Euler: each step minimises
//   E(x) = 1/(2h²)‖x − x_n − h v_n‖²_M + W_membrane + W_bend − f_gravityᵀx
//          + E_pins + E_collision(x; obstacles) + D_friction(x; x_n) + E_cons(x)
// with the Newton solver. The simulator is the layer S of the method (see step()).
#include <memory>
#include <vector>

#include "physics/bending_energy.h"
#include "physics/body_mesh.h"
#include "physics/cloth_model.h"
#include "physics/collision_energy.h"
#include "physics/friction_energy.h"
#include "physics/membrane_energy.h"
#include "physics/newton_solver.h"
#include "physics/vertex_energies.h"

namespace weft::physics {

// g₀, m/s²: the weight m_i·g₀ is each vertex's force scale in Newton's convergence test.
inline constexpr double kStandardGravity = 9.80665;

struct SimulationSettings {
  double time_step = 0.01;  // seconds per frame
  int substeps = 1;         // implicit Euler steps per frame
  // A frame whose Newton solve fails (iteration cap, line search) is rolled back and run
  // again with twice the sub-steps, up to this many times (h/2, h/4, h/8 at 3): a smaller
  // step moves the body less per solve and brings the inertia term's stiffness M/h² up,
  // so the solve is better conditioned. Only then is the frame reported as failed. 0
  // turns the retries off.
  int max_step_halvings = 3;
  // Adaptive sub-steps (m; 0 turns them off): a frame with a moving body is split into
  // enough sub-steps that no body vertex near the cloth (within max_body_motion_reach of
  // the cloth's bounding box) moves more than this per sub-step, so a limb that sweeps
  // through the garment's band in one frame is met in pieces no longer than a few
  // collision thicknesses. Never fewer than `substeps`, never more than
  // max_adaptive_substeps; the retries then halve from there.
  double max_body_motion = 0.0;
  double max_body_motion_reach = 0.05;  // m
  int max_adaptive_substeps = 16;
  Vec3 gravity{0.0, -9.81, 0.0};  // m/s²
  ClothMaterial material;
  double collision_thickness = 0.005;  // m
  double collision_stiffness = 1.0e4;  // N/m
  // Degrees (0: off): a vertex in the band of a body also feels the other sheet of a
  // crease or gap, faces turned more than this from its closest face
  // (CollisionEnergy::set_second_sheet_angle).
  double collision_second_sheet_deg = 0.0;
  // Outside a body, the penalty summed over its faces, edges and vertices in the band
  // (CollisionEnergy::set_smooth_creases): no kink on a concave crease's medial surface.
  bool collision_smooth_creases = false;
  // The per-vertex step filter bounds only a vertex's approach along its closest
  // obstacle point's normal and leaves its slide along the body free
  // (CollisionEnergy::set_planar_step_bounds); false scales the vertex's whole move.
  bool collision_planar_step_bounds = true;
  // The collision's secant stiffness along the contact normal (CollisionEnergy::
  // set_secant_stiffness); false: Newton's tangent stiffness (the default: no consistent gain).
  bool collision_secant_stiffness = false;
  // ε_v (m/s) of the friction's smoothing (FrictionEnergy): a vertex slipping slower than
  // this against an obstacle feels less than the full Coulomb force, so "stuck" cloth
  // creeps at under ε_v (about 0.48·ε_v on a 20° slope with μ = 0.5). 1 cm/s (issue 41,
  // decision 1): creep under 0.17 mm per 1/60 s step, while the static regime's stiffness
  // 2μλ/(ε_v·h) stays about 10× the inertia m/h² (μ = 0.5, λ ≈ m·g, h = 10 ms). IPC's
  // usual 1 mm/s made the kink at the onset of sliding only ε_v·h = 17 µm wide at
  // h = 1/60 s: Newton's worst drape frames back-tracked on it for tens of iterations
  // while the vertex there crept 10–26 µm per iteration; at 1 cm/s the worst frame took 39
  // Newton iterations instead of 77 (docs/notes/2026-12-06-contact-crawl-levers.md).
  double friction_velocity = 1.0e-2;
  double pin_stiffness = 1.0e4;        // N/m
  double constraint_stiffness = 1.0e2; // N/m, silhouette rays
  NewtonOptions newton;
  // Per-element PSD projection of the membrane Hessian (clamping compressive stress in
  // its geometric term). Off by default: Newton then uses the exact membrane Hessian and
  // falls back to the projected one only in iterations where the exact sum is not
  // positive definite (MembraneEnergy::add_hessian_correction), which keeps quadratic
  // convergence near the solution. Measured on the drape (1k vertices, 10 frames,
  // tolerance 1e-3): always projected, 65 Newton iterations per frame and 7 steps
  // unconverged at the cap; exact with fallback, 42 per frame, all converged.
  // Bending and collision Hessians are always projected.
  bool project_membrane_hessian = false;
  // Newton's first iterate: x_n + α·h·v_n (the inertial prediction, α ≤ 1 cut by the step
  // filter) instead of x_n.
  bool start_from_prediction = true;
  // Measured levers (issue 41), both off: the prediction's move cut per vertex
  // (NewtonSolver::clip_vertex_steps, when the solver's per_vertex_step_limits is on)
  // instead of one α for the whole move, and vertices in contact starting with the body's
  // motion along its normal where the body pushes (FrictionEnergy::follow_obstacles).
  // Per vertex: 1k skirt 36.1 → 26.2 Newton iterations per frame, but the 4k drape 23.1 →
  // 34.5 and a 3k skirt frame at the cap; following the body: drape 22.0, 1k skirt 40.6.
  bool start_filter_per_vertex = false;
  bool start_following_body = false;
};
// Throws weft::Error naming the field if a value is non-physical.
void validate(const SimulationSettings& settings);

struct StepResult {
  Positions x;                 // 3n, finite: the last good state if a step failed
  StepStatus status = StepStatus::converged;  // worst over sub-steps
  int newton_iterations = 0;   // summed over sub-steps and retries
  int substeps = 1;            // of the attempt returned (the frame's sub-steps × 2^retries)
  int adaptive_substeps = 1;   // the frame's sub-steps before any retry (≥ settings' substeps)
  double gradient_norm = 0;    // ‖∇E‖∞ after the last sub-step, N
  double energy = 0;           // incremental potential after the last sub-step, J
  double step_ms = 0;
  NewtonReport last;           // the last sub-step's report (timings)
};

class ClothSimulator {
 public:
  ClothSimulator(ClothMesh mesh, SimulationSettings settings);
  ClothSimulator(const ClothSimulator&) = delete;
  ClothSimulator& operator=(const ClothSimulator&) = delete;

  const ClothMesh& mesh() const { return mesh_; }
  const SimulationSettings& settings() const { return settings_; }
  NewtonSolver& solver() { return *solver_; }

  // Soft pins holding `vertices` at `targets` (default: their rest positions).
  void set_pins(std::vector<int> vertices, std::vector<Vec3> targets = {});
  void set_spheres(std::vector<SphereObstacle> spheres);
  // Adds a body mesh obstacle with its Coulomb friction coefficient against the cloth
  // (0.3: cloth on skin, ARCSim's default against obstacles; 0 for none); returns its
  // index. Spheres carry theirs in SphereObstacle::friction.
  int add_body(BodyMesh body, double friction = 0.3);
  BodyMesh& body(int index) { return *bodies_.at(index); }
  int num_bodies() const { return static_cast<int>(bodies_.size()); }
  void set_ray_targets(std::vector<RayTarget> targets);

  // One implicit Euler step of length h from (x, v); on return x = x_{n+1} and
  // v = (x_{n+1} − x_n)/h. A failed step leaves x at the last accepted Newton iterate
  // (or unchanged) and never makes it non-finite.
  NewtonReport advance(Positions& x, Positions& v, double h);

  // The layer S(x_{t−2}, x_{t−1}, body_{t−1}, body_t) → x_t: the velocity comes from the
  // two previous states, body 0 moves linearly from body_prev to body_now over the
  // settings' sub-steps (pass null pointers for static obstacles). A failed frame is
  // retried with halved steps (SimulationSettings::max_step_halvings); the last attempt
  // runs all its sub-steps whatever fails, so the state returned is at the frame's end.
  StepResult step(const Positions& x_prev2, const Positions& x_prev,
                  const Eigen::MatrixX3d* body_prev = nullptr,
                  const Eigen::MatrixX3d* body_now = nullptr);

  // Forces at x (N, 3n): internal (membrane + bending), external (gravity, pins,
  // silhouette rays) and collision, summed. Not friction: it is not a function of x alone
  // but of the step's motion (see friction_force).
  Positions total_force(const Positions& x) const;
  // The same forces by source (N, 3n each): elastic (membrane + bending), external
  // (gravity, pins, silhouette rays) and collision; they sum to total_force.
  struct ForceParts {
    Positions elastic, external, collision;
  };
  ForceParts force_parts(const Positions& x) const;
  // Friction force (N, 3n) on the cloth at x after a frame that started at x_prev: the
  // friction energy lagged at x_prev over one frame (time_step; the moving body's motion
  // of the last sub-step times the last step()'s sub-step count, exact for its linear
  // motion).
  // With one sub-step this is the friction Newton balanced at the end of that frame.
  Positions friction_force(const Positions& x_prev, const Positions& x) const;
  // Sub-steps for a frame whose body moves from body_prev to body_now: the settings'
  // substeps, raised so that no body vertex near the cloth at x moves more than
  // max_body_motion per sub-step (see SimulationSettings).
  int adaptive_substeps(const Positions& x, const Eigen::MatrixX3d& body_prev,
                        const Eigen::MatrixX3d& body_now) const;
  // Smallest signed distance of a point to any obstacle (m; +inf without obstacles).
  double signed_distance(const Vec3& p) const { return collision_->min_signed_distance(p); }

 private:
  ClothMesh mesh_;
  SimulationSettings settings_;
  std::unique_ptr<InertiaEnergy> inertia_;
  std::unique_ptr<GravityEnergy> gravity_;
  std::unique_ptr<MembraneEnergy> membrane_;
  std::unique_ptr<BendingEnergy> bending_;
  std::unique_ptr<PinEnergy> pins_;
  std::unique_ptr<RayConstraintEnergy> rays_;
  std::unique_ptr<CollisionEnergy> collision_;
  std::unique_ptr<FrictionEnergy> friction_;
  std::vector<std::unique_ptr<BodyMesh>> bodies_;
  std::unique_ptr<NewtonSolver> solver_;
  int last_substeps_ = 1;  // sub-steps of the last step() (friction_force's lag)
};

}  // namespace weft::physics
