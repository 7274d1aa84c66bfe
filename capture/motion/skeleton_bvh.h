#pragma once
// A Skeletool skeleton's motion as BVH, for tools that read BVH (Blender, MotionBuilder,
// most mocap viewers): the skeleton's chains of one-dof joints become BVH joints with
// three rotation channels.
//
// BVH joints: the root and every joint that starts a segment (a non-zero offset from its
// parent, or a zero offset from a parent with several children); the joints that follow
// it at zero offset as an only child are absorbed into it, so a BVH joint stands for the
// last joint of its chain (hips_tx … hips → "hips"). Per frame, a BVH joint's local
// transform is the one between its chain's end and its parent's chain's end:
// rotation channels Zrotation Xrotation Yrotation (R = Rz Rx Ry, degrees, unwrapped to
// stay continuous over frames), its OFFSET the local translation (position channels as
// well where that translation changes over the motion: the root, prismatic joints).
// The global transforms bvh_global_transforms() gives back are those of the chain ends.
#include <string>
#include <vector>

#include "capture/character/skeleton.h"
#include "capture/motion/bvh.h"

namespace weft::capture {

// globals[f]: forward_kinematics of frame f (every frame the skeleton's joint count).
// bvh_joint_of (optional): for each skeleton joint, the index of its BVH joint.
BvhMotion skeleton_motion_bvh(const Skeleton& skeleton, const std::vector<Transforms>& globals, double frame_time_s,
                              std::vector<int>* bvh_joint_of = nullptr);

}  // namespace weft::capture
