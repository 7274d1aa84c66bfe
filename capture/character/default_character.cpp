#include "capture/character/default_character.h"


#include <algorithm>
#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "graph/atomic_file.h"
#include "capture/character/automatic_weights.h"
#include "capture/character/joint_limits.h"
#include "geometry/mesh_io.h"
#include "capture/character/skeletool_io.h"
#include "files/strict_yaml.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;
using Eigen::Vector3d;

// ------------------------------------------------------------------ config

namespace {

int count(const StrictYaml& y, const YAML::Node& n, const std::string& key, int lo, int hi) {
  const int v = y.get<int>(n, key, "an integer");
  if (v < lo || v > hi)
    y.fail_at(n, key, "expected an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + ", found " +
                          std::to_string(v));
  return v;
}

DefaultCharacterConfig parse_config(const StrictYaml& y, const YAML::Node& root) {
  DefaultCharacterConfig c;
  c.file = y.file;
  y.check_keys(root, "", {"name", "base", "mesh", "height_m", "body", "garment", "appearance", "joint_limits"});
  if (root["name"]) c.name = y.get<std::string>(root["name"], "name", "a string");
  if (root["base"]) {
    // An existing character.yaml dressed with a generated garment: its body is used as is.
    for (const char* k : {"mesh", "height_m", "body", "joint_limits"})
      if (root[k]) y.fail_at(root[k], k, "not with 'base' (the base character.yaml describes the body)");
    c.base = fs::absolute(y.path(root["base"], "base")).lexically_normal().string();
    const std::string ext = fs::path(c.base).extension().string();
    if (ext != ".yaml" && ext != ".yml") y.fail_at(root["base"], "base", "expected a character.yaml, found " + c.base);
    if (!root["name"]) c.name = fs::path(y.file).stem().string();
  } else {
    if (root["mesh"]) c.mesh = y.get<std::string>(root["mesh"], "mesh", "a file path");
    if (c.mesh.empty()) y.fail_at(root["mesh"], "mesh", "expected a file path, found an empty one");
    if (fs::path(c.mesh).is_relative()) c.mesh = (y.dir / c.mesh).lexically_normal().string();
    if (root["height_m"]) c.height_m = y.positive(root["height_m"], "height_m");
    if (const YAML::Node b = root["body"]) {
      y.check_keys(b, "body", {"graph_nodes", "nodes_per_vertex"});
      if (b["graph_nodes"]) c.body_graph_nodes = count(y, b["graph_nodes"], "body.graph_nodes", 1, 100000);
      if (b["nodes_per_vertex"]) c.nodes_per_vertex = count(y, b["nodes_per_vertex"], "body.nodes_per_vertex", 1, 16);
    }
  }
  if (const YAML::Node g = root["garment"]) {
    y.check_keys(g, "garment", {"type", "length", "flare", "clearance", "top_offset", "straps", "segments", "rings",
                                "graph_nodes", "rigidity"});
    if (const YAML::Node t = g["type"]) {
      const std::string type = y.get<std::string>(t, "garment.type", "skirt, dress or none");
      if (type == "skirt") c.garment = GarmentType::skirt;
      else if (type == "dress") c.garment = GarmentType::dress;
      else if (type == "none") c.garment = GarmentType::none;
      else y.fail_at(t, "garment.type", "expected skirt, dress or none, found '" + type + "'");
      if (!c.base.empty() && c.garment != GarmentType::skirt)
        y.fail_at(t, "garment.type", "a 'base' character is dressed with a skirt only, found '" + type + "'");
    }
    if (g["length"]) c.length = y.positive(g["length"], "garment.length");
    if (g["flare"]) c.flare = y.number(g["flare"], "garment.flare", 0, 1e3);
    if (g["clearance"]) c.clearance = y.positive(g["clearance"], "garment.clearance");
    if (g["top_offset"]) c.top_offset = y.number(g["top_offset"], "garment.top_offset");
    if (g["straps"]) {
      c.straps = y.get<bool>(g["straps"], "garment.straps", "true or false");
      if (c.straps && c.garment != GarmentType::dress) y.fail_at(g["straps"], "garment.straps", "needs type: dress");
    }
    if (g["segments"]) c.segments = count(y, g["segments"], "garment.segments", 8, 4096);
    if (g["rings"]) c.rings = count(y, g["rings"], "garment.rings", 2, 4096);
    if (g["graph_nodes"]) c.cloth_graph_nodes = count(y, g["graph_nodes"], "garment.graph_nodes", 1, 100000);
    if (g["rigidity"]) c.cloth_rigidity = y.number(g["rigidity"], "garment.rigidity", 0, 1);
  }
  if (root["appearance"]) c.appearance = parse_appearance(y, root["appearance"], "appearance");
  if (root["joint_limits"]) c.joint_limits = parse_body_joint_limits(y, root["joint_limits"], "joint_limits");
  return c;
}

}  // namespace

