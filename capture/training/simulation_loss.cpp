#include "capture/training/simulation_loss.h"

#include "capture/garment/garment_collision_resolution.h"
#include "capture/garment/garment_simulator.h"
#include "graph/error.h"
#include "ops/ops.h"
#include "physics/collision_resolution.h"

namespace weft::capture {

physics::SimulationWindow simulation_loss_window(const Character& ch, const SynthSimulationConfig& simulation,
                                                 const PredictedWindow& in, bool resolve_start,
                                                 SimulationWindowRecord& rec) {
  const int F = int(in.cloth.size());
  WEFT_CHECK(F >= 2, "simulation window: ", F, " predicted frames, expected at least 2 (a start and a target)");
  WEFT_CHECK(int(in.body.size()) == F, "simulation window: ", in.body.size(), " bodies for ", F, " cloth frames");
  WEFT_CHECK(in.rays.empty() || int(in.rays.size()) == F - 1, "simulation window: ", in.rays.size(),
             " frames of rays, expected ", F - 1);
  const double mpu = ch.metres_per_unit;
  physics::Positions x0 = to_positions(in.cloth[0], mpu);
  const physics::Positions velocity_step = to_positions(in.cloth[1], mpu) - x0;  // h · forward-difference velocity
  if (resolve_start) {
    const GarmentCollisionResolution cleaned = resolve_garment_collisions(ch, simulation, in.body[0], in.cloth[0]);
    rec.start_max_mm = cleaned.pass.before.max_depth * 1e3;
    rec.start_inside = cleaned.pass.before.vertices_inside;
    rec.cleaned_inside = cleaned.pass.after.vertices_inside;
    rec.cleanup_iterations = cleaned.pass.iterations;
    x0 = cleaned.pass.x;
  } else {
    const physics::BodyMesh obstacle = body_obstacle(ch, Eigen::MatrixX3d(in.body[0] * mpu));
    const physics::PenetrationStats before = physics::measure_penetration(x0, {{}, {&obstacle}});
    rec.start_max_mm = before.max_depth * 1e3;
    rec.cleaned_inside = rec.start_inside = before.vertices_inside;
  }
  physics::SimulationWindow w;
  w.x_prev = x0;
  w.x_prev2 = x0 - velocity_step;
  w.frames = F - 1;
  w.stop_after_failure = true;
  w.pin_vertices = garment_pin_vertices(ch);
  for (int j = 0; j < F; ++j) {
    w.body.push_back(Eigen::MatrixX3d(in.body[j] * mpu));
    if (j > 0) w.pin_targets.push_back(garment_pin_targets_on_body(ch, in.body[j]));
  }
  w.ray_targets = in.rays;
  rec.rays = 0;
  for (const auto& r : in.rays) rec.rays += int(r.size());
  return w;
}

std::vector<Vertices> simulation_loss_targets(const std::vector<physics::StepResult>& results,
                                              double metres_per_unit, SimulationWindowRecord& rec) {
  std::vector<Vertices> targets;
  rec.newton_iterations = 0;
  rec.status = "converged";
  for (const physics::StepResult& st : results) {
    rec.newton_iterations += st.newton_iterations;
    if (st.status != physics::StepStatus::converged || !st.x.allFinite()) {
      rec.status = physics::to_string(st.x.allFinite() ? st.status : physics::StepStatus::non_finite);
      break;
    }
    targets.push_back(to_vertices(st.x, metres_per_unit));
  }
  rec.frames_kept = int(targets.size());
  return targets;
}

Tensor simulation_loss(const Tensor& predicted, const Tensor& targets, double metres_per_unit) {
  WEFT_CHECK(predicted.shape() == targets.shape() && predicted.dim() == 3 && predicted.size(2) == 3,
             "simulation_loss: predicted ", shape_str(predicted.shape()), " and targets ", shape_str(targets.shape()),
             " must both be [n,V,3]");
  const Tensor d = ops::sub(predicted, targets);
  return ops::scale(ops::mean(ops::mul(d, d)), 3.0 * metres_per_unit * metres_per_unit);
}

}  // namespace weft::capture
