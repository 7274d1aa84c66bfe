#include "physics/simulation_window.h"

#include <tbb/parallel_for.h>

#include "graph/error.h"

namespace weft::physics {

std::vector<StepResult> simulate_window(ClothSimulator& sim, const SimulationWindow& w) {
  WEFT_CHECK(w.frames >= 1, "simulation window: frames must be >= 1, got ", w.frames);
  WEFT_CHECK(w.body.empty() || static_cast<int>(w.body.size()) == w.frames + 1,
             "simulation window: ", w.body.size(), " body frames given, expected ", w.frames + 1,
             " (the start frame and each simulated frame)");
  WEFT_CHECK(w.pin_targets.empty() || static_cast<int>(w.pin_targets.size()) == w.frames,
             "simulation window: ", w.pin_targets.size(), " frames of pin targets given, expected ", w.frames);
  WEFT_CHECK(w.ray_targets.empty() || static_cast<int>(w.ray_targets.size()) == w.frames,
             "simulation window: ", w.ray_targets.size(), " frames of ray targets given, expected ", w.frames);
  for (const auto& t : w.pin_targets)
    WEFT_CHECK(t.size() == w.pin_vertices.size(), "simulation window: ", t.size(), " pin targets for ",
               w.pin_vertices.size(), " pinned vertices");
  std::vector<StepResult> results;
  results.reserve(w.frames);
  Positions x2 = w.x_prev2, x1 = w.x_prev;
  for (int f = 0; f < w.frames; ++f) {
    if (!w.pin_targets.empty()) sim.set_pins(w.pin_vertices, w.pin_targets[f]);
    if (!w.ray_targets.empty()) sim.set_ray_targets(w.ray_targets[f]);
    StepResult r = w.body.empty() ? sim.step(x2, x1)
                                  : sim.step(x2, x1, &w.body[f], &w.body[f + 1]);
    x2 = std::move(x1);
    x1 = r.x;
    const bool failed = r.status != StepStatus::converged;
    results.push_back(std::move(r));
    if (failed && w.stop_after_failure) break;
  }
  return results;
}

std::vector<std::vector<StepResult>> simulate_windows(const SimulatorFactory& make_simulator,
                                                      const std::vector<SimulationWindow>& windows) {
  std::vector<std::vector<StepResult>> results(windows.size());
  tbb::parallel_for(size_t{0}, windows.size(), [&](size_t i) {
    std::unique_ptr<ClothSimulator> sim = make_simulator();
    results[i] = simulate_window(*sim, windows[i]);
  });
  return results;
}

}  // namespace weft::physics