DefaultCharacterConfig parse_default_character_config(const std::string& yaml_text, const std::string& name) {
  const StrictYaml y{name, fs::path(name).parent_path()};
  const YAML::Node root = y.parse(yaml_text);
  if (!root.IsMap()) fail(name, ": expected a map of character generation keys");
  return parse_config(y, root);
}

DefaultCharacterConfig load_default_character_config(const std::string& path) {
  return parse_default_character_config(read_file_bytes(path), path);
}

// ------------------------------------------------------------------ building

namespace {

// The garment of a config in character units (lengths in the config are metres; flare is
// a ratio). top_y and mid_x are the caller's.
GarmentSpec garment_spec(const DefaultCharacterConfig& cfg, double metres_per_unit) {
  GarmentSpec spec;
  spec.type = cfg.garment;
  spec.tube.length = cfg.length / metres_per_unit;
  spec.tube.flare = cfg.flare;
  spec.tube.clearance = cfg.clearance / metres_per_unit;
  spec.tube.segments = cfg.segments;
  spec.tube.rings = cfg.rings;
  spec.graph_nodes = cfg.cloth_graph_nodes;
  spec.nodes_per_vertex = cfg.nodes_per_vertex;
  spec.rigidity = cfg.cloth_rigidity;
  return spec;
}

// The garment's colours (appearance.h), when there is one.
void paint_garment(DefaultCharacter& out, const DefaultCharacterConfig& cfg) {
  Character& ch = out.character;
  if (!ch.cloth) return;
  ch.cloth->mesh.colors =
      garment_colors(ch.cloth->mesh, out.garment_top_y, cfg.length / ch.metres_per_unit, cfg.appearance);
}

// The MakeHuman path: body from a mesh file, skeleton and landmarks fitted to it. Metres.
DefaultCharacter make_fitted_character(const DefaultCharacterConfig& cfg) {
  const std::string what = cfg.file.empty() ? cfg.mesh : cfg.file;
  DefaultCharacter out;
  out.loaded = load_body_mesh(cfg.mesh, cfg.height_m);
  out.fit = fit_body_skeleton(out.loaded.mesh, out.loaded.extra, cfg.mesh);
  Character& ch = out.character;
  ch.name = cfg.name;
  ch.source = cfg.file;
  ch.metres_per_unit = 1.0;
  apply_dof_limits(out.fit.skeleton, cfg.joint_limits, what);  // over the defaults of build_body_skeleton
  ch.skeleton = out.fit.skeleton;
  ch.rest_dofs = Eigen::VectorXd::Zero(ch.skeleton.num_dofs());  // the zero pose is the bind pose
  ch.bind = forward_kinematics(ch.skeleton, ch.rest_dofs);
  ch.zero_pose = ch.bind;
  ch.body25 = out.fit.body25;

  // The body, as load_character builds it from the written files: bone-distance weights,
  // a sampled graph with uniform rigidity.
  CharacterMesh& body = ch.body;
  body.path = cfg.mesh;
  body.mesh = out.loaded.mesh;
  body.weights = bone_distance_weights(body.mesh.V, ch.skeleton, ch.bind);
  EmbeddedGraphOptions go;
  go.num_nodes = cfg.body_graph_nodes;
  go.nodes_per_vertex = cfg.nodes_per_vertex;
  body.graph = sample_embedded_graph(body.mesh, go);
  body.graph.rigidity = Eigen::VectorXd::Ones(body.graph.num_nodes());

  // Arms and hands (by geometry): their faces are left out of collisions, and garments
  // are sized without them.
  out.arm_vertices = arm_vertices(body.mesh, out.fit);
  ch.inactive_body_faces = faces_of_vertices(body.mesh, out.arm_vertices);

  if (cfg.garment != GarmentType::none) {
    GarmentSpec spec = garment_spec(cfg, ch.metres_per_unit);
    spec.tube.top_y =
        cfg.garment == GarmentType::skirt ? out.fit.waist_y + cfg.top_offset : out.fit.armpit_y - cfg.top_offset;
    if (cfg.straps)
      for (const char* side : {"l_", "r_"}) {
        // Over the shoulder 60 % of the way out to the shoulder joint; the part above the
        // clavicles is anchored.
        const Vector3d& sh = out.fit.joints.at(std::string(side) + "shoulder");
        const Vector3d& cl = out.fit.joints.at(std::string(side) + "clavicle");
        spec.straps.push_back({0.6 * sh.x(), cl.y()});
      }
    out.garment_top_y = spec.tube.top_y;
    const GarmentFit fit = dress_character(ch, spec, out.arm_vertices, what);
    out.garment_min_distance = fit.min_distance;
    out.garment_inside = fit.inside;
  }
  if (cfg.appearance.textured) {
    body.mesh.colors = body_colors(body.mesh, out.fit, out.arm_vertices, cfg.appearance);
    paint_garment(out, cfg);
  }
  return out;
}

// The `base:` path: a loaded character.yaml, dressed as it is. The skirt's top ring is at
// the hips (the BODY_25 hip keypoints in the bind pose) + top_offset, its axis in the
// hips' midline plane; arms and hands by skinning weight (arm_vertices_from_skinning) are
// ignored when sizing it and join the inactive faces.
DefaultCharacter make_dressed_base_character(const DefaultCharacterConfig& cfg) {
  const std::string what = cfg.file.empty() ? cfg.base : cfg.file;
  DefaultCharacter out;
  Character& ch = out.character;
  ch = load_character(cfg.base);
  if (ch.has_cloth()) fail(what, ": the base character ", cfg.base, " already has a cloth; dress one without");
  ch.name = cfg.name;
  ch.source = cfg.file;
  out.arm_vertices = arm_vertices_from_skinning(ch);
  const std::vector<int> arm_faces = faces_of_vertices(ch.body.mesh, out.arm_vertices);
  std::vector<int>& inactive = ch.inactive_body_faces;
  inactive.insert(inactive.end(), arm_faces.begin(), arm_faces.end());
  std::sort(inactive.begin(), inactive.end());
  inactive.erase(std::unique(inactive.begin(), inactive.end()), inactive.end());
  if (cfg.garment != GarmentType::none) {
    const Vector3d hips = bind_pose_hip_centre(ch, what);
    GarmentSpec spec = garment_spec(cfg, ch.metres_per_unit);
    spec.tube.top_y = hips.y() + cfg.top_offset / ch.metres_per_unit;
    spec.tube.mid_x = hips.x();
    out.garment_top_y = spec.tube.top_y;
    const GarmentFit fit = dress_character(ch, spec, out.arm_vertices, what);
    out.garment_min_distance = fit.min_distance;
    out.garment_inside = fit.inside;
  }
  if (cfg.appearance.textured) paint_garment(out, cfg);
  return out;
}

}  // namespace

