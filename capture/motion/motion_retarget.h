#pragma once
// Retargeting a BVH motion onto any weft Skeleton (Skeletool-style 1-dof joint chains).
//
// The mapping (YAML, docs/MOTIONS.md) pairs source joints with character joints. Each
// mapped source joint and its nearest mapped source ancestor make a *bone*; extra bones
// join any two mapped joints (e.g. the two hips: the pelvis' side-to-side direction).
// Per output frame, the source's bone directions (after the axis conversion) are targets
// for the character's matching bones, and the mean of the root joints is a position
// target (scaled by the size ratio of the two skeletons; vertically, it is then moved so
// that the character's lowest mapped joint is as high above its floor as the source's). A damped least-squares (Levenberg–Marquardt) solve over the character's dofs
// meets them, with analytic Jacobians of the 1-dof chains, dof limits respected by
// projection, a weak pull toward the previous frame (it fixes what directions leave
// free, e.g. a straight arm's twist) and warm starts from the previous frame.
#include <Eigen/Core>
#include <functional>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "capture/motion/bvh.h"
#include "capture/character/skeletool_io.h"
#include "capture/character/skeleton.h"

namespace weft::capture {

struct Character;

struct RetargetBoneSpec {
  std::string source_from, source_to;  // source (BVH) joint names
  double weight = 1.0;
};

struct RetargetMapping {
  std::string file;                     // where it was loaded from (for messages)
  double source_metres_per_unit = 1.0;  // BVH length unit in metres (CMU ≈ 0.0564)
  // Rotation taking source coordinates to the character's: row i is the character's
  // axis i written in source axes ("source_axes: [-x, y, -z]" turns CMU, facing +z with
  // its left at +x, into ddc, facing −z with its right at +x).
  Eigen::Matrix3d source_to_target = Eigen::Matrix3d::Identity();
  int up_axis = 1;                      // the character's up axis (0 x, 1 y, 2 z)
  // source joint → character joint, in file order.
  std::vector<std::pair<std::string, std::string>> joints;
  std::vector<std::pair<std::string, double>> bone_weights;  // by the bone's source end joint
  std::vector<RetargetBoneSpec> extra_bones;
  // Orientation targets: the mapped character joint's global rotation follows the source
  // joint's, relative to their rest and zero poses, [source, weight]. Bone directions leave a
  // joint's rotation about them free and cannot tell a pelvis that tilts from a lower spine
  // that bends above it (CMU's LowerBack bends at the hips' own position, while the
  // MakeHuman character's first spine joint sits 15 cm higher: matching the lumbar bone
  // tilted the character's pelvis 42° where CMU 01_03's tilts 13.5°, bench_pelvis_tilt).
  std::vector<std::pair<std::string, double>> orientations;
  // Bones (by their source end joint) that keep the character's rest elevation relative
  // to the source's zero pose: where the two skeletons put a joint differently (ddc's
  // ankle sits higher above its toes than CMU's), matching the feet's directions exactly
  // would tilt the character's feet and sink its heels when the source stands flat.
  std::vector<std::string> rest_elevation;
  // Character markers that count as feet for the floor (heels and toes: CMU has no heel
  // joint, so a heel strike would otherwise push the character's heel through the floor).
  std::vector<std::string> floor_markers;
  // Root position target: the mean of these source joints, matched to the mean of their
  // mapped character joints.
  std::vector<std::string> root_joints;
  double root_weight = 1.0;
  double root_scale = 0;                // 0: auto, the ratio of summed bone lengths
  bool root_on_floor = true;            // false: vertical position as in the source × scale
  bool root_relative = true;            // horizontal motion starts at the character's rest position
  // Height of the source's lowest mapped joint when standing (source units along up);
  // NaN: auto, the median over the clip of the per-frame lowest mapped joint.
  double source_floor = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::string> fixed_dofs;  // dof names or '*' patterns kept at the rest pose
  // Solver (Levenberg–Marquardt per frame).
  int iterations = 30;                  // per frame; the first frame gets 10×
  double smoothness = 0.02;             // pull toward the previous frame's dofs
  double rest_weight = 1e-4;            // pull toward the rest dofs
  double tolerance = 1e-9;              // stop when the cost decreases by less (relative)
};

RetargetMapping load_retarget_mapping(const std::string& path);
// Parses YAML text as if read from `name`; unknown keys are errors naming key, file, line.
RetargetMapping parse_retarget_mapping(const std::string& yaml_text, const std::string& name);

struct RetargetOptions {
  double fps = 0;          // output frame rate; 0: the source's
  double start_s = 0;      // clip window in source seconds
  double end_s = -1;       // -1: to the end
  std::function<void(int, int)> progress;  // (frames done, frames total)
};

struct RetargetBone {
  std::string name;                    // "from->to" (source names)
  int source_from = -1, source_to = -1;  // BVH joint indices
  int target_from = -1, target_to = -1;  // character joint indices
  double weight = 1.0;
  double elevation_offset = 0;           // radians added to the source's elevation
};

struct RetargetResult {
  Motion motion;                        // frames × D dofs, frame ids 0..N-1
  double fps = 0;
  std::vector<RetargetBone> bones;
  std::vector<int> solved_dofs;         // the dofs the solver moved; the rest stay at rest
  Eigen::VectorXd direction_error_deg;  // per frame: mean angle over bones (degrees)
  Eigen::VectorXd root_error;           // per frame: root position error (character units)
  // Per frame: the mean angle between each orientation target and its joint's rotation
  // (degrees; 0 without orientation targets).
  Eigen::VectorXd orientation_error_deg;
  double mean_direction_error_deg = 0, max_direction_error_deg = 0;
  double root_scale = 1;                // character size / source size
  double source_height_m = 0;           // standing height of the source's mapped joints, first frame
  double target_height = 0;             // rest height of the character's mapped joints (units)
  double source_floor_m = 0;            // height of the source's lowest mapped joint when standing
  double target_floor = 0;              // the character's lowest mapped joint at rest (units)
};

// Retargets `motion` onto `skeleton`, whose rest pose `rest_dofs` is standing upright on
// the floor (it defines the floor and the starting position); lengths of the skeleton
// are in units of `metres_per_unit`.
RetargetResult retarget_motion(const BvhMotion& motion, const RetargetMapping& mapping,
                               const Skeleton& skeleton, const Eigen::VectorXd& rest_dofs,
                               double metres_per_unit, const RetargetOptions& options = {});
RetargetResult retarget_motion(const BvhMotion& motion, const RetargetMapping& mapping,
                               const Character& character, const RetargetOptions& options = {});

// Angle (degrees) between each mapped bone of the character posed by `dofs` and its
// target from the source at source time t (the source's direction, with the rest
// elevation offset for `rest_elevation` bones): the measure reported per frame above.
Eigen::VectorXd bone_direction_errors_deg(const BvhMotion& motion, const RetargetMapping& mapping,
                                          const std::vector<RetargetBone>& bones,
                                          const Skeleton& skeleton, const Eigen::VectorXd& dofs,
                                          double t);

// The BVH skeleton as a weft Skeleton: per BVH joint a chain of 1-dof joints, one per
// channel in file order (prismatic for positions, revolute for rotations; the first
// carries the OFFSET), the last named like the BVH joint; joints without channels (end
// sites) are revolute joints no dof drives. One dof per channel, named
// "<joint>_<Channel>", weight 1: radians for rotations, file units for positions.
Skeleton skeleton_from_bvh(const BvhMotion& motion);
// The dof vector of skeleton_from_bvh for one frame (degrees → radians).
Eigen::VectorXd bvh_frame_dofs(const BvhMotion& motion, int frame);

}  // namespace weft::capture
