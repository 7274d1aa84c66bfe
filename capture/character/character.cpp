#include "capture/character/character.h"


#include <algorithm>
#include <filesystem>
#include <limits>
#include <set>

#include "capture/character/automatic_weights.h"
#include "geometry/mesh_io.h"
#include "files/strict_yaml.h"
#include "capture/character/skeletool_io.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

std::vector<int> read_index_list(const std::string& path) {
  TextReader in(path);
  std::vector<int> out;
  while (in.next_line())
    for (std::string_view t : in.tokens()) {
      const long long v = in.to_int(t, "an integer");
      if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max()) in.fail("integer ", v, " out of range");
      out.push_back(static_cast<int>(v));
    }
  return out;
}

namespace {

int find_joint_or_marker(const Skeleton& s, const std::string& name, LandmarkSource& src) {
  if (const int j = s.joint_index(name); j >= 0) {
    src.joints.push_back(j);
    return 1;
  }
  if (const int m = s.marker_index(name); m >= 0) {
    src.markers.push_back(m);
    return 1;
  }
  return 0;
}

std::vector<int> inactive_faces_from_labels(const TriangleMesh& mesh, const std::vector<int>& labels,
                                            const std::set<int>& inactive) {
  std::vector<int> faces;
  for (int f = 0; f < mesh.num_faces(); ++f) {
    bool all = true;
    for (int k = 0; k < 3; ++k) all = all && inactive.count(labels[mesh.F(f, k)]);
    if (all) faces.push_back(f);
  }
  return faces;
}

// Loads one mesh section (body or cloth).
CharacterMesh load_mesh_section(const StrictYaml& ctx, const YAML::Node& node, const std::string& section,
                                const Character& ch, const CharacterMesh* body_for_transfer,
                                std::vector<int>* inactive_faces, std::vector<int>* anchors) {
  if (section == "body")
    ctx.check_keys(node, section, {"mesh", "skin", "labels", "graph", "graph_nodes", "nodes_per_vertex",
                                   "rigidity", "inactive_faces", "inactive_labels"});
  else
    ctx.check_keys(node, section, {"mesh", "skin", "labels", "graph", "graph_nodes", "nodes_per_vertex",
                                   "rigidity", "anchors"});
  CharacterMesh cm;
  if (!node["mesh"]) ctx.fail_at(node, section, "missing key 'mesh'");
  cm.path = ctx.path(node["mesh"], section + ".mesh");
  cm.mesh = read_mesh(cm.path);
  validate_mesh(cm.mesh, cm.path);
  if (cm.mesh.num_faces() == 0) ctx.fail_at(node["mesh"], section + ".mesh", "mesh has no triangles");
  const int n = cm.mesh.num_vertices();

  // Skinning weights: given, transferred from the body (cloth), or from bone distances.
  if (node["skin"]) {
    cm.weights = read_skin(ctx.path(node["skin"], section + ".skin"), ch.skeleton, n);
  } else if (body_for_transfer) {
    cm.weights = transfer_weights_from_closest_point(body_for_transfer->mesh, body_for_transfer->weights, cm.mesh);
  } else {
    cm.weights = bone_distance_weights(cm.mesh.V, ch.skeleton, ch.bind);
  }

  if (node["labels"]) {
    const std::string p = ctx.path(node["labels"], section + ".labels");
    cm.labels = read_index_list(p);
    if (static_cast<int>(cm.labels.size()) != n)
      ctx.fail_at(node["labels"], section + ".labels",
                  display_name(p) + " has " + std::to_string(cm.labels.size()) + " labels, expected one per vertex (" +
                      std::to_string(n) + ")");
  }

  EmbeddedGraphOptions go;
  if (node["nodes_per_vertex"]) {
    go.nodes_per_vertex = ctx.get<int>(node["nodes_per_vertex"], section + ".nodes_per_vertex", "an integer");
    if (go.nodes_per_vertex < 1 || go.nodes_per_vertex > 16)
      ctx.fail_at(node["nodes_per_vertex"], section + ".nodes_per_vertex", "expected 1..16");
  }
  if (node["graph"] && node["graph_nodes"])
    ctx.fail_at(node["graph_nodes"], section + ".graph_nodes", "give either 'graph' or 'graph_nodes', not both");
  if (node["graph"]) {
    const std::string p = ctx.path(node["graph"], section + ".graph");
    cm.graph = embedded_graph_from_mesh(read_mesh(p), cm.mesh, go);
  } else {
    if (node["graph_nodes"]) {
      go.num_nodes = ctx.get<int>(node["graph_nodes"], section + ".graph_nodes", "an integer");
      if (go.num_nodes < 1) ctx.fail_at(node["graph_nodes"], section + ".graph_nodes", "expected a positive integer");
    }
    cm.graph = sample_embedded_graph(cm.mesh, go);
  }

  // Rigidity by label.
  if (node["rigidity"]) {
    const YAML::Node r = node["rigidity"];
    ctx.check_keys(r, section + ".rigidity", {"default", "labels"});
    const double def = r["default"] ? ctx.get<double>(r["default"], section + ".rigidity.default", "a number") : 1.0;
    std::map<int, double> by_label;
    if (r["labels"]) {
      if (!r["labels"].IsMap()) ctx.fail_at(r["labels"], section + ".rigidity.labels", "expected a map label: rigidity");
      for (const auto& kv : r["labels"])
        by_label[ctx.get<int>(kv.first, section + ".rigidity.labels", "an integer label")] =
            ctx.get<double>(kv.second, section + ".rigidity.labels", "a number");
      if (cm.labels.empty()) ctx.fail_at(r["labels"], section + ".rigidity.labels", "needs '" + section + ".labels'");
    }
    if (cm.labels.empty()) cm.graph.rigidity = Eigen::VectorXd::Constant(cm.graph.num_nodes(), def);
    else cm.graph.rigidity = node_rigidity(cm.graph, cm.mesh.V, cm.labels, by_label, def);
  }

  if (inactive_faces) {
    if (node["inactive_faces"]) {
      const std::string p = ctx.path(node["inactive_faces"], section + ".inactive_faces");
      for (int f : read_index_list(p)) {
        if (f < 0 || f >= cm.mesh.num_faces())
          ctx.fail_at(node["inactive_faces"], section + ".inactive_faces",
                      display_name(p) + ": face index " + std::to_string(f) + " out of range (" +
                          std::to_string(cm.mesh.num_faces()) + " faces)");
        inactive_faces->push_back(f);
      }
    }
    if (node["inactive_labels"]) {
      if (cm.labels.empty()) ctx.fail_at(node["inactive_labels"], section + ".inactive_labels", "needs 'body.labels'");
      const auto list = ctx.get<std::vector<int>>(node["inactive_labels"], section + ".inactive_labels", "a list of labels");
      const auto faces = inactive_faces_from_labels(cm.mesh, cm.labels, {list.begin(), list.end()});
      inactive_faces->insert(inactive_faces->end(), faces.begin(), faces.end());
    }
    std::sort(inactive_faces->begin(), inactive_faces->end());
    inactive_faces->erase(std::unique(inactive_faces->begin(), inactive_faces->end()), inactive_faces->end());
  }
  if (anchors && node["anchors"]) {
    const std::string p = ctx.path(node["anchors"], section + ".anchors");
    for (int v : read_index_list(p)) {
      if (v < 0 || v >= n)
        ctx.fail_at(node["anchors"], section + ".anchors",
                    display_name(p) + ": vertex index " + std::to_string(v) + " out of range (" + std::to_string(n) + " vertices)");
      anchors->push_back(v);
    }
  }
  return cm;
}

void finish_character(Character& ch) {
  ch.zero_pose = forward_kinematics(ch.skeleton, Eigen::VectorXd::Zero(ch.skeleton.num_dofs()));
  if (ch.bind.empty()) ch.bind = forward_kinematics(ch.skeleton, ch.rest_dofs);
}

}  // namespace