DefaultCharacter make_default_character(const DefaultCharacterConfig& cfg) {
  return cfg.base.empty() ? make_fitted_character(cfg) : make_dressed_base_character(cfg);
}

// ------------------------------------------------------------------ writing

namespace {

void write_indices(const std::string& path, const std::vector<int>& values) {
  std::string text;
  for (int v : values) text += std::to_string(v) + "\n";
  write_text_atomically(path, text);
}

// The shortest text that reads back as the same double.
std::string yaml_number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

// A base character.yaml with its paths made absolute (its files stay where they are),
// the dressed character's name, inactive faces (base's and the arms', written to `dir`) and
// the generated cloth.
std::string write_dressed_base_character(const DefaultCharacter& dc, const DefaultCharacterConfig& cfg,
                                         const fs::path& d) {
  const Character& ch = dc.character;
  const StrictYaml base_yaml{display_name(cfg.base), fs::path(cfg.base).parent_path()};
  YAML::Node root = base_yaml.parse(read_file_bytes(cfg.base));
  const fs::path base_dir = fs::path(cfg.base).parent_path();
  auto absolute = [&](YAML::Node node, const char* key) {
    if (node[key]) node[key] = (base_dir / node[key].as<std::string>()).lexically_normal().string();
  };
  root["name"] = ch.name;
  absolute(root, "skeleton");
  absolute(root, "rest_pose");
  YAML::Node body = root["body"];
  for (const char* key : {"mesh", "skin", "labels", "graph"}) absolute(body, key);
  body.remove("inactive_labels");  // their faces are in the written list
  body.remove("inactive_faces");
  if (!ch.inactive_body_faces.empty()) {
    write_indices((d / "inactive_faces.txt").string(), ch.inactive_body_faces);
    body["inactive_faces"] = "inactive_faces.txt";
  }
  if (ch.cloth) {
    const std::string mesh = std::string(garment_name(cfg.garment)) + ".obj";
    write_obj((d / mesh).string(), ch.cloth->mesh);
    std::vector<int> anchors(ch.attachment.anchors.data(), ch.attachment.anchors.data() + ch.attachment.size());
    write_indices((d / "anchors.txt").string(), anchors);
    YAML::Node cloth = root["cloth"];
    cloth["mesh"] = mesh;
    cloth["graph_nodes"] = ch.cloth->graph.num_nodes();
    cloth["nodes_per_vertex"] = cfg.nodes_per_vertex;
    cloth["rigidity"]["default"] = yaml_number(cfg.cloth_rigidity);
    cloth["anchors"] = "anchors.txt";
  }
  YAML::Emitter out;
  out << root;
  std::ostringstream y;
  y << "# Generated by `weft character` from " << (cfg.file.empty() ? std::string("a config") : cfg.file)
    << " (docs/CHARACTER.md,\n# \"Dressing an existing character\"). The base, " << cfg.base << ", its files\n"
    << "# referenced where they are (absolute paths, never copied), dressed with a generated "
    << garment_name(cfg.garment) << " (" << garment_name(cfg.garment) << ".obj, anchors.txt).\n"
    << "# inactive_faces.txt: the base's inactive faces and its arms and hands (by skinning weight).\n"
    << out.c_str() << "\n";
  const std::string yaml = (d / "character.yaml").string();
  write_text_atomically(yaml, y.str());
  return yaml;
}

}  // namespace

