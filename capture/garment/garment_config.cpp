#include "capture/garment/garment_config.h"

#include <filesystem>

#include "files/text_reader.h"
#include "graph/error.h"
#include "physics/cloth_material_yaml.h"

namespace weft::capture {

void parse_simulation_config(const StrictYaml& y, const YAML::Node& n, SynthSimulationConfig& s) {
  y.check_keys(n, "simulation.", {"enabled", "substeps", "settle_frames", "material", "collision", "pins", "solver",
                                  "max_penetration", "friction", "max_body_motion", "max_step_halvings"});
  if (n["max_body_motion"]) s.max_body_motion = y.number(n["max_body_motion"], "simulation.max_body_motion", 0, 1);
  if (n["max_step_halvings"])
    s.max_step_halvings = static_cast<int>(y.number(n["max_step_halvings"], "simulation.max_step_halvings", 0, 10));
  if (n["friction"]) s.friction = y.number(n["friction"], "simulation.friction", 0, 10);
  if (n["enabled"]) s.enabled = y.get<bool>(n["enabled"], "simulation.enabled", "true or false");
  if (n["substeps"]) s.substeps = static_cast<int>(y.number(n["substeps"], "simulation.substeps", 1, 100));
  if (n["settle_frames"])
    s.settle_frames = static_cast<int>(y.number(n["settle_frames"], "simulation.settle_frames", 0, 10000));
  if (const YAML::Node m = n["material"]) physics::read_cloth_material(y, m, "simulation.material", s.material);
  if (const YAML::Node c = n["collision"]) {
    y.check_keys(c, "simulation.collision.", {"thickness", "stiffness", "second_sheet_deg", "smooth_creases"});
    if (c["second_sheet_deg"])
      s.collision_second_sheet_deg = y.number(c["second_sheet_deg"], "simulation.collision.second_sheet_deg", 0, 179);
    if (c["smooth_creases"])
      s.collision_smooth_creases = y.get<bool>(c["smooth_creases"], "simulation.collision.smooth_creases", "true or false");
    if (c["thickness"]) s.collision_thickness = y.positive(c["thickness"], "simulation.collision.thickness");
    if (c["stiffness"]) s.collision_stiffness = y.positive(c["stiffness"], "simulation.collision.stiffness");
  }
  if (const YAML::Node p = n["pins"]) {
    y.check_keys(p, "simulation.pins.", {"stiffness"});
    if (p["stiffness"]) s.pin_stiffness = y.positive(p["stiffness"], "simulation.pins.stiffness");
  }
  if (const YAML::Node v = n["solver"]) {
    y.check_keys(v, "simulation.solver.", {"max_iterations", "tolerance", "per_vertex_step_limits"});
    if (v["per_vertex_step_limits"])
      s.per_vertex_step_limits =
          y.get<bool>(v["per_vertex_step_limits"], "simulation.solver.per_vertex_step_limits", "true or false");
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

std::string simulation_config_yaml(const SynthSimulationConfig& s) {
  using physics::yaml_number;
  return std::string("simulation:\n") + "  enabled: " + (s.enabled ? "true" : "false") + "\n" +
         "  substeps: " + std::to_string(s.substeps) + "\n" +
         "  settle_frames: " + std::to_string(s.settle_frames) + "\n" +
         "  max_body_motion: " + yaml_number(s.max_body_motion) + "\n" +
         "  max_step_halvings: " + std::to_string(s.max_step_halvings) + "\n" +
         "  material: " + physics::cloth_material_yaml(s.material) + "\n" +
         "  collision: {thickness: " + yaml_number(s.collision_thickness) +
         ", stiffness: " + yaml_number(s.collision_stiffness) +
         ", second_sheet_deg: " + yaml_number(s.collision_second_sheet_deg) +
         ", smooth_creases: " + (s.collision_smooth_creases ? "true" : "false") + "}\n" +
         "  pins: {stiffness: " + yaml_number(s.pin_stiffness) + "}\n" +
         "  friction: " + yaml_number(s.friction) + "\n" +
         "  solver: {max_iterations: " + std::to_string(s.max_iterations) + ", tolerance: " + yaml_number(s.tolerance) +
         ", per_vertex_step_limits: " + (s.per_vertex_step_limits ? "true" : "false") + "}\n" +
         "  max_penetration: " + yaml_number(s.max_penetration) + "\n";
}

std::optional<SynthSimulationConfig> find_dataset_simulation(const std::string& dataset_dir) {
  const std::string file = (std::filesystem::path(dataset_dir) / "dataset.yaml").string();
  StrictYaml y;
  y.file = file;
  y.dir = dataset_dir;
  const YAML::Node root = y.parse(read_file_bytes(file));
  if (!root.IsMap()) y.fail_at(root, "(document)", "expected a mapping");
  if (!root["simulation"]) return std::nullopt;
  SynthSimulationConfig s;
  parse_simulation_config(y, root["simulation"], s);
  return s;
}

SynthSimulationConfig read_dataset_simulation(const std::string& dataset_dir) {
  std::optional<SynthSimulationConfig> s = find_dataset_simulation(dataset_dir);
  WEFT_CHECK(s.has_value(), (std::filesystem::path(dataset_dir) / "dataset.yaml").string(),
             ": missing key 'simulation' (the garment's simulation settings, which `weft synth` writes since "
             "datasets carry them): regenerate the dataset with `weft synth --config RECIPE --out ", dataset_dir, "`");
  return *s;
}

}  // namespace weft::capture
