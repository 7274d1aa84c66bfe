#pragma once
// Dressing a character: a garment generated around its body in the bind pose
// (capture/character/garment.h) becomes the character's cloth, with skinning weights transferred from
// the closest body point, a sampled embedded graph and its anchors attached to the body.
// One path for the MakeHuman default character (capture/character/default_character.h) and for any
// loaded character such as ddc (a `base:` config, docs/CHARACTER.md "Dressing an existing
// character"). Character units throughout; Y up, the body facing ±z.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/character/garment.h"

namespace weft::capture {

enum class GarmentType { none, skirt, dress };
const char* garment_name(GarmentType type);  // "skirt", "dress", "none"

// A strap over one shoulder (add_shoulder_strap), character units.
struct ShoulderStrap {
  double x = 0;         // the plane x = const it follows over the shoulder
  double anchor_y = 0;  // its vertices above this height are anchors
};

struct GarmentSpec {
  GarmentType type = GarmentType::skirt;  // not none; names the cloth mesh (<type>.obj)
  TubeGarmentOptions tube;                // character units, top_y and mid_x included
  std::vector<ShoulderStrap> straps;      // dress only
  int graph_nodes = 300;                  // the cloth's embedded graph (farthest-point sampled)
  int nodes_per_vertex = 4;
  double rigidity = 0.1;                  // per graph node
};

struct GarmentFit {
  double min_distance = 0;  // garment to body in the bind pose (character units)
  int inside = 0;           // garment vertices inside the body (0 expected)
};

// Generates the garment around character.body (bind pose), sized without the
// `excluded_body_vertices` (per body vertex, may be empty: the arms and hands), and sets
// character.cloth (weights: transfer_weights_from_closest_point from the body's weights;
// graph: sample_embedded_graph, uniform rigidity) and character.attachment (the garment's
// anchors, attach_to_body). Throws weft::Error naming `what` when the hem would be below
// the body's lowest point.
GarmentFit dress_character(Character& character, const GarmentSpec& spec,
                           const std::vector<char>& excluded_body_vertices, const std::string& what);

// Faces whose three vertices are all marked (inactive faces from a vertex set).
std::vector<int> faces_of_vertices(const TriangleMesh& mesh, const std::vector<char>& vertices);

// Landmarks of a character without the MakeHuman landmark fit, from its skeleton, skinning
// weights and BODY_25 map:
// - arm and hand vertices: skinning weight ≥ ½ on the joints at or below the joints of the
//   RShoulder and LShoulder keypoints (a marker counts as its joint); empty when neither
//   shoulder is mapped;
// - the hips: the mean bind-pose position of the RHip and LHip keypoints (or MidHip);
//   throws naming `what` when none is mapped.
std::vector<char> arm_vertices_from_skinning(const Character& character);
Eigen::Vector3d bind_pose_hip_centre(const Character& character, const std::string& what);

}  // namespace weft::capture
