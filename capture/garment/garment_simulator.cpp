#include "capture/garment/garment_simulator.h"

#include "graph/error.h"

namespace weft::capture {

physics::Positions to_positions(const Vertices& V, double metres_per_unit) {
  physics::Positions x(3 * V.rows());
  for (int i = 0; i < V.rows(); ++i) x.segment<3>(3 * i) = V.row(i).transpose() * metres_per_unit;
  return x;
}

Vertices to_vertices(const physics::Positions& x, double metres_per_unit) {
  Vertices V(x.size() / 3, 3);
  for (int i = 0; i < V.rows(); ++i) V.row(i) = x.segment<3>(3 * i).transpose() / metres_per_unit;
  return V;
}

physics::SimulationSettings garment_simulation_settings(const SynthSimulationConfig& s, double fps,
                                                        double ray_stiffness) {
  physics::SimulationSettings settings;
  settings.time_step = 1.0 / fps;
  settings.substeps = s.substeps;
  settings.max_body_motion = s.max_body_motion;
  settings.max_step_halvings = s.max_step_halvings;
  settings.material = s.material;
  settings.collision_thickness = s.collision_thickness;
  settings.collision_stiffness = s.collision_stiffness;
  settings.collision_second_sheet_deg = s.collision_second_sheet_deg;
  settings.collision_smooth_creases = s.collision_smooth_creases;
  settings.pin_stiffness = s.pin_stiffness;
  settings.newton.max_iterations = s.max_iterations;
  settings.newton.tolerance = s.tolerance;
  settings.newton.per_vertex_step_limits = s.per_vertex_step_limits;
  if (ray_stiffness >= 0) settings.constraint_stiffness = ray_stiffness;
  return settings;
}

std::vector<int> garment_pin_vertices(const Character& ch) {
  return std::vector<int>(ch.attachment.anchors.data(), ch.attachment.anchors.data() + ch.attachment.size());
}

std::vector<physics::Vec3> garment_pin_targets(const Character& ch, const Vertices& posed_cloth) {
  std::vector<physics::Vec3> t;
  t.reserve(ch.attachment.size());
  for (int a : garment_pin_vertices(ch)) t.push_back(posed_cloth.row(a).transpose() * ch.metres_per_unit);
  return t;
}

std::vector<physics::Vec3> garment_pin_targets_on_body(const Character& ch, const Vertices& body) {
  WEFT_CHECK(ch.has_cloth(), ch.source, ": the character has no garment to pin");
  const Vertices& rest = ch.body.mesh.V;
  WEFT_CHECK(body.rows() == rest.rows(), "garment pins: ", body.rows(), " body vertices, the character has ",
             rest.rows());
  const Attachment& at = ch.attachment;
  std::vector<physics::Vec3> t;
  t.reserve(at.size());
  for (int i = 0; i < at.size(); ++i) {
    const int a = at.body_vertices(i, 0), b = at.body_vertices(i, 1), c = at.body_vertices(i, 2);
    auto frame = [&](const Vertices& V) {
      Eigen::Matrix3d m;
      m.col(0) = (V.row(b) - V.row(a)).transpose();
      m.col(1) = (V.row(c) - V.row(a)).transpose();
      m.col(2) = m.col(0).cross(m.col(1)).normalized();
      return m;
    };
    const Eigen::Vector3d offset = ch.cloth->mesh.V.row(at.anchors(i)).transpose() - rest.row(a).transpose();
    const Eigen::Vector3d coefficients = frame(rest).colPivHouseholderQr().solve(offset);
    t.push_back((body.row(a).transpose() + frame(body) * coefficients) * ch.metres_per_unit);
  }
  return t;
}

physics::BodyMesh body_obstacle(const Character& ch, const Eigen::MatrixX3d& body_metres) {
  const Faces& F = ch.body.mesh.F;
  std::vector<std::array<int, 3>> faces(F.rows());
  for (int i = 0; i < F.rows(); ++i) faces[i] = {F(i, 0), F(i, 1), F(i, 2)};
  return physics::BodyMesh(body_metres, std::move(faces), ch.inactive_body_faces);
}

namespace {

physics::ClothMesh garment_cloth_mesh(const Character& ch, const SynthSimulationConfig& s) {
  const TriangleMesh& cloth_mesh = ch.cloth->mesh;
  std::vector<std::array<int, 3>> tris(cloth_mesh.num_faces());
  for (int i = 0; i < cloth_mesh.num_faces(); ++i) tris[i] = {cloth_mesh.F(i, 0), cloth_mesh.F(i, 1), cloth_mesh.F(i, 2)};
  return physics::make_cloth_mesh(to_positions(cloth_mesh.V, ch.metres_per_unit), tris, s.material.density);
}

std::unique_ptr<physics::ClothSimulator> assemble_garment_simulator(const Character& ch, const SynthSimulationConfig& s,
                                                                    double fps, physics::ClothMesh cloth,
                                                                    physics::BodyMesh body,
                                                                    const std::vector<physics::Vec3>& pin_targets,
                                                                    double ray_stiffness) {
  auto sim = std::make_unique<physics::ClothSimulator>(std::move(cloth), garment_simulation_settings(s, fps, ray_stiffness));
  sim->add_body(std::move(body), s.friction);
  sim->set_pins(garment_pin_vertices(ch), pin_targets);
  return sim;
}

}  // namespace

std::unique_ptr<physics::ClothSimulator> make_garment_simulator(const Character& ch,
                                                                const SynthSimulationConfig& s, double fps,
                                                                const Eigen::MatrixX3d& body_metres,
                                                                const std::vector<physics::Vec3>& pin_targets,
                                                                double ray_stiffness) {
  WEFT_CHECK(ch.has_cloth(), ch.source, ": the character has no garment to simulate");
  return assemble_garment_simulator(ch, s, fps, garment_cloth_mesh(ch, s), body_obstacle(ch, body_metres), pin_targets,
                                    ray_stiffness);
}

physics::SimulatorFactory garment_simulator_factory(const Character& ch, const SynthSimulationConfig& s,
                                                    double fps, double ray_stiffness) {
  WEFT_CHECK(ch.has_cloth(), ch.source, ": the character has no garment to simulate");
  auto character = std::make_shared<const Character>(ch);
  auto pins = std::make_shared<const std::vector<physics::Vec3>>(garment_pin_targets(ch, ch.cloth->mesh.V));
  // The cloth's rest state and the body's search tree are built once and copied per call:
  // building them per call took 18 of a 448-vertex window's 269 ms CPU (bench_simulation_windows).
  auto cloth = std::make_shared<const physics::ClothMesh>(garment_cloth_mesh(ch, s));
  auto body = std::make_shared<const physics::BodyMesh>(body_obstacle(ch, ch.body.mesh.V * ch.metres_per_unit));
  return [character, s, fps, cloth, body, pins, ray_stiffness]() {
    return assemble_garment_simulator(*character, s, fps, *cloth, *body, *pins, ray_stiffness);
  };
}

}  // namespace weft::capture
