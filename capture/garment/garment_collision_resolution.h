#pragma once
// The final collision-resolution pass (physics/collision_resolution.h) for a character's
// garment, as `weft infer --resolve-collisions` runs it per frame: the predicted cloth
// pushed out of the predicted body with the garment simulator's own material, collision
// thickness and stiffness (a synth config's simulation section, garment_simulator.h) and
// the body as the simulator collides with it (body_obstacle: inactive faces, the arms and
// hands, left out). Inputs and outputs in character units; the pass runs in metres.
//
// The garment's anchors are not held: the proximal term keeps them where the prediction
// put them unless they are inside the body, and pinning them there would leave them inside.
#include <memory>

#include "capture/character/character.h"
#include "capture/garment/garment_config.h"
#include "physics/collision_resolution.h"

namespace weft::capture {

struct GarmentCollisionResolution {
  Vertices cloth;                            // resolved cloth vertices, character units
  physics::CollisionResolutionResult pass;   // positions (m), stats (m), iterations, timings
  double body_ms = 0;                        // building or refitting the body obstacle, ms
};

// The pass's options from a synth config's simulation section (material, collision
// thickness and stiffness, pin stiffness); the pass's own keys at their defaults.
physics::CollisionResolutionOptions garment_collision_resolution_options(const SynthSimulationConfig& simulation);

// Resolves frame after frame for one character: the garment's mesh and the body obstacle
// are built once (the body refitted to each frame's vertices).
class GarmentCollisionResolver {
 public:
  // The character needs a garment (weft::Error otherwise); it is copied.
  GarmentCollisionResolver(const Character& character, const SynthSimulationConfig& simulation);
  ~GarmentCollisionResolver();
  GarmentCollisionResolver(const GarmentCollisionResolver&) = delete;
  GarmentCollisionResolver& operator=(const GarmentCollisionResolver&) = delete;

  // body: posed body vertices, cloth: predicted cloth vertices (n × 3, character units, the
  // template's vertex counts). Throws weft::Error on a wrong vertex count or a non-finite
  // vertex.
  GarmentCollisionResolution resolve(const Vertices& body, const Vertices& cloth);

  physics::CollisionResolutionOptions& options() { return options_; }
  const physics::ClothMesh& cloth_mesh() const { return mesh_; }

 private:
  Character character_;  // a copy: the resolver may outlive the caller's
  physics::CollisionResolutionOptions options_;
  physics::ClothMesh mesh_;
  std::unique_ptr<physics::BodyMesh> body_;
};

// One frame, without keeping anything between calls.
GarmentCollisionResolution resolve_garment_collisions(const Character& character,
                                                      const SynthSimulationConfig& simulation, const Vertices& body,
                                                      const Vertices& cloth);

}  // namespace weft::capture
