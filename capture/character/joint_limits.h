#pragma once
// Joint limits of the generated body skeleton (body_skeleton_fit.h): anatomical defaults
// for its ball joints, and overrides from a character config's `joint_limits:` section
// (configs/characters/*.yaml, docs/CHARACTER.md "Joint limits").
//
// Why: with unlimited hips and spine, a pelvis turned the wrong way (even by 180°) with
// hips and spine twisted back meets the same landmarks, so PoseNet's root rotation is not
// identifiable. Limits keep hips, spine and neck within human ranges; PoseNet's output
// respects them (capture_networks.h) and retargeting clamps to them (motion_retarget.h).
//
// Angles in the skeleton are radians about the axes of the bind pose (y up, facing +z,
// the character's left at +x; a ball joint is Rx · Ry · Rz), measured from the bind pose
// (the A-pose: every dof 0). The root (hips_*) stays free.

#include <string>
#include <vector>

#include "capture/character/skeleton.h"
#include "files/strict_yaml.h"

namespace weft::capture {

struct DofLimit {
  std::string dof;       // e.g. l_hip_ry
  bool limited = true;   // false: free (no limits)
  double lower = 0, upper = 0;  // radians, lower <= 0 <= upper
};

// The defaults of build_body_skeleton for hips, spine, chest, neck, head, clavicles,
// wrists and ankles (the knees, elbows and toes get theirs where they are built;
// shoulders and the root are free). Sources in joint_limits.cpp.
const std::vector<DofLimit>& default_body_dof_limits();

// Sets the limits of the named dofs of `skeleton`; a dof it lacks is an error naming
// `what`.
void apply_dof_limits(Skeleton& skeleton, const std::vector<DofLimit>& limits, const std::string& what);

// A config's `joint_limits:` section: a map joint → {axis: [min, max] in degrees, or
// `free`}, axes as the generated skeleton names its dofs (rx, ry, rz for ball joints; rx
// for knees and toes; flex for elbows). An unknown joint or axis, min > max, or a range
// without 0 (the bind pose) is an error naming the file, line and key.
std::vector<DofLimit> parse_body_joint_limits(const StrictYaml& y, const YAML::Node& section,
                                              const std::string& key);

}  // namespace weft::capture
