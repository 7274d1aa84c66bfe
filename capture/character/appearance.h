#pragma once
// The look of a generated character: per-vertex colours (RGB in [0, 1], the renderer's
// ColorSource::vertex) painted on the body and the garment from their bind-pose geometry,
// so that a network can tell front from back and left from right. A flat-coloured body
// under a headlight looks the same from the front and from behind; these colours do not:
//
//   body (a fitted body: metres, y up, facing +z, its left at +x)
//   - hair over the back and top of the head, the face in skin with dark eyes and red lips;
//   - a shirt on the torso with short sleeves, and a print on the chest's front only
//     (a disc with a dark centre and a bar beneath it); the back is plain;
//   - leggings on the legs, and different shoes: the left one red, the right one white;
//   - skin on the forearms, hands and face.
//   garment (a skirt or dress around a vertical axis, front at +z)
//   - its colour with darker panels every 45° around, a light band at the hem, and one
//     light stripe down the front centre only.
//
// Colours are a pure function of the geometry and the config: no randomness. A character
// dressed from a `base:` (ddc) keeps its scan texture; only its garment is painted.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "capture/character/body_skeleton_fit.h"
#include "geometry/mesh.h"

namespace YAML {
class Node;
}

namespace weft {
struct StrictYaml;  // files/strict_yaml.h
}  // namespace weft

namespace weft::capture {

struct AppearanceConfig {
  bool textured = false;  // false: no vertex colours (the studio draws flat skin and a red garment)
  // RGB in [0, 1].
  Eigen::Vector3d skin{0.86, 0.68, 0.57};
  Eigen::Vector3d hair{0.20, 0.12, 0.07};
  Eigen::Vector3d shirt{0.16, 0.35, 0.70};
  Eigen::Vector3d print{0.98, 0.80, 0.12};  // the chest print (front only)
  Eigen::Vector3d legs{0.18, 0.18, 0.22};
  Eigen::Vector3d left_shoe{0.80, 0.10, 0.10};
  Eigen::Vector3d right_shoe{0.95, 0.95, 0.92};
  Eigen::Vector3d garment{0.75, 0.20, 0.22};
  Eigen::Vector3d garment_trim{0.96, 0.92, 0.80};  // the hem band and the front stripe
};

// Reads an `appearance:` section (`textured` and the colours as [r, g, b] in 0..1, each
// optional); `key` prefixes messages (e.g. "appearance"). Unknown keys and colours out of
// range are errors naming the file, line and key.
AppearanceConfig parse_appearance(const StrictYaml& yaml, const YAML::Node& section, const std::string& key);

// Body colours (N×3) from the bind pose: `fit` gives the joints and face markers,
// `arm_vertices` (arm_vertices in body_skeleton_fit.h) which vertices are arms and hands.
Vertices body_colors(const TriangleMesh& body, const BodySkeletonFit& fit, const std::vector<char>& arm_vertices,
                     const AppearanceConfig& look);

// Garment colours (N×3) from the bind pose: the garment hangs from top_y down `length`
// (character units) around the vertical axis through its vertices' mean.
Vertices garment_colors(const TriangleMesh& garment, double top_y, double length, const AppearanceConfig& look);

}  // namespace weft::capture
