#pragma once
// Rolling the simulator over short windows, as the method's simulation loss does: a
// window starts from two consecutive cloth states (velocity by finite differences) and
// follows a moving body for F frames. Windows are independent; simulate_windows runs
// many of them in parallel with TBB, each on its own simulator, so the results equal
// running them one by one.
#include <functional>
#include <memory>
#include <vector>

#include "physics/cloth_simulator.h"

namespace weft::physics {

struct SimulationWindow {
  Positions x_prev2, x_prev;  // two states one time step apart, x_prev the newest
  // Body 0's vertices at the frame of x_prev and at each of the `frames` frames after it
  // (frames + 1 entries), or empty for static obstacles.
  std::vector<Eigen::MatrixX3d> body;
  // Pins that move with the body (a garment's waistband following the skin): the pinned
  // vertices and their targets (m) at each simulated frame (`frames` entries of
  // pin_vertices.size() targets), set before each frame's step. Empty: the simulator's
  // pins as configured.
  std::vector<int> pin_vertices;
  std::vector<std::vector<Vec3>> pin_targets;
  // The silhouette constraint E_cons of each simulated frame (`frames` entries, each the
  // rays of that frame, m), set before the frame's step. Empty: no rays.
  std::vector<std::vector<RayTarget>> ray_targets;
  int frames = 1;
  // Stop at the first step that does not converge: the results then end with that step
  // (the frames before it converged), instead of carrying on from its last iterate.
  bool stop_after_failure = false;
};

// Runs one window on `sim` (its obstacles and pins as configured); one result per frame
// (fewer with stop_after_failure).
std::vector<StepResult> simulate_window(ClothSimulator& sim, const SimulationWindow& window);

// Makes a configured simulator for one window; called once per window, possibly from
// several threads at once.
using SimulatorFactory = std::function<std::unique_ptr<ClothSimulator>()>;

// All windows in parallel (TBB, within weft's thread budget); results in window order.
std::vector<std::vector<StepResult>> simulate_windows(const SimulatorFactory& make_simulator,
                                                      const std::vector<SimulationWindow>& windows);

}  // namespace weft::physics
