// The collision-resolution pass on a character's garment (capture/studio/
// garment_collision_resolution.h): the coarse generated skirt (448 vertices) on the
// MakeHuman body, with patches pushed 2 cm into the body as a network's prediction might
// have them, comes out within 1 mm; the bind-pose skirt (clear of the body) is returned
// unchanged; a character in millimetres gives the same answer as in metres; wrong vertex
// counts and non-finite vertices are one clear error.
#include <gtest/gtest.h>

#include <memory>

#include "capture/character/default_character.h"
#include "capture/studio/cloth_perturbation.h"
#include "capture/garment/garment_collision_resolution.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "tests/capture/coarse_skirt.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::coarse_skirt;
using weft::capture::testing::repo_file;
using weft::capture::testing::skirt_pushed_into_body;

namespace {


SynthSimulationConfig simulation() { return SynthSimulationConfig{}; }  // the synth's defaults (training.yaml's values)


}  // namespace

TEST(GarmentCollisionResolution, PushedInSkirtComesOutOfTheBody) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  const Vertices cloth = skirt_pushed_into_body(ch);
  const weft::physics::BodyMesh body = body_obstacle(ch, ch.body.mesh.V * ch.metres_per_unit);
  const Penetration before = body_penetration(body, to_positions(cloth, ch.metres_per_unit));
  ASSERT_GT(before.max_depth, 0.01);

  GarmentCollisionResolver resolver(ch, simulation());
  const GarmentCollisionResolution r = resolver.resolve(ch.body.mesh.V, cloth);
  ASSERT_EQ(r.cloth.rows(), cloth.rows());
  EXPECT_NE(r.pass.status, weft::physics::StepStatus::non_finite);
  EXPECT_GT(r.pass.iterations, 0);
  EXPECT_NEAR(r.pass.before.max_depth, before.max_depth, 1e-12);
  const Penetration after = body_penetration(body, to_positions(r.cloth, ch.metres_per_unit));
  EXPECT_LE(after.max_depth, 1e-3) << after.vertices_inside << " vertices inside";
  EXPECT_NEAR(r.pass.after.max_depth, after.max_depth, 1e-12);
  for (size_t k = 1; k < r.pass.energies.size(); ++k) EXPECT_LE(r.pass.energies[k], r.pass.energies[k - 1]);
  // Far from the patches the skirt is where the prediction put it: the untouched hem.
  int unchanged = 0;
  for (int i = 0; i < cloth.rows(); ++i) unchanged += (r.cloth.row(i) - cloth.row(i)).norm() == 0.0;
  EXPECT_GT(unchanged, cloth.rows() / 4);

  // The same resolver, next frame: the bind-pose skirt, 12 mm clear of the body, unchanged.
  const GarmentCollisionResolution clear = resolver.resolve(ch.body.mesh.V, ch.cloth->mesh.V);
  EXPECT_EQ(clear.pass.iterations, 0);
  EXPECT_EQ(clear.cloth, ch.cloth->mesh.V);
}

TEST(GarmentCollisionResolution, CharacterUnitsDoNotChangeTheAnswer) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  Character mm = ch;  // the same character in millimetres
  mm.metres_per_unit = 0.001 * ch.metres_per_unit;
  mm.body.mesh.V *= 1000;
  mm.cloth->mesh.V *= 1000;
  const Vertices cloth = skirt_pushed_into_body(ch);
  const GarmentCollisionResolution in_m = resolve_garment_collisions(ch, simulation(), ch.body.mesh.V, cloth);
  const GarmentCollisionResolution in_mm =
      resolve_garment_collisions(mm, simulation(), mm.body.mesh.V, Vertices(cloth * 1000));
  EXPECT_EQ(in_mm.pass.iterations, in_m.pass.iterations);
  // To a micrometre: the inputs differ by rounding (× 1000, × 0.001), which Newton carries.
  EXPECT_LT((in_mm.cloth / 1000 - in_m.cloth).cwiseAbs().maxCoeff(), 1e-6);
}

TEST(GarmentCollisionResolution, BadInputIsOneClearError) {
  REQUIRE_HUMAN();
  const Character& ch = coarse_skirt();
  GarmentCollisionResolver resolver(ch, simulation());
  const Vertices& body = ch.body.mesh.V;
  const Vertices& cloth = ch.cloth->mesh.V;
  weft::capture::testing::expect_error([&] { resolver.resolve(body.topRows(100), cloth); },
                                       {"100 body vertices given", "has 13380"});
  weft::capture::testing::expect_error([&] { resolver.resolve(body, cloth.topRows(10)); },
                                       {"10 cloth vertices given", "garment has 448"});
  Vertices nan = cloth;
  nan(5, 1) = std::numeric_limits<double>::quiet_NaN();
  weft::capture::testing::expect_error([&] { resolver.resolve(body, nan); }, {"cloth has a non-finite vertex"});
  Character bare = ch;
  bare.cloth.reset();
  weft::capture::testing::expect_error([&] { GarmentCollisionResolver r(bare, simulation()); }, {"has no garment"});
}
