#pragma once
// The garment simulator of the synthetic studio, as a reusable piece: `weft synth` builds
// its simulator here, and so does anything that must simulate the same garment the same
// way later (the simulation windows of the method's simulation loss, their benchmark and
// tests), so that a change to how the studio simulates reaches every user at once.
//
// The simulator: the character's garment in its bind pose as the rest shape (metres), the
// body as one moving mesh obstacle with the character's inactive faces (arms and hands)
// left out of collisions, Coulomb friction at the simulator's default, and the anchors
// (the waistband) as soft pins whose targets follow the skinned garment frame by frame
// (garment_pin_targets; the caller moves them, see SimulationWindow::pin_targets).
#include <memory>
#include <vector>

#include "capture/character/character.h"
#include "capture/garment/garment_config.h"
#include "physics/cloth_simulator.h"
#include "physics/simulation_window.h"

namespace weft::capture {

// Positions (3n, metres) from character-unit vertices, and back.
physics::Positions to_positions(const Vertices& V, double metres_per_unit);
Vertices to_vertices(const physics::Positions& x, double metres_per_unit);

// The simulator's settings from a synth config's simulation section; one frame is 1/fps s.
// ray_stiffness: the silhouette constraint's stiffness (N/m; < 0 keeps the simulator's
// default), for the simulation loss's rays (SimulationWindow::ray_targets).
physics::SimulationSettings garment_simulation_settings(const SynthSimulationConfig& simulation, double fps,
                                                        double ray_stiffness = -1);

// The pinned garment vertices (the character's attachment anchors).
std::vector<int> garment_pin_vertices(const Character& character);
// The pins' targets (metres) for a posed garment (character units, e.g.
// PosedCharacter::cloth): where the skin carries each anchor.
std::vector<physics::Vec3> garment_pin_targets(const Character& character, const Vertices& posed_cloth);
// The pins' targets (metres) carried by a posed body (character units): each anchor keeps
// its bind-pose offset from its attachment triangle (character.attachment), written in the
// triangle's frame (two edges and the unit normal), so it rides the skin wherever the
// body's surface goes and is exactly the bind-pose anchor on the bind-pose body. For a
// network's prediction, whose anchors may lie inside its body, this is where the skin
// would carry them.
std::vector<physics::Vec3> garment_pin_targets_on_body(const Character& character, const Vertices& posed_body);

// The body as the simulator collides with it: vertices in metres (n × 3), the
// character's inactive faces (arms, hands) left out.
physics::BodyMesh body_obstacle(const Character& character, const Eigen::MatrixX3d& body_metres);

// A configured simulator: body obstacle at `body_metres` (n × 3, metres), pins at
// `pin_targets` (garment_pin_vertices order). The character needs a garment.
std::unique_ptr<physics::ClothSimulator> make_garment_simulator(const Character& character,
                                                                const SynthSimulationConfig& simulation,
                                                                double fps, const Eigen::MatrixX3d& body_metres,
                                                                const std::vector<physics::Vec3>& pin_targets,
                                                                double ray_stiffness = -1);

// For physics::simulate_windows: each call makes a simulator as above, with the body and
// pins of the bind pose (every window then sets both per frame: SimulationWindow::body and
// pin_targets). Holds its own copy of the character; safe to call from several threads.
physics::SimulatorFactory garment_simulator_factory(const Character& character,
                                                    const SynthSimulationConfig& simulation, double fps,
                                                    double ray_stiffness = -1);

}  // namespace weft::capture
