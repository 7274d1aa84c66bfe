// Laws of the final collision-resolution pass: cloth pushed into a sphere or a body mesh
// comes out (deepest vertex within 1 mm), every accepted Newton iterate lowers the energy,
// cloth away from the contact barely moves (and outside the solved region not at all), the
// solved region agrees with solving the whole cloth, cloth already clear of the obstacle is
// returned unchanged without a Newton iteration, and bad input is one clear weft::Error.
#include <gtest/gtest.h>

#include "graph/error.h"
#include "physics/collision_resolution.h"
#include "tests/physics/physics_test_util.h"

namespace weft::physics {
namespace {

// 1 m × 1 m, 41 × 41 vertices (2.5 cm apart) in the plane y = 0, centred on the origin.
ClothMesh flat_cloth() { return make_grid_cloth(Vec3(-0.5, 0, -0.5), 1.0, 1.0, 41, 41, "xz", 0.2); }

CollisionResolutionOptions options() {
  CollisionResolutionOptions o;
  o.material = testing::simulation_settings(0.01).material;  // the simulation tests' cloth
  o.collision_thickness = 0.005;
  return o;
}

// A sphere whose top pokes 2 cm through the cloth: the vertices within 10.8 cm of the
// centre are inside, the deepest 2 cm.
SphereObstacle poking_sphere() { return SphereObstacle{Vec3(0, -0.28, 0), 0.3}; }

double max_move(const Positions& a, const Positions& b, const std::vector<int>& vertices) {
  double m = 0;
  for (int i : vertices) m = std::max(m, (a.segment<3>(3 * i) - b.segment<3>(3 * i)).norm());
  return m;
}

// Vertices at least `r` (m) from the y axis.
std::vector<int> vertices_beyond(const ClothMesh& mesh, double r) {
  std::vector<int> v;
  for (int i = 0; i < mesh.num_vertices(); ++i)
    if (Eigen::Vector2d(mesh.rest[3 * i], mesh.rest[3 * i + 2]).norm() >= r) v.push_back(i);
  return v;
}

void expect_energy_decreases(const CollisionResolutionResult& r) {
  ASSERT_GE(r.energies.size(), 2u);
  for (size_t k = 1; k < r.energies.size(); ++k)
    EXPECT_LE(r.energies[k], r.energies[k - 1]) << "accepted iterate " << k << " raised the energy";
  EXPECT_LT(r.energies.back(), r.energies.front());
}

TEST(CollisionResolution, ClothPushedIntoASphereComesOut) {
  const ClothMesh mesh = flat_cloth();
  CollisionObstacles obstacles;
  obstacles.spheres = {poking_sphere()};
  const CollisionResolutionResult r = resolve_collisions(mesh, mesh.rest, obstacles, options());
  EXPECT_GT(r.before.vertices_inside, 50);
  EXPECT_NEAR(r.before.max_depth, 0.02, 1e-9);  // the centre vertex
  EXPECT_EQ(r.status, StepStatus::converged);
  EXPECT_LE(r.iterations, options().max_iterations);
  EXPECT_LE(r.after.max_depth, 1e-3);
  EXPECT_EQ(measure_penetration(r.x, obstacles).max_depth, r.after.max_depth);
  expect_energy_decreases(r);
  // The centre vertex was lifted at least the 2 cm it was inside.
  const int centre = 20 * 41 + 20;
  EXPECT_GE(r.x[3 * centre + 1] - mesh.rest[3 * centre + 1], 0.02 - 1e-3);
}

TEST(CollisionResolution, ClothAwayFromTheContactBarelyMoves) {
  const ClothMesh mesh = flat_cloth();
  CollisionObstacles obstacles;
  obstacles.spheres = {poking_sphere()};
  CollisionResolutionOptions o = options();
  const CollisionResolutionResult r = resolve_collisions(mesh, mesh.rest, obstacles, o);
  // The vertices inside reach 10.8 cm from the axis, the region `region_radius` beyond
  // along the cloth (plus one held ring, 2.5 cm). Outside it nothing moves; 5 cm beyond
  // the penetration, under a millimetre.
  EXPECT_EQ(max_move(r.x, mesh.rest, vertices_beyond(mesh, 0.108 + o.region_radius + 0.026)), 0.0);
  EXPECT_LT(max_move(r.x, mesh.rest, vertices_beyond(mesh, 0.158)), 1e-3);
  EXPECT_LT(r.region_vertices, mesh.num_vertices());

  // Solving the whole cloth gives the same answer to a fraction of a millimetre.
  o.region_radius = std::numeric_limits<double>::infinity();
  const CollisionResolutionResult whole = resolve_collisions(mesh, mesh.rest, obstacles, o);
  EXPECT_EQ(whole.region_vertices, mesh.num_vertices());
  std::vector<int> all(mesh.num_vertices());
  for (int i = 0; i < mesh.num_vertices(); ++i) all[i] = i;
  EXPECT_LT(max_move(r.x, whole.x, all), 2e-4);
  EXPECT_LE(whole.after.max_depth, 1e-3);
}

TEST(CollisionResolution, ClothPushedIntoABodyMeshComesOut) {
  // A box (a closed body mesh) 20 cm wide whose top is 2 cm above a wavy cloth: the cloth
  // over the top is inside, the deepest 2.5 cm.
  ClothMesh mesh = flat_cloth();
  Positions x0 = mesh.rest;
  for (int i = 0; i < mesh.num_vertices(); ++i) x0[3 * i + 1] = 0.005 * std::sin(20 * x0[3 * i] + 7 * x0[3 * i + 2]);
  const BodyMesh box = testing::cube(Vec3(0, -0.08, 0), 0.1);
  CollisionObstacles obstacles;
  obstacles.bodies = {&box};
  const CollisionResolutionResult r = resolve_collisions(mesh, x0, obstacles, options());
  EXPECT_GT(r.before.vertices_inside, 50);
  EXPECT_GT(r.before.max_depth, 0.02);
  EXPECT_NE(r.status, StepStatus::non_finite);
  EXPECT_LE(r.after.max_depth, 1e-3) << r.after.vertices_inside << " vertices inside after "
                                     << r.iterations << " iterations (" << to_string(r.status) << ")";
  expect_energy_decreases(r);
  EXPECT_LT(max_move(r.x, x0, vertices_beyond(mesh, 0.35)), 1e-3);
}

TEST(CollisionResolution, ClothClearOfTheObstacleIsReturnedUnchanged) {
  ClothMesh mesh = flat_cloth();
  CollisionObstacles obstacles;
  obstacles.spheres = {SphereObstacle{Vec3(0, -0.303, 0), 0.3}};  // 3 mm below the cloth: in the 5 mm band, not inside
  const CollisionResolutionResult r = resolve_collisions(mesh, mesh.rest, obstacles, options());
  EXPECT_EQ(r.iterations, 0);
  EXPECT_EQ(r.status, StepStatus::converged);
  EXPECT_EQ(r.x, mesh.rest);
  EXPECT_EQ(r.before.vertices_inside, 0);
  EXPECT_EQ(r.after.max_depth, 0.0);
  // A stretched and bent prediction clear of the obstacle, too: the elasticity is measured
  // from the prediction, so its shape exerts no force.
  Positions x0 = mesh.rest * 1.2;
  for (int i = 0; i < mesh.num_vertices(); ++i) x0[3 * i + 1] += 0.05 * std::cos(5 * x0[3 * i]) + 0.05;
  obstacles.spheres = {SphereObstacle{Vec3(0, -0.4, 0), 0.3}};
  const CollisionResolutionResult s = resolve_collisions(mesh, x0, obstacles, options());
  EXPECT_EQ(s.iterations, 0);
  EXPECT_EQ(s.x, x0);
}

TEST(CollisionResolution, HeldVerticesStayAtThePrediction) {
  const ClothMesh mesh = flat_cloth();
  CollisionObstacles obstacles;
  obstacles.spheres = {poking_sphere()};
  // The ring of vertices 15 cm from the axis, outside the sphere but where the lifted
  // cloth would pull them up.
  std::vector<int> held;
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    const double r = Eigen::Vector2d(mesh.rest[3 * i], mesh.rest[3 * i + 2]).norm();
    if (r > 0.14 && r < 0.16) held.push_back(i);
  }
  ASSERT_FALSE(held.empty());
  const CollisionResolutionResult free = resolve_collisions(mesh, mesh.rest, obstacles, options());
  const CollisionResolutionResult pinned = resolve_collisions(mesh, mesh.rest, obstacles, options(), held);
  EXPECT_LE(max_move(pinned.x, mesh.rest, held), max_move(free.x, mesh.rest, held));
  EXPECT_LT(max_move(pinned.x, mesh.rest, held), 2e-4);
}

TEST(CollisionResolution, CollapsedPredictedTrianglesAreNoObstacle) {
  // A prediction with two vertices on top of each other inside the sphere: their
  // triangles have no shape to measure elasticity from and are left out, the rest comes out.
  const ClothMesh mesh = flat_cloth();
  Positions x0 = mesh.rest;
  const int centre = 20 * 41 + 20;
  x0.segment<3>(3 * (centre + 1)) = x0.segment<3>(3 * centre);
  CollisionObstacles obstacles;
  obstacles.spheres = {poking_sphere()};
  const CollisionResolutionResult r = resolve_collisions(mesh, x0, obstacles, options());
  EXPECT_TRUE(r.x.allFinite());
  EXPECT_LE(r.after.max_depth, 1e-3);
  expect_energy_decreases(r);
}

TEST(CollisionResolution, BadInputIsOneClearError) {
  const ClothMesh mesh = flat_cloth();
  CollisionObstacles obstacles;
  obstacles.spheres = {poking_sphere()};
  auto expect_error = [&](const Positions& x, const std::vector<int>& held, const CollisionResolutionOptions& o,
                          const std::string& part) {
    try {
      resolve_collisions(mesh, x, obstacles, o, held);
      ADD_FAILURE() << "no error for " << part;
    } catch (const weft::Error& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  Positions nan = mesh.rest;
  nan[3 * 17 + 1] = std::numeric_limits<double>::quiet_NaN();
  expect_error(nan, {}, options(), "cloth vertex 17 has a non-finite position");
  expect_error(mesh.rest.head(30), {}, options(), "the cloth has 1681 vertices but the positions have 30 entries");
  expect_error(mesh.rest, {5000}, options(), "held vertex 5000");
  CollisionResolutionOptions o = options();
  o.proximal_stiffness = -1;
  expect_error(mesh.rest, {}, o, "proximal_stiffness");
  o = options();
  o.max_iterations = 0;
  expect_error(mesh.rest, {}, o, "max_iterations");
}

}  // namespace
}  // namespace weft::physics
