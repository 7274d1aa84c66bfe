#pragma once
// The coarse generated skirt (448 vertices) on the MakeHuman body, and that skirt with
// patches pushed 2 cm into the body as a network's prediction might have them: the
// garment of the tests of the collision-resolution pass and of the simulation loss.
#include <memory>

#include "capture/character/default_character.h"
#include "capture/studio/cloth_perturbation.h"
#include "capture/garment/garment_simulator.h"
#include "tests/capture/test_files.h"

namespace weft::capture::testing {

// Built once per test program (a few seconds).
inline const Character& coarse_skirt() {
  static std::unique_ptr<Character> ch;
  if (!ch)
    ch = std::make_unique<Character>(
        make_default_character(
            load_default_character_config(repo_file("configs/characters/makehuman_skirt_coarse.yaml")))
            .character);
  return *ch;
}

// The bind-pose skirt with 3 patches pushed 2 cm into the body (perturb_start's patches
// only: no stretch, no displacement), character units.
inline Vertices skirt_pushed_into_body(const Character& ch) {
  const double mpu = ch.metres_per_unit;
  const physics::Positions x = to_positions(ch.cloth->mesh.V, mpu);
  ClothPerturbationConfig c;
  c.max_stretch = 0;
  c.max_displacement_m = 0;
  c.patches = 3;
  c.velocity_noise_smooth_mps = 0;
  c.velocity_noise_vertex_mps = 0;
  const physics::BodyMesh body = body_obstacle(ch, ch.body.mesh.V * mpu);
  return to_vertices(perturb_start(x, x, x, body, 1.0 / 30, c, 7).x_prev, mpu);
}

}  // namespace weft::capture::testing