Character load_character_yaml(const std::string& path) {
  StrictYaml ctx{display_name(path), fs::path(path).parent_path()};
  const YAML::Node root = ctx.parse(read_file_bytes(path));
  if (!root.IsMap()) fail(ctx.file, ": expected a map of character keys");
  ctx.check_keys(root, "", {"name", "metres_per_unit", "skeleton", "rest_pose", "rest_pose_frame", "body", "cloth", "body25"});
  Character ch;
  ch.source = path;
  ch.name = root["name"] ? ctx.get<std::string>(root["name"], "name", "a string") : fs::path(path).stem().string();
  if (root["metres_per_unit"]) {
    ch.metres_per_unit = ctx.get<double>(root["metres_per_unit"], "metres_per_unit", "a number");
    if (!(ch.metres_per_unit > 0) || !std::isfinite(ch.metres_per_unit))
      ctx.fail_at(root["metres_per_unit"], "metres_per_unit", "expected a positive number");
  }
  if (!root["skeleton"]) fail(ctx.file, ": missing key 'skeleton'");
  ch.skeleton = read_skeleton(ctx.path(root["skeleton"], "skeleton"));
  if (root["rest_pose"]) {
    const Motion rest = read_motion(ctx.path(root["rest_pose"], "rest_pose"), ch.skeleton.num_dofs());
    int frame = 0;
    if (root["rest_pose_frame"]) frame = ctx.get<int>(root["rest_pose_frame"], "rest_pose_frame", "an integer");
    if (frame < 0 || frame >= rest.num_frames())
      ctx.fail_at(root["rest_pose_frame"], "rest_pose_frame", "frame out of range (" + std::to_string(rest.num_frames()) + " frames)");
    ch.rest_dofs = rest.dofs.row(frame).transpose();
  } else {
    ch.rest_dofs = Eigen::VectorXd::Zero(ch.skeleton.num_dofs());
  }
  finish_character(ch);
  if (!root["body"]) fail(ctx.file, ": missing key 'body'");
  ch.body = load_mesh_section(ctx, root["body"], "body", ch, nullptr, &ch.inactive_body_faces, nullptr);
  if (root["cloth"]) {
    std::vector<int> anchors;
    ch.cloth = load_mesh_section(ctx, root["cloth"], "cloth", ch, &ch.body, nullptr, &anchors);
    ch.attachment = attach_to_body(ch.body.mesh, ch.cloth->mesh, anchors);
  }
  if (root["body25"]) {
    const YAML::Node map = root["body25"];
    if (!map.IsMap()) ctx.fail_at(map, "body25", "expected a map keypoint: joint or marker name(s)");
    for (const auto& kv : map) {
      const std::string kp = ctx.get<std::string>(kv.first, "body25", "a BODY_25 keypoint name");
      const int idx = body25_index(kp);
      if (idx < 0) ctx.fail_at(kv.first, "body25." + kp, "not a BODY_25 keypoint name (Nose, Neck, RShoulder, …)");
      std::vector<std::string> names;
      if (kv.second.IsSequence()) names = ctx.get<std::vector<std::string>>(kv.second, "body25." + kp, "names");
      else names.push_back(ctx.get<std::string>(kv.second, "body25." + kp, "a joint or marker name"));
      LandmarkSource src;
      for (const std::string& n : names)
        if (!find_joint_or_marker(ch.skeleton, n, src))
          ctx.fail_at(kv.second, "body25." + kp, "'" + n + "' is neither a joint nor a marker of the skeleton");
      ch.body25[idx] = src;
    }
  }
  return ch;
}

