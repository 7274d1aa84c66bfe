#pragma once
// The generic humanoid that procedural motions are played on (procedural_motion.h,
// random_motion.h), and its poses in anatomical angles.
//
// Metres, y up, facing +z, its left at +x (like CMU BVH): pelvis (root: position +
// yaw/pitch/roll), spine, chest, neck, head, and per side <side>_hip, _knee, _ankle, _toe,
// _clavicle, _shoulder, _elbow, _wrist, with end sites head_end, <side>_toe_end and
// <side>_wrist_end; side is left or right. Joint angles are anatomical (degrees):
// flexion, abduction and twist per joint, turned into BVH rotation channels (Xrotation
// Zrotation Yrotation) with the signs of each side by humanoid_channels.
#include <Eigen/Core>
#include <array>

#include "capture/motion/bvh.h"

namespace weft::capture {

namespace humanoid {

enum Joint {
  pelvis, l_hip, l_knee, l_ankle, l_toe, l_toe_end, r_hip, r_knee, r_ankle, r_toe, r_toe_end,
  spine, chest, neck, head, head_end, l_clavicle, l_shoulder, l_elbow, l_wrist, l_wrist_end,
  r_clavicle, r_shoulder, r_elbow, r_wrist, r_wrist_end, kJointCount
};

// Thigh and shank lengths (m) of a 1.75 m adult.
inline constexpr double kThigh = 0.42, kShank = 0.41, kLeg = kThigh + kShank;
// Standing height of the pelvis (m): the toe joints on the floor y = 0.
inline constexpr double kPelvisHeight = 0.07 + kLeg + 0.06;

// Anatomical angles of one joint (degrees): flexion (forward bend / dorsiflexion / knee
// bend; for the clavicle protraction), abduction (away from the midline; for the trunk a
// lean to the left; for the clavicle elevation) and twist (to the left for the trunk).
struct Angles {
  double flex = 0, abd = 0, twist = 0;
};

struct Pose {
  std::array<Angles, kJointCount> a{};
  Eigen::Vector3d root_offset = Eigen::Vector3d::Zero();  // m, heading frame (x left, y up, z forward)
  double pitch = 0, roll = 0;                              // pelvis, degrees
};

// Channel values (Xrotation, Zrotation, Yrotation) of joint j from its anatomical angles.
std::array<double, 3> channels(int j, const Angles& a);

// Knee flexion (degrees) that lowers the pelvis by `drop` m with the thigh and shank
// making equal angles with the vertical (feet stay under the hips, flat on the floor),
// and its inverse.
double knee_for_drop(double drop_m);
double drop_for_knee(double knee_deg);
// Flexes both legs by knee angle `kappa` (degrees): hips and ankles by half, pelvis down
// by drop_for_knee(kappa), so that the feet stay flat on the floor.
void crouch(Pose& p, double kappa);
// Hip flexion (degrees) that lifts a foot by `lift_m` with the knee bent twice as much
// and the ankle by as much, keeping the foot level.
// Tilts the pelvis forward by `pitch_deg` (backward when < 0) about its left axis with the
// legs left where they were: the hips flex by the same angle and the pelvis moves so the
// hip joints stay put (bending at the hips, as people do when they bow or squat).
void tilt_pelvis(Pose& p, double pitch_deg);
double hip_for_foot_lift(double lift_m);

// Writes frame f of a motion of the generic humanoid: pose p with the pelvis at floor
// position (x, z) = `position` (m) and heading `yaw_deg` about +y.
void set_humanoid_frame(BvhMotion& m, int f, const Pose& p, double yaw_deg, const Eigen::Vector2d& position);

}  // namespace humanoid

// The generic humanoid with all channels at zero (standing, arms down), pelvis at its
// standing height above the floor y = 0; no frames.
BvhMotion generic_humanoid();
// Standing height of the pelvis (m): the toe joints touch the floor.
double generic_pelvis_height();

}  // namespace weft::capture
