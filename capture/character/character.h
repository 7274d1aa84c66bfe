#pragma once
// The Character template: everything fixed about one person, loaded once and then posed
// and deformed per frame. File format: docs/CHARACTER.md (character.yaml); a Skeletool
// `.character` imports as well.
#include <Eigen/Core>
#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "capture/character/attachment.h"
#include "capture/character/embedded_graph.h"
#include "geometry/mesh.h"
#include "capture/io/openpose.h"
#include "capture/character/skeleton.h"
#include "capture/character/skinning.h"

namespace weft::capture {

// One deformable surface of the character (the body or the garment), in the bind pose.
struct CharacterMesh {
  std::string path;            // where the mesh came from
  TriangleMesh mesh;           // bind-pose geometry (character units)
  SkinningWeights weights;     // per vertex, joint indices of the character's skeleton
  std::vector<int> labels;     // per vertex (ddc segmentation: 0 clothing, 18 skin/shoes); may be empty
  EmbeddedGraph graph;         // nodes, edges, vertex weights and per-node rigidity
};

// Where a BODY_25 keypoint sits on the character: the mean of one or more joint origins
// and/or markers. Empty: the keypoint is not mapped (treat its detections as missing).
struct LandmarkSource {
  std::vector<int> joints;   // skeleton joint indices
  std::vector<int> markers;  // skeleton marker indices
  bool empty() const { return joints.empty() && markers.empty(); }
};

struct Character {
  std::string name;
  std::string source;              // the character.yaml or .character it was loaded from
  double metres_per_unit = 1.0;    // ddc: 0.001 (millimetres)
  Skeleton skeleton;
  Eigen::VectorXd rest_dofs;       // the bind pose (D); skinning uses G(θ)·G(rest)⁻¹
  Transforms bind;                 // G(rest_dofs)
  Transforms zero_pose;            // G(0): markers are stored in this frame
  CharacterMesh body;
  std::optional<CharacterMesh> cloth;
  std::vector<int> inactive_body_faces;  // body faces left out of collisions (sorted)
  Attachment attachment;                  // cloth anchors → body triangles (empty without cloth)
  std::array<LandmarkSource, kBody25Count> body25;

  bool has_cloth() const { return cloth.has_value(); }
};

// Loads a character.yaml (.yaml / .yml) or a Skeletool .character; errors name the file
// and the key or line at fault.
Character load_character(const std::string& path);
Character load_character_yaml(const std::string& path);
// A Skeletool .character: skeleton, mesh, skin, pose (the first frame is the bind pose);
// millimetres; embedded graph sampled with default options; no labels, cloth or BODY_25 map.
Character load_skeletool_character(const std::string& path);

enum class SkinningMethod { dual_quaternion, linear_blend };

struct PosedCharacter {
  Transforms joints;         // G(θ)
  Vertices body;             // posed body vertices
  Vertices cloth;            // posed cloth vertices (empty without cloth)
  Vertices markers;          // M×3
  Vertices body25;           // 25×3; rows of unmapped keypoints are NaN
};

// Poses the bind-pose template by the dofs (no embedded deformation).
PosedCharacter pose_character(const Character& character, const Eigen::VectorXd& dofs,
                              SkinningMethod method = SkinningMethod::dual_quaternion);

// BODY_25 positions (25×3, NaN where unmapped) from joint transforms and marker positions.
Vertices body25_positions(const Character& character, const Transforms& joints, const Vertices& markers);

// Integers from a text file, whitespace separated (labels, anchor or face lists);
// errors name the file and line.
std::vector<int> read_index_list(const std::string& path);

}  // namespace weft::capture