Character load_skeletool_character(const std::string& path) {
  const SkeletoolCharacterFiles files = read_skeletool_character(path);
  Character ch;
  ch.source = path;
  ch.name = fs::path(path).stem().string();
  ch.metres_per_unit = 0.001;
  ch.skeleton = read_skeleton(files.skeleton);
  ch.rest_dofs = files.pose.empty() ? Eigen::VectorXd::Zero(ch.skeleton.num_dofs())
                                    : Eigen::VectorXd(read_motion(files.pose, ch.skeleton.num_dofs()).dofs.row(0).transpose());
  finish_character(ch);
  ch.body.path = files.mesh;
  ch.body.mesh = read_mesh(files.mesh);
  validate_mesh(ch.body.mesh, files.mesh);
  ch.body.weights = files.skin.empty() ? bone_distance_weights(ch.body.mesh.V, ch.skeleton, ch.bind)
                                       : read_skin(files.skin, ch.skeleton, ch.body.mesh.num_vertices());
  ch.body.graph = sample_embedded_graph(ch.body.mesh);
  return ch;
}

namespace {
Character load_by_extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".yaml" || ext == ".yml") return load_character_yaml(path);
  if (ext == ".character") return load_skeletool_character(path);
  fail(path, ": unknown character format '", ext, "' (expected .yaml, .yml or .character)");
}
}  // namespace

Character load_character(const std::string& path) {
  try {
    return load_by_extension(path);
  } catch (const YAML::Exception& e) {  // conversions deep inside yaml-cpp
    fail(display_name(path), ":", e.mark.line + 1, ": ", e.msg);
  }
}

Vertices body25_positions(const Character& ch, const Transforms& joints, const Vertices& markers) {
  Vertices out(kBody25Count, 3);
  for (int k = 0; k < kBody25Count; ++k) {
    const LandmarkSource& src = ch.body25[k];
    if (src.empty()) {
      out.row(k).setConstant(std::numeric_limits<double>::quiet_NaN());
      continue;
    }
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int j : src.joints) sum += joints[j].translation();
    for (int m : src.markers) sum += markers.row(m).transpose();
    out.row(k) = (sum / static_cast<double>(src.joints.size() + src.markers.size())).transpose();
  }
  return out;
}

PosedCharacter pose_character(const Character& ch, const Eigen::VectorXd& dofs, SkinningMethod method) {
  PosedCharacter p;
  p.joints = forward_kinematics(ch.skeleton, dofs);
  const Transforms S = skinning_transforms(p.joints, ch.bind);
  auto skin = [&](const CharacterMesh& m) {
    return method == SkinningMethod::dual_quaternion ? dual_quaternion_skinning(m.mesh.V, m.weights, S)
                                                     : linear_blend_skinning(m.mesh.V, m.weights, S);
  };
  p.body = skin(ch.body);
  if (ch.cloth) p.cloth = skin(*ch.cloth);
  p.markers = marker_positions(ch.skeleton, p.joints, ch.zero_pose);
  p.body25 = body25_positions(ch, p.joints, p.markers);
  return p;
}

}  // namespace weft::capture
