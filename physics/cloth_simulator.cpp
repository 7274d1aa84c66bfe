#include "physics/cloth_simulator.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "graph/error.h"

namespace weft::physics {

void validate(const SimulationSettings& s) {
  validate(s.material);
  WEFT_CHECK(std::isfinite(s.time_step) && s.time_step > 0, "simulation: time_step must be > 0 s, got ", s.time_step);
  WEFT_CHECK(s.substeps >= 1, "simulation: substeps must be >= 1, got ", s.substeps);
  WEFT_CHECK(s.max_step_halvings >= 0 && s.max_step_halvings <= 10,
             "simulation: max_step_halvings must be in [0, 10], got ", s.max_step_halvings);
  WEFT_CHECK(std::isfinite(s.max_body_motion) && s.max_body_motion >= 0,
             "simulation: max_body_motion must be >= 0 m (0: no adaptive sub-steps), got ", s.max_body_motion);
  WEFT_CHECK(std::isfinite(s.max_body_motion_reach) && s.max_body_motion_reach >= 0,
             "simulation: max_body_motion_reach must be >= 0 m, got ", s.max_body_motion_reach);
  WEFT_CHECK(s.max_adaptive_substeps >= 1 && s.max_adaptive_substeps <= 1024,
             "simulation: max_adaptive_substeps must be in [1, 1024], got ", s.max_adaptive_substeps);
  WEFT_CHECK(s.gravity.allFinite(), "simulation: gravity must be finite");
  WEFT_CHECK(s.collision_thickness > 0, "simulation: collision thickness must be > 0 m, got ",
             s.collision_thickness);
  WEFT_CHECK(std::isfinite(s.collision_second_sheet_deg) && s.collision_second_sheet_deg >= 0 &&
                 s.collision_second_sheet_deg < 180,
             "simulation: collision_second_sheet_deg must be in [0, 180) (0: off), got ", s.collision_second_sheet_deg);
  WEFT_CHECK(s.collision_stiffness > 0, "simulation: collision stiffness must be > 0 N/m, got ",
             s.collision_stiffness);
  WEFT_CHECK(std::isfinite(s.friction_velocity) && s.friction_velocity > 0,
             "simulation: friction velocity must be > 0 m/s, got ", s.friction_velocity);
  WEFT_CHECK(s.pin_stiffness > 0, "simulation: pin stiffness must be > 0 N/m, got ", s.pin_stiffness);
  WEFT_CHECK(s.constraint_stiffness >= 0, "simulation: constraint stiffness must be >= 0 N/m, got ",
             s.constraint_stiffness);
}

ClothSimulator::ClothSimulator(ClothMesh mesh, SimulationSettings settings)
    : mesh_(std::move(mesh)), settings_(std::move(settings)) {
  validate(settings_);
  last_substeps_ = settings_.substeps;
  const int n = mesh_.num_vertices();
  inertia_ = std::make_unique<InertiaEnergy>(mesh_.mass, settings_.time_step);
  gravity_ = std::make_unique<GravityEnergy>(mesh_.mass, settings_.gravity);
  membrane_ = std::make_unique<MembraneEnergy>(mesh_, settings_.material);
  membrane_->set_hessian_projection(settings_.project_membrane_hessian);
  bending_ = std::make_unique<BendingEnergy>(mesh_, settings_.material);
  pins_ = std::make_unique<PinEnergy>(std::vector<int>{}, std::vector<Vec3>{},
                                      settings_.pin_stiffness);
  rays_ = std::make_unique<RayConstraintEnergy>(std::vector<RayTarget>{},
                                                std::max(settings_.constraint_stiffness, 0.0));
  collision_ = std::make_unique<CollisionEnergy>(n, settings_.collision_thickness,
                                                 settings_.collision_stiffness);
  collision_->set_second_sheet_angle(settings_.collision_second_sheet_deg);
  collision_->set_smooth_creases(settings_.collision_smooth_creases);
  collision_->set_planar_step_bounds(settings_.collision_planar_step_bounds);
  collision_->set_secant_stiffness(settings_.collision_secant_stiffness);
  friction_ = std::make_unique<FrictionEnergy>(n, *collision_, settings_.friction_velocity,
                                               settings_.time_step / settings_.substeps);
  solver_ = std::make_unique<NewtonSolver>(
      n,
      std::vector<Energy*>{inertia_.get(), gravity_.get(), membrane_.get(), bending_.get(),
                           pins_.get(), rays_.get(), collision_.get(), friction_.get()},
      settings_.newton);
  // Convergence is judged per vertex against its weight under standard gravity (not the
  // scene's gravity, which may be zero).
  solver_->set_force_scale(kStandardGravity * mesh_.mass);
}

void ClothSimulator::set_pins(std::vector<int> vertices, std::vector<Vec3> targets) {
  for (int v : vertices)
    WEFT_CHECK(v >= 0 && v < mesh_.num_vertices(), "pins: vertex ", v, " outside [0, ",
               mesh_.num_vertices(), ")");
  if (targets.empty())
    for (int v : vertices) targets.push_back(mesh_.rest_vertex(v));
  *pins_ = PinEnergy(std::move(vertices), std::move(targets), settings_.pin_stiffness);
}

void ClothSimulator::set_spheres(std::vector<SphereObstacle> spheres) {
  for (const auto& s : spheres) {
    WEFT_CHECK(s.radius > 0 && s.center.allFinite(), "sphere obstacle: radius must be > 0 m, got ",
               s.radius);
    WEFT_CHECK(std::isfinite(s.friction) && s.friction >= 0,
               "sphere obstacle: friction must be >= 0, got ", s.friction);
  }
  collision_->set_spheres(std::move(spheres));
}

int ClothSimulator::add_body(BodyMesh body, double friction) {
  WEFT_CHECK(std::isfinite(friction) && friction >= 0, "body obstacle: friction must be >= 0, got ",
             friction);
  bodies_.push_back(std::make_unique<BodyMesh>(std::move(body)));
  std::vector<const BodyMesh*> ptrs;
  for (const auto& b : bodies_) ptrs.push_back(b.get());
  collision_->set_bodies(std::move(ptrs));
  std::vector<double> mu = friction_->body_friction();
  mu.push_back(friction);
  friction_->set_body_friction(std::move(mu));
  return static_cast<int>(bodies_.size()) - 1;
}

void ClothSimulator::set_ray_targets(std::vector<RayTarget> targets) {
  for (const auto& t : targets)
    WEFT_CHECK(t.vertex >= 0 && t.vertex < mesh_.num_vertices(), "ray constraint: vertex ",
               t.vertex, " outside [0, ", mesh_.num_vertices(), ")");
  *rays_ = RayConstraintEnergy(std::move(targets), settings_.constraint_stiffness);
}

NewtonReport ClothSimulator::advance(Positions& x, Positions& v, double h) {
  WEFT_CHECK(x.size() == 3 * mesh_.num_vertices() && v.size() == x.size(),
             "cloth step: state has ", x.size(), " entries, expected ", 3 * mesh_.num_vertices());
  inertia_->set_time_step(h);
  friction_->set_time_step(h);  // its smoothing ε = ε_v·h
  const Positions x_start = x;
  Positions x_hat = x + h * v;
  if (!x_hat.allFinite()) x_hat = x;  // a non-finite velocity carries no information
  inertia_->set_prediction(x_hat);
  for (Energy* e : solver_->energies()) e->begin_step(x);
  // Newton starts from the prediction x̂ as far as the energies' step filter allows: a
  // prediction that has tunnelled through a thin obstacle would be pushed out on the
  // wrong side, so the move from x_n is cut where a vertex would come closer than δ/2 to
  // an obstacle (Energy::max_step).
  Positions x_new = x_start;
  if (settings_.start_from_prediction) {
    Positions dx = x_hat - x_start;
    if (settings_.start_following_body) friction_->follow_obstacles(dx);
    if (settings_.start_filter_per_vertex && settings_.newton.per_vertex_step_limits) {
      solver_->clip_vertex_steps(x_start, dx);
      x_new += dx;
    } else {
      const double alpha = solver_->max_step(x_start, dx);
      if (alpha > 0 && std::isfinite(alpha)) x_new += alpha * dx;
    }
  }
  NewtonReport report = solver_->minimize(x_new);
  if (!x_new.allFinite()) {
    x_new = x_start;
    report.status = StepStatus::non_finite;
  }
  v = (x_new - x_start) / h;
  x = std::move(x_new);
  return report;
}

StepResult ClothSimulator::step(const Positions& x_prev2, const Positions& x_prev,
                                const Eigen::MatrixX3d* body_prev,
                                const Eigen::MatrixX3d* body_now) {
  const auto t0 = std::chrono::steady_clock::now();
  WEFT_CHECK((body_prev == nullptr) == (body_now == nullptr),
             "cloth step: give both body_prev and body_now, or neither");
  WEFT_CHECK(body_prev == nullptr || !bodies_.empty(),
             "cloth step: body positions given but the simulator has no body mesh");
  const double h = settings_.time_step;
  StepResult result;
  result.x = x_prev;
  Positions v = (x_prev - x_prev2) / h;
  if (!v.allFinite()) v.setZero();
  if (!result.x.allFinite()) {
    result.status = StepStatus::non_finite;
    result.x = x_prev2.allFinite() ? x_prev2 : mesh_.rest;
    result.step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return result;
  }
  const Positions v_start = v;
  const int substeps = body_now ? adaptive_substeps(x_prev, *body_prev, *body_now) : settings_.substeps;
  result.adaptive_substeps = substeps;
  int iterations = 0;
  for (int halvings = 0;; ++halvings) {
    const int n = substeps << halvings;
    // The last attempt runs every sub-step even after one fails, so a failed frame still
    // hands on a state at the frame's end, beside the body where the frame leaves it
    // (breaking off would hand on a state from partway through the frame).
    const bool last_attempt = halvings >= settings_.max_step_halvings;
    const double hs = h / n;
    result.x = x_prev;
    result.status = StepStatus::converged;
    result.substeps = n;
    v = v_start;
    for (int s = 0; s < n; ++s) {
      if (body_now) {
        const double t = static_cast<double>(s + 1) / n;
        const Eigen::MatrixX3d now = (1.0 - t) * (*body_prev) + t * (*body_now);
        // The first sub-step moves the body from body_prev, wherever the mesh was left (its
        // motion over the sub-step drags the cloth by friction).
        if (s == 0)
          bodies_[0]->set_vertices(now, *body_prev);
        else
          bodies_[0]->set_vertices(now);
      }
      NewtonReport r = advance(result.x, v, hs);
      iterations += r.iterations;
      if (static_cast<int>(r.status) > static_cast<int>(result.status)) result.status = r.status;
      result.gradient_norm = r.gradient_norm;
      result.energy = r.energy;
      result.last = std::move(r);
      if (result.status != StepStatus::converged && !last_attempt) break;  // retried below
    }
    if (result.status == StepStatus::converged || last_attempt) break;
  }
  result.newton_iterations = iterations;
  last_substeps_ = result.substeps;
  result.step_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

int ClothSimulator::adaptive_substeps(const Positions& x, const Eigen::MatrixX3d& body_prev,
                                      const Eigen::MatrixX3d& body_now) const {
  const int base = settings_.substeps;
  if (!(settings_.max_body_motion > 0) || body_prev.rows() != body_now.rows() || x.size() == 0) return base;
  // The cloth's bounding box, grown by the reach: body vertices outside it at both ends of
  // the frame cannot meet the cloth within the frame unless they move further than the
  // reach, and such a vertex is counted by its motion's end points lying on either side.
  const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>> X(x.data(), x.size() / 3, 3);
  const Eigen::RowVector3d lo = X.colwise().minCoeff().array() - settings_.max_body_motion_reach;
  const Eigen::RowVector3d hi = X.colwise().maxCoeff().array() + settings_.max_body_motion_reach;
  auto inside = [&](const Eigen::RowVector3d& p) { return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all(); };
  double motion = 0;
  for (Eigen::Index i = 0; i < body_now.rows(); ++i) {
    const Eigen::RowVector3d a = body_prev.row(i), b = body_now.row(i);
    const double d = (b - a).norm();
    if (d <= motion) continue;
    if (inside(a) || inside(b) || d > settings_.max_body_motion_reach) motion = d;
  }
  if (!std::isfinite(motion)) return base;
  const double needed = std::ceil(motion / settings_.max_body_motion - 1e-9);  // round-off: 0.1 / 0.01 is 10
  return std::clamp(static_cast<int>(std::min(needed, 1e6)), base, std::max(base, settings_.max_adaptive_substeps));
}

Positions ClothSimulator::total_force(const Positions& x) const {
  const ForceParts p = force_parts(x);
  return p.elastic + p.external + p.collision;
}

ClothSimulator::ForceParts ClothSimulator::force_parts(const Positions& x) const {
  auto force = [&](std::initializer_list<const Energy*> energies) {
    Positions g = Positions::Zero(x.size());
    for (const Energy* e : energies) e->evaluate(x, &g, nullptr);
    return Positions(-g);
  };
  return {force({membrane_.get(), bending_.get()}), force({gravity_.get(), pins_.get(), rays_.get()}),
          force({collision_.get()})};
}

Positions ClothSimulator::friction_force(const Positions& x_prev, const Positions& x) const {
  // A copy: the simulator's own energy keeps the lag of its last sub-step.
  FrictionEnergy frame = *friction_;
  frame.set_time_step(settings_.time_step);
  frame.lag(x_prev, last_substeps_);
  Positions g = Positions::Zero(x.size());
  frame.evaluate(x, &g, nullptr);
  return -g;
}

}  // namespace weft::physics
