#include "capture/default_character.h"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "capture/atomic_file.h"
#include "capture/automatic_weights.h"
#include "capture/mesh_io.h"
#include "capture/skeletool_io.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;
using Eigen::Vector3d;

const char* garment_name(GarmentType type) {
  switch (type) {
    case GarmentType::skirt: return "skirt";
    case GarmentType::dress: return "dress";
    case GarmentType::none: break;
  }
  return "none";
}

// ------------------------------------------------------------------ config

namespace {

// One YAML mapping whose keys must all be known.
struct Keys {
  const YAML::Node& node;
  const std::string& file;
  std::string prefix;

  std::string key(const std::string& k) const { return prefix.empty() ? k : prefix + "." + k; }
  void allow(std::initializer_list<const char*> known) const {
    if (!node.IsMap()) fail(file, ": '", prefix.empty() ? "(top level)" : prefix, "' must be a mapping");
    const std::set<std::string> ok(known.begin(), known.end());
    for (const auto& kv : node) {
      const std::string k = kv.first.as<std::string>();
      if (ok.count(k)) continue;
      std::string list;
      for (const auto& o : ok) list += (list.empty() ? "" : ", ") + o;
      fail(file, ": unknown key '", key(k), "' (expected one of: ", list, ")");
    }
  }
  template <class T>
  void read(const char* k, T& out, const char* expected) const {
    const YAML::Node n = node[k];
    if (!n) return;
    try {
      if (!n.IsScalar()) fail(file, ": '", key(k), "' must be ", expected);
      out = n.as<T>();
    } catch (const YAML::Exception&) {
      fail(file, ":", n.Mark().line + 1, ": '", key(k), "' must be ", expected);
    }
  }
  void positive(const char* k, double& out) const {
    read(k, out, "a number");
    if (!(std::isfinite(out) && out > 0)) fail(file, ": '", key(k), "' must be > 0, got ", out);
  }
  void count(const char* k, int& out, int lo, int hi) const {
    read(k, out, "an integer");
    if (out < lo || out > hi) fail(file, ": '", key(k), "' must be in ", lo, "..", hi, ", got ", out);
  }
};

DefaultCharacterConfig parse_config(const YAML::Node& root, const std::string& file, const fs::path& dir) {
  DefaultCharacterConfig c;
  c.file = file;
  const Keys top{root, file, ""};
  top.allow({"name", "mesh", "height_m", "body", "garment"});
  top.read("name", c.name, "a string");
  top.read("mesh", c.mesh, "a file path");
  if (c.mesh.empty()) fail(file, ": 'mesh' must not be empty");
  if (fs::path(c.mesh).is_relative()) c.mesh = (dir / c.mesh).lexically_normal().string();
  top.positive("height_m", c.height_m);
  if (root["body"]) {
    const Keys b{root["body"], file, "body"};
    b.allow({"graph_nodes", "nodes_per_vertex"});
    b.count("graph_nodes", c.body_graph_nodes, 1, 100000);
    b.count("nodes_per_vertex", c.nodes_per_vertex, 1, 16);
  }
  if (root["garment"]) {
    const Keys g{root["garment"], file, "garment"};
    g.allow({"type", "length", "flare", "clearance", "top_offset", "straps", "segments", "rings",
             "graph_nodes", "rigidity"});
    std::string type = garment_name(c.garment);
    g.read("type", type, "skirt, dress or none");
    if (type == "skirt") c.garment = GarmentType::skirt;
    else if (type == "dress") c.garment = GarmentType::dress;
    else if (type == "none") c.garment = GarmentType::none;
    else fail(file, ": 'garment.type' must be skirt, dress or none, got '", type, "'");
    g.positive("length", c.length);
    g.read("flare", c.flare, "a number");
    if (!(std::isfinite(c.flare) && c.flare >= 0)) fail(file, ": 'garment.flare' must be ≥ 0, got ", c.flare);
    g.positive("clearance", c.clearance);
    g.read("top_offset", c.top_offset, "a number");
    if (!std::isfinite(c.top_offset)) fail(file, ": 'garment.top_offset' must be finite");
    g.read("straps", c.straps, "true or false");
    if (c.straps && c.garment != GarmentType::dress) fail(file, ": 'garment.straps' needs type: dress");
    g.count("segments", c.segments, 8, 4096);
    g.count("rings", c.rings, 2, 4096);
    g.count("graph_nodes", c.cloth_graph_nodes, 1, 100000);
    g.read("rigidity", c.cloth_rigidity, "a number");
    if (!(c.cloth_rigidity >= 0 && c.cloth_rigidity <= 1)) fail(file, ": 'garment.rigidity' must be in [0, 1]");
  }
  return c;
}

YAML::Node load_yaml(const std::string& text, const std::string& name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    fail(name, ":", e.mark.line + 1, ": invalid YAML: ", e.msg);
  }
}

}  // namespace

