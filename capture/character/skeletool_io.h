#pragma once
// Skeletool text formats (DeepCap / DynaCap / DDC lineage); see DESIGN.md "File formats
// users bring". Every reader throws weft::Error naming the file, the line and what was
// expected; lines may end in LF or CRLF.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "capture/character/skeleton.h"
#include "capture/character/skinning.h"

namespace weft::capture {

// `.skeleton`: "joints: N" lines `name type parent ox oy oz ax ay az scale` (parent
// "none" for a root; axes are normalised on load), "markers: M" lines
// `name joint point ox oy oz size r g b`, "dofs: D" blocks `name count`, `nolimits` or
// `limits lo hi`, then `count` lines `joint weight`. Trailing sections are ignored.
Skeleton read_skeleton(const std::string& path);
Skeleton parse_skeleton(std::string text, const std::string& name);
void write_skeleton(const std::string& path, const Skeleton& skeleton);

// `.skin`: "bones:" then one line of bone names, "vertex weights:", then per vertex
// `index (bone weight)*` with bone indices into the bone list. A bone drives the LAST
// joint whose name up to its first '_' equals the bone name. Weights are parsed as
// written, then normalised per vertex; the first listed bone stays first. Every vertex
// 0..num_vertices-1 must appear exactly once (num_vertices < 0: as many as lines).
SkinningWeights read_skin(const std::string& path, const Skeleton& skeleton, int num_vertices = -1);
SkinningWeights parse_skin(std::string text, const std::string& name, const Skeleton& skeleton,
                           int num_vertices = -1);
// The joint a skin bone name drives, or -1.
int skin_bone_joint(const Skeleton& skeleton, const std::string& bone);

// `.motion`: a header line, then per frame `index dof_0 … dof_{D-1}`.
struct Motion {
  std::vector<long long> frame_ids;  // the index column as written
  Eigen::MatrixXd dofs;              // frames × D (radians / character units)
  int num_frames() const { return static_cast<int>(dofs.rows()); }
};
// num_dofs < 0: taken from the first frame line.
Motion read_motion(const std::string& path, int num_dofs = -1);
Motion parse_motion(std::string text, const std::string& name, int num_dofs = -1);
void write_motion(const std::string& path, const Motion& motion);

// `.character`: keyword / path pairs (skeleton, mesh, skin, pose), paths relative to the
// file; returned as paths joined to the file's folder. Unknown keywords are errors.
struct SkeletoolCharacterFiles {
  std::string skeleton, mesh, skin, pose;
};
SkeletoolCharacterFiles read_skeletool_character(const std::string& path);

}  // namespace weft::capture
