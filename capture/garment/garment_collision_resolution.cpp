#include "capture/garment/garment_collision_resolution.h"

#include <chrono>

#include "capture/garment/garment_simulator.h"
#include "graph/error.h"

namespace weft::capture {

physics::CollisionResolutionOptions garment_collision_resolution_options(const SynthSimulationConfig& s) {
  physics::CollisionResolutionOptions o;
  o.material = s.material;
  o.collision_thickness = s.collision_thickness;
  o.collision_stiffness = s.collision_stiffness;
  o.pin_stiffness = s.pin_stiffness;
  return o;
}

GarmentCollisionResolver::GarmentCollisionResolver(const Character& character, const SynthSimulationConfig& s)
    : character_(character), options_(garment_collision_resolution_options(s)) {
  WEFT_CHECK(character.has_cloth(), character.source, ": the character has no garment to resolve collisions of");
  const TriangleMesh& cloth = character.cloth->mesh;
  std::vector<std::array<int, 3>> tris(cloth.num_faces());
  for (int i = 0; i < cloth.num_faces(); ++i) tris[i] = {cloth.F(i, 0), cloth.F(i, 1), cloth.F(i, 2)};
  mesh_ = physics::make_cloth_mesh(to_positions(cloth.V, character.metres_per_unit), std::move(tris),
                                   s.material.density);
}

GarmentCollisionResolver::~GarmentCollisionResolver() = default;

GarmentCollisionResolution GarmentCollisionResolver::resolve(const Vertices& body, const Vertices& cloth) {
  const int body_n = character_.body.mesh.num_vertices(), cloth_n = mesh_.num_vertices();
  WEFT_CHECK(body.rows() == body_n, "collision resolution: ", body.rows(), " body vertices given, the character ",
             character_.name, " has ", body_n);
  WEFT_CHECK(cloth.rows() == cloth_n, "collision resolution: ", cloth.rows(),
             " cloth vertices given, the character ", character_.name, "'s garment has ", cloth_n);
  WEFT_CHECK(body.allFinite(), "collision resolution: the body has a non-finite vertex");
  WEFT_CHECK(cloth.allFinite(), "collision resolution: the cloth has a non-finite vertex");
  const double mpu = character_.metres_per_unit;
  GarmentCollisionResolution r;
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::MatrixX3d body_metres = body * mpu;
  if (!body_)
    body_ = std::make_unique<physics::BodyMesh>(body_obstacle(character_, body_metres));
  else
    body_->set_vertices(body_metres);
  r.body_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  physics::CollisionObstacles obstacles;
  obstacles.bodies = {body_.get()};
  r.pass = physics::resolve_collisions(mesh_, to_positions(cloth, mpu), obstacles, options_);
  r.cloth = to_vertices(r.pass.x, mpu);
  return r;
}

GarmentCollisionResolution resolve_garment_collisions(const Character& character,
                                                      const SynthSimulationConfig& simulation, const Vertices& body,
                                                      const Vertices& cloth) {
  GarmentCollisionResolver resolver(character, simulation);
  return resolver.resolve(body, cloth);
}

}  // namespace weft::capture