DefaultCharacterConfig parse_default_character_config(const std::string& yaml_text, const std::string& name) {
  const YAML::Node root = load_yaml(yaml_text, name);
  if (!root.IsMap()) fail(name, ": expected a map of character generation keys");
  return parse_config(root, name, fs::path(name).parent_path());
}

DefaultCharacterConfig load_default_character_config(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, ": cannot open file for reading");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_default_character_config(ss.str(), path);
}

// ------------------------------------------------------------------ building

DefaultCharacter make_default_character(const DefaultCharacterConfig& cfg) {
  const std::string what = cfg.file.empty() ? cfg.mesh : cfg.file;
  DefaultCharacter out;
  out.loaded = load_body_mesh(cfg.mesh, cfg.height_m);
  out.fit = fit_body_skeleton(out.loaded.mesh, out.loaded.extra, cfg.mesh);
  Character& ch = out.character;
  ch.name = cfg.name;
  ch.source = cfg.file;
  ch.metres_per_unit = 1.0;
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
  for (int f = 0; f < body.mesh.num_faces(); ++f)
    if (out.arm_vertices[body.mesh.F(f, 0)] && out.arm_vertices[body.mesh.F(f, 1)] && out.arm_vertices[body.mesh.F(f, 2)])
      ch.inactive_body_faces.push_back(f);

  if (cfg.garment != GarmentType::none) {
    TubeGarmentOptions o;
    o.length = cfg.length;
    o.flare = cfg.flare;
    o.clearance = cfg.clearance;
    o.segments = cfg.segments;
    o.rings = cfg.rings;
    o.top_y = cfg.garment == GarmentType::skirt ? out.fit.waist_y + cfg.top_offset : out.fit.armpit_y - cfg.top_offset;
    if (o.top_y - o.length < 0) fail(what, ": the garment's hem would be below the floor (top at ", o.top_y, " m, length ", o.length, " m)");
    TubeGarment g = generate_tube_garment(body.mesh, out.arm_vertices, o);
    if (cfg.straps)
      for (const char* side : {"l_", "r_"}) {
        // Over the shoulder 60 % of the way out to the shoulder joint; the part above the
        // clavicles is anchored.
        const Vector3d& sh = out.fit.joints.at(std::string(side) + "shoulder");
        const Vector3d& cl = out.fit.joints.at(std::string(side) + "clavicle");
        add_shoulder_strap(g, body.mesh, 0.6 * sh.x(), cfg.clearance, cl.y(), cfg.segments);
      }
    out.garment_min_distance = g.min_distance;
    out.garment_inside = g.inside;
    CharacterMesh cloth;
    cloth.path = std::string(garment_name(cfg.garment)) + ".obj";
    cloth.mesh = g.mesh;
    cloth.weights = transfer_weights_from_closest_point(body.mesh, body.weights, cloth.mesh);
    EmbeddedGraphOptions cgo;
    cgo.num_nodes = cfg.cloth_graph_nodes;
    cgo.nodes_per_vertex = cfg.nodes_per_vertex;
    cloth.graph = sample_embedded_graph(cloth.mesh, cgo);
    cloth.graph.rigidity = Eigen::VectorXd::Constant(cloth.graph.num_nodes(), cfg.cloth_rigidity);
    ch.attachment = attach_to_body(body.mesh, cloth.mesh, g.anchors);
    ch.cloth = std::move(cloth);
  }
  return out;
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

}  // namespace

std::string write_default_character(const DefaultCharacter& dc, const DefaultCharacterConfig& cfg,
                                    const std::string& dir) {
  const Character& ch = dc.character;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (!fs::is_directory(dir)) fail(dir, ": cannot create the output folder");
  const fs::path d(dir);
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
