#include "capture/garment/garment_config.h"

#include <filesystem>

#include "files/text_reader.h"
#include "physics/cloth_material_yaml.h"

namespace weft::capture {

void parse_simulation_config(const StrictYaml& y, const YAML::Node& n, SynthSimulationConfig& s) {
  y.check_keys(n, "simulation.", {"enabled", "substeps", "settle_frames", "material", "collision", "pins", "solver",
                                  "max_penetration", "friction"});
  if (n["friction"]) s.friction = y.number(n["friction"], "simulation.friction", 0, 10);
  if (n["enabled"]) s.enabled = y.get<bool>(n["enabled"], "simulation.enabled", "true or false");
  if (n["substeps"]) s.substeps = static_cast<int>(y.number(n["substeps"], "simulation.substeps", 1, 100));
  if (n["settle_frames"])
    s.settle_frames = static_cast<int>(y.number(n["settle_frames"], "simulation.settle_frames", 0, 10000));
  if (const YAML::Node m = n["material"]) physics::read_cloth_material(y, m, "simulation.material", s.material);
  if (const YAML::Node c = n["collision"]) {
    y.check_keys(c, "simulation.collision.", {"thickness", "stiffness"});
    if (c["thickness"]) s.collision_thickness = y.positive(c["thickness"], "simulation.collision.thickness");
    if (c["stiffness"]) s.collision_stiffness = y.positive(c["stiffness"], "simulation.collision.stiffness");
  }
  if (const YAML::Node p = n["pins"]) {
    y.check_keys(p, "simulation.pins.", {"stiffness"});
    if (p["stiffness"]) s.pin_stiffness = y.positive(p["stiffness"], "simulation.pins.stiffness");
  }
  if (const YAML::Node v = n["solver"]) {
    y.check_keys(v, "simulation.solver.", {"max_iterations", "tolerance"});
    if (v["max_iterations"])
      s.max_iterations = static_cast<int>(y.number(v["max_iterations"], "simulation.solver.max_iterations", 1, 10000));
    if (v["tolerance"]) s.tolerance = y.positive(v["tolerance"], "simulation.solver.tolerance");
  }
  if (n["max_penetration"]) s.max_penetration = y.positive(n["max_penetration"], "simulation.max_penetration");
}

SynthSimulationConfig load_simulation_config(const std::string& synth_config) {
  StrictYaml y;
  y.file = display_name(synth_config);
  y.dir = std::filesystem::path(synth_config).parent_path();
  const YAML::Node root = y.parse(read_file_bytes(synth_config));
  if (!root.IsMap()) y.fail_at(root, "(document)", "expected a mapping");
  SynthSimulationConfig s;
  if (root["simulation"]) parse_simulation_config(y, root["simulation"], s);
  return s;
}

}  // namespace weft::capture