std::string write_default_character(const DefaultCharacter& dc, const DefaultCharacterConfig& cfg,
                                    const std::string& dir) {
  const Character& ch = dc.character;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) fail(dir, ": cannot create the output folder");
  const fs::path d(dir);
  if (!cfg.base.empty()) return write_dressed_base_character(dc, cfg, d);
  write_obj((d / "body.obj").string(), ch.body.mesh);
  write_skeleton((d / "body.skeleton").string(), ch.skeleton);
  Motion rest;
  rest.frame_ids = {0};
  rest.dofs = ch.rest_dofs.transpose();
  write_motion((d / "rest.motion").string(), rest);
  write_indices((d / "inactive_faces.txt").string(), ch.inactive_body_faces);

  std::ostringstream y;
  y << "# Generated by `weft character` from " << (cfg.file.empty() ? std::string("defaults") : cfg.file)
    << " (docs/CHARACTER.md, \"Generated characters\").\n"
    << "# Source body: " << cfg.mesh << ", scaled to " << yaml_number(cfg.height_m) << " m. Metres, Y up, facing +z,\n"
    << "# the character's left at +x. The skeleton's zero pose is the bind pose (A-pose).\n"
    << "name: " << ch.name << "\n"
    << "metres_per_unit: 1\n"
    << "skeleton: body.skeleton\n"
    << "rest_pose: rest.motion\n"
    << "body:\n"
    << "  mesh: body.obj\n"
    << "  graph_nodes: " << ch.body.graph.num_nodes() << "\n"
    << "  nodes_per_vertex: " << cfg.nodes_per_vertex << "\n"
    << "  rigidity: {default: 1.0}\n"
    << "  inactive_faces: inactive_faces.txt   # arms and hands: left out of collisions\n";
  if (ch.cloth) {
    const std::string mesh = std::string(garment_name(cfg.garment)) + ".obj";
    write_obj((d / mesh).string(), ch.cloth->mesh);
    std::vector<int> anchors(ch.attachment.anchors.data(), ch.attachment.anchors.data() + ch.attachment.size());
    write_indices((d / "anchors.txt").string(), anchors);
    y << "cloth:\n"
      << "  mesh: " << mesh << "\n"
      << "  graph_nodes: " << ch.cloth->graph.num_nodes() << "\n"
      << "  nodes_per_vertex: " << cfg.nodes_per_vertex << "\n"
      << "  rigidity: {default: " << yaml_number(cfg.cloth_rigidity) << "}\n"
      << "  anchors: anchors.txt   # the top ring\n";
  }
  y << "body25:\n";
  for (int k = 0; k < kBody25Count; ++k) {
    const LandmarkSource& s = ch.body25[k];
    if (s.empty()) continue;
    std::vector<std::string> names;
    for (int j : s.joints) names.push_back(ch.skeleton.joints[j].name);
    for (int m : s.markers) names.push_back(ch.skeleton.markers[m].name);
    y << "  " << kBody25Names[k] << ": ";
    if (names.size() == 1) {
      y << names[0] << "\n";
    } else {
      y << "[";
      for (size_t i = 0; i < names.size(); ++i) y << (i ? ", " : "") << names[i];
      y << "]\n";
    }
  }
  const std::string yaml = (d / "character.yaml").string();
  write_text_atomically(yaml, y.str());
  return yaml;
}

}  // namespace weft::capture
