#pragma once
// How the garment is simulated: the `simulation` section of a `weft synth` config
// (docs/DATASET.md), which the synthetic studio makes the ground truth with. `weft synth`
// writes it into the dataset's dataset.yaml and `weft train` copies it into the model
// folder's model.yaml, where the simulation loss, the collision-resolution pass and the
// out-of-balance force read it, so the garment is simulated everywhere as the data was made
// and no recipe has to stay where it was.
#include <optional>
#include <string>

#include "files/strict_yaml.h"
#include "physics/cloth_model.h"

namespace weft::capture {

struct SynthSimulationConfig {
  bool enabled = true;     // false: the garment is skinned, not simulated
  int substeps = 1;        // implicit Euler steps per frame (> 1: the frame-level out-of-balance
                           // force then includes the sub-stepping error)
  int settle_frames = 15;  // frames simulated at the first pose before the motion starts
  // Adaptive sub-steps: a frame is split so that the body near the garment moves at most
  // this far (m) per sub-step; 0: off (physics::SimulationSettings::max_body_motion).
  // Off by default: a sub-stepped frame is in balance at the sub-step, not at the frame,
  // so its frame-level out-of-balance force (three consecutive frames, the paper's
  // measure) is the sub-stepping error, up to 77× a vertex's weight on the tiny ground
  // truth; ground truth must be in balance at the frame rate it is measured at. With the
  // two settings marked (measured) below, squat_jump.yaml lost 2 frames of 315 instead of
  // 76 (docs/SIMULATION.md, "Frames that fail").
  double max_body_motion = 0.0;
  int max_step_halvings = 3;      // retries of a failed frame at h/2, h/4, … (0: none)
  physics::ClothMaterial material{0.15, 2.0e5, 0.3, 2.0e-6, 0.001};
  double collision_thickness = 0.004;  // m
  double collision_stiffness = 1.0e4;  // N/m
  double collision_second_sheet_deg = 45.0;  // both sheets of a crease (physics::SimulationSettings); 0: off (measured)
  // The penalty summed over the body's faces, edges and vertices in the band, so the
  // medial surface of a concave crease is no kink (physics::CollisionEnergy::set_smooth_creases).
  bool collision_smooth_creases = true;  // (measured)
  double pin_stiffness = 1.0e4;        // N/m
  double friction = 0.3;               // Coulomb coefficient of the garment on the body (skin)
  // Newton iterations per step. A body stepping into the skirt cuts every step through
  // the collision step filter (a global α), so such steps take 50–150 iterations to
  // converge (measured on training.yaml, frames 33–49): with a cap of 50 the first of them
  // stopped out of balance and every later frame failed after it.
  int max_iterations = 200;
  double tolerance = 1e-3;             // relative to each vertex's weight
  // The collision step filter and friction's slip-reversal clamp per vertex
  // (physics::NewtonOptions::per_vertex_step_limits) instead of one α for the whole step.
  bool per_vertex_step_limits = true;  // (measured)
  double max_penetration = 0.01;       // m: a frame deeper than this counts as failed

  bool operator==(const SynthSimulationConfig&) const = default;
};

// Reads the `simulation` section `n` into `s` (absent keys keep their value); errors name
// the file, the line and the key (simulation.material.* by physics/cloth_material_yaml.h).
void parse_simulation_config(const StrictYaml& yaml, const YAML::Node& n, SynthSimulationConfig& s);

// The `simulation` section of the synth config at `synth_config` (defaults when it has
// none); the config's other sections are not read. `weft eval --synth-config` and model
// folders written before datasets carried their simulation read it.
SynthSimulationConfig load_simulation_config(const std::string& synth_config);

// The section as `weft synth` writes it into dataset.yaml and `weft train` into model.yaml:
// "simulation:" and every key, indented by two spaces, numbers in their shortest exact form,
// so parse_simulation_config reads back the same settings.
std::string simulation_config_yaml(const SynthSimulationConfig& simulation);

// The garment's simulation settings a dataset was made with: the `simulation` section of
// DIR/dataset.yaml. find_: nothing when the dataset has none; read_: an error naming
// dataset.yaml and the missing key, and how to regenerate the dataset.
std::optional<SynthSimulationConfig> find_dataset_simulation(const std::string& dataset_dir);
SynthSimulationConfig read_dataset_simulation(const std::string& dataset_dir);

}  // namespace weft::capture
