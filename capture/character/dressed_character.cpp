#include "capture/character/dressed_character.h"

#include <algorithm>
#include <cstring>

#include "capture/character/automatic_weights.h"
#include "graph/error.h"

namespace weft::capture {

const char* garment_name(GarmentType type) {
  switch (type) {
    case GarmentType::skirt: return "skirt";
    case GarmentType::dress: return "dress";
    case GarmentType::none: break;
  }
  return "none";
}

GarmentFit dress_character(Character& ch, const GarmentSpec& spec, const std::vector<char>& excluded,
                           const std::string& what) {
  if (spec.type == GarmentType::none) fail(what, ": dress_character needs a garment type (skirt or dress)");
  const CharacterMesh& body = ch.body;
  const TubeGarmentOptions& o = spec.tube;
  const double floor_y = body.mesh.V.col(1).minCoeff();
  if (o.top_y - o.length < floor_y)
    fail(what, ": the garment's hem would be below the body's lowest point (top at ", o.top_y, ", length ",
         o.length, ", lowest point ", floor_y, "; character units)");
  TubeGarment g = generate_tube_garment(body.mesh, excluded, o);
  for (const ShoulderStrap& s : spec.straps)
    add_shoulder_strap(g, body.mesh, s.x, o.clearance, s.anchor_y, o.segments);

  CharacterMesh cloth;
  cloth.path = std::string(garment_name(spec.type)) + ".obj";
  cloth.mesh = g.mesh;
  cloth.weights = transfer_weights_from_closest_point(body.mesh, body.weights, cloth.mesh);
  EmbeddedGraphOptions go;
  go.num_nodes = spec.graph_nodes;
  go.nodes_per_vertex = spec.nodes_per_vertex;
  cloth.graph = sample_embedded_graph(cloth.mesh, go);
  cloth.graph.rigidity = Eigen::VectorXd::Constant(cloth.graph.num_nodes(), spec.rigidity);
  ch.attachment = attach_to_body(body.mesh, cloth.mesh, g.anchors);
  ch.cloth = std::move(cloth);
  return {g.min_distance, g.inside};
}

std::vector<int> faces_of_vertices(const TriangleMesh& mesh, const std::vector<char>& vertices) {
  std::vector<int> faces;
  if (vertices.empty()) return faces;
  for (int f = 0; f < mesh.num_faces(); ++f)
    if (vertices[mesh.F(f, 0)] && vertices[mesh.F(f, 1)] && vertices[mesh.F(f, 2)]) faces.push_back(f);
  return faces;
}

namespace {

int body25_index(const char* name) {
  for (int k = 0; k < kBody25Count; ++k)
    if (std::strcmp(kBody25Names[k], name) == 0) return k;
  fail("BODY_25 has no keypoint '", name, "'");
}

}  // namespace

std::vector<char> arm_vertices_from_skinning(const Character& ch) {
  const Skeleton& sk = ch.skeleton;
  // The joints at or below a shoulder keypoint's joints (parents precede children).
  std::vector<char> arm_joint(sk.num_joints(), 0);
  bool mapped = false;
  for (const char* name : {"RShoulder", "LShoulder"}) {
    const LandmarkSource& s = ch.body25[body25_index(name)];
    for (int j : s.joints) arm_joint[j] = 1, mapped = true;
    for (int m : s.markers) arm_joint[sk.markers[m].joint] = 1, mapped = true;
  }
  if (!mapped) return {};
  for (int j = 0; j < sk.num_joints(); ++j)
    if (sk.joints[j].parent >= 0 && arm_joint[sk.joints[j].parent]) arm_joint[j] = 1;
  const SkinningWeights& w = ch.body.weights;
  std::vector<char> arm(ch.body.mesh.num_vertices(), 0);
  for (int v = 0; v < w.num_vertices(); ++v) {
    double on_arm = 0;
    for (const SkinInfluence& i : w.vertices[v])
      if (arm_joint[i.joint]) on_arm += i.weight;
    arm[v] = on_arm >= 0.5;
  }
  return arm;
}

Eigen::Vector3d bind_pose_hip_centre(const Character& ch, const std::string& what) {
  const Vertices k = pose_character(ch, ch.rest_dofs).body25;
  const int r = body25_index("RHip"), l = body25_index("LHip"), mid = body25_index("MidHip");
  if (!ch.body25[r].empty() && !ch.body25[l].empty()) return 0.5 * (k.row(r) + k.row(l)).transpose();
  if (!ch.body25[mid].empty()) return k.row(mid).transpose();
  fail(what, ": the character maps neither RHip and LHip nor MidHip in its body25 section; a generated skirt "
       "needs the hips' height");
}

}  // namespace weft::capture
