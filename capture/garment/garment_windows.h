#pragma once
// Simulation windows over a `weft synth` dataset's ground truth (docs/DATASET.md), built
// to simulate the garment exactly as the synth did: the dataset's character, simulation
// settings and fps (garment_simulator.h), the body of gt/body_*.ply as
// the moving obstacle and the waistband pins following the character skinned by
// gt/pose.motion. A window starting at frame t takes two given states for frames t − 1
// and t and simulates frames t + 1 … t + F − 1 (F = frames + 1 states in all).
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/garment/garment_config.h"
#include "physics/simulation_window.h"

namespace weft::capture {

struct GarmentSequence {
  std::string dir;                         // the dataset folder
  Character character;                     // DIR/character/character.yaml
  SynthSimulationConfig simulation;        // dataset.yaml's simulation section
  double fps = 30;                         // the dataset's
  int frames = 0;
  std::vector<int> failed_frames;          // from dataset.yaml
  std::vector<int> segments;               // first frame of each clip (dataset.yaml; empty: one clip)
  std::vector<physics::Positions> cloth;   // gt/cloth_<f>.ply per frame (3n, m)
  std::vector<std::vector<physics::Vec3>> pin_targets;  // per frame (m)
  double time_step() const { return 1.0 / fps; }
  // gt/body_<f>.ply (n × 3, m), read when asked (a 300-frame body would be ~100 MB).
  Eigen::MatrixX3d body(int frame) const;
  physics::SimulatorFactory simulator_factory() const;
};

// Reads the dataset with the simulation settings it was made with (dataset.yaml's
// `simulation` section, garment_config.h); the time step is the dataset's. Errors
// (weft::Error) when the dataset has no such section, the simulation is off or the
// meshes' vertex counts do not match.
GarmentSequence load_garment_sequence(const std::string& dataset_dir);

// A window from given states x_prev2 (frame start − 1) and x_prev (frame start),
// simulating `frames` frames after `start` with the ground-truth body and pins. Frames
// start .. start + frames must lie in one clip (a weft::Error otherwise).
physics::SimulationWindow garment_window(const GarmentSequence& sequence, int start, int frames,
                                         physics::Positions x_prev2, physics::Positions x_prev);

// Depth (m, ≥ 0) of the deepest cloth vertex inside the body's active faces (those the
// simulator collides with), and how many vertices are inside.
struct Penetration {
  double max_depth = 0;
  double depth_sum = 0;  // m, over the vertices inside
  int vertices_inside = 0;
  int vertices_in_contact = 0;  // outside, closer to the body than contact_distance
};
// contact_distance (m): how close to the surface an outside vertex counts as in contact.
Penetration body_penetration(const physics::BodyMesh& body, const physics::Positions& x, double contact_distance = 0);
// The body of `frame` as the simulator sees it (inactive faces left out).
physics::BodyMesh collision_body(const GarmentSequence& sequence, int frame);

}  // namespace weft::capture
