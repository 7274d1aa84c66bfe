#pragma once
// The windows of the simulation loss L_sim (the paper's Eq. 8, section 3.3.2), apart from
// the trainer so that they can be tested on their own. A window is F consecutive predicted
// frames t' … t'+F−1 of one clip:
// - the simulator starts at the prediction of t', first cleared of penetration by the
//   collision-resolution pass (physics/collision_resolution.h; the start of a network's
//   prediction may lie inside the body, where the simulator's penalty would throw it out
//   in one violent step), with the velocity of the predictions' forward difference
//   (x_{t'+1} − x_{t'})/h;
// - it follows the predicted bodies, with the anchors pinned where the predicted body's
//   skin carries them (garment_pin_targets_on_body: a predicted anchor may lie inside its
//   body, and a pin there would hold the cloth inside) and the silhouette rays of each
//   frame (E_cons, silhouette_rays.h), and simulates
//   t'+1 … t'+F−1; no gradient reaches its inputs;
// - each converged frame is the target of its prediction, up to the first step that
//   fails: a window that fails later keeps the frames before.
// Frame t'+1 is thus pulled toward x + h²M⁻¹f(x) of the prediction itself: a direct
// penalty on its out-of-balance force and its penetration.
#include <string>
#include <vector>

#include "graph/tensor.h"
#include "capture/character/character.h"
#include "capture/garment/garment_config.h"
#include "physics/simulation_window.h"

namespace weft::capture {

// One window as RUN/windows.csv records it.
struct SimulationWindowRecord {
  int frame = 0;                     // t', the window's first frame
  double start_max_mm = 0;           // deepest start vertex inside the body, before the clean-up
  int start_inside = 0;              // start vertices inside the body, before the clean-up
  int cleaned_inside = 0;            // and after it
  int cleanup_iterations = 0;        // Newton iterations of the clean-up
  std::string status = "converged";  // the first failed step's status, or converged
  int newton_iterations = 0;         // over the simulated steps
  int frames_kept = 0;               // simulated frames with a target (the converged prefix)
  int rays = 0;                      // E_cons rays over the window's frames
};

// The predictions of one window, character units: cloth and body of each of its F frames,
// and the rays of each simulated frame (F − 1 entries, or empty for no E_cons).
struct PredictedWindow {
  std::vector<Vertices> cloth, body;
  std::vector<std::vector<physics::RayTarget>> rays;
};

// The simulator's window (metres) for these predictions, with the start cleared of
// penetration when resolve_start (`simulation`: the garment's material and collision
// settings). Fills the record's start fields. Throws weft::Error for fewer than 2 frames
// or mismatched counts.
physics::SimulationWindow simulation_loss_window(const Character& character, const SynthSimulationConfig& simulation,
                                                 const PredictedWindow& window, bool resolve_start,
                                                 SimulationWindowRecord& record);

// The targets (character units) of frames t'+1 … in order: the simulated states up to the
// first step that did not converge (or is not finite). Fills the record's status,
// iterations and frames kept.
std::vector<Vertices> simulation_loss_targets(const std::vector<physics::StepResult>& results,
                                              double metres_per_unit, SimulationWindowRecord& record);

// L_sim itself: the mean over vertices of the squared distance (m²) between predicted
// cloth [n,V,3] and its simulated targets [n,V,3] (character units; the targets carry no
// gradient: the simulator is a stop-gradient).
Tensor simulation_loss(const Tensor& predicted, const Tensor& targets, double metres_per_unit);

}  // namespace weft::capture
