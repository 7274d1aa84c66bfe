#include "capture/motion/generic_humanoid.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string_view>

namespace weft::capture {

namespace humanoid {

namespace {

constexpr double kPi = std::numbers::pi;
double deg(double radians) { return radians * 180.0 / kPi; }
double rad(double degrees) { return degrees * kPi / 180.0; }

struct JointDef {
  const char* name;
  int parent;
  double x, y, z;  // offset from the parent (m); x is mirrored for the right side
  bool end_site;
};

constexpr JointDef kJoints[kJointCount] = {
    {"pelvis", -1, 0, 0, 0, false},
    {"left_hip", pelvis, 0.09, -0.07, 0.0, false},
    {"left_knee", l_hip, 0, -kThigh, 0, false},
    {"left_ankle", l_knee, 0, -kShank, 0, false},
    {"left_toe", l_ankle, 0, -0.06, 0.13, false},
    {"left_toe_end", l_toe, 0, 0, 0.05, true},
    {"right_hip", pelvis, -0.09, -0.07, 0.0, false},
    {"right_knee", r_hip, 0, -kThigh, 0, false},
    {"right_ankle", r_knee, 0, -kShank, 0, false},
    {"right_toe", r_ankle, 0, -0.06, 0.13, false},
    {"right_toe_end", r_toe, 0, 0, 0.05, true},
    {"spine", pelvis, 0, 0.10, -0.01, false},
    {"chest", spine, 0, 0.22, 0, false},
    {"neck", chest, 0, 0.20, 0, false},
    {"head", neck, 0, 0.10, 0.02, false},
    {"head_end", head, 0, 0.17, 0, true},
    {"left_clavicle", chest, 0.02, 0.16, 0.03, false},
    {"left_shoulder", l_clavicle, 0.16, 0, -0.04, false},
    {"left_elbow", l_shoulder, 0, -0.29, 0, false},
    {"left_wrist", l_elbow, 0, -0.25, 0, false},
    {"left_wrist_end", l_wrist, 0, -0.09, 0, true},
    {"right_clavicle", chest, -0.02, 0.16, 0.03, false},
    {"right_shoulder", r_clavicle, -0.16, 0, -0.04, false},
    {"right_elbow", r_shoulder, 0, -0.29, 0, false},
    {"right_wrist", r_elbow, 0, -0.25, 0, false},
    {"right_wrist_end", r_wrist, 0, -0.09, 0, true},
};

}  // namespace

// Signs: a limb hanging down (−y) flexes forward under Rx(−θ); the knee bends back under
// Rx(+θ); the trunk (pointing +y) bends forward under Rx(+θ) and leans left under Rz(−θ);
// a left limb abducts (toward +x) under Rz(+θ), a right one under Rz(−θ).
std::array<double, 3> channels(int j, const Angles& a) {
  const bool left = std::string_view(kJoints[j].name).starts_with("left_");
  const double side = left ? 1.0 : -1.0;
  switch (j) {
    case spine: case chest: case neck: case head:
      return {a.flex, -a.abd, a.twist};
    case l_knee: case r_knee:
      return {a.flex, 0, 0};
    case l_clavicle: case r_clavicle:  // elevation about z, protraction about y
      return {0, side * a.abd, -side * a.flex};
    default:  // hips, ankles, toes, shoulders, elbows, wrists
      return {-a.flex, side * a.abd, side * a.twist};
  }
}

double knee_for_drop(double drop) { return deg(2 * std::acos(std::clamp(1 - drop / kLeg, -1.0, 1.0))); }
double drop_for_knee(double knee_deg) { return kLeg * (1 - std::cos(rad(knee_deg) / 2)); }

void crouch(Pose& p, double kappa) {
  for (int side = 0; side < 2; ++side) {
    p.a[side ? r_hip : l_hip].flex += kappa / 2;
    p.a[side ? r_knee : l_knee].flex += kappa;
    p.a[side ? r_ankle : l_ankle].flex += kappa / 2;
  }
  p.root_offset.y() -= drop_for_knee(kappa);
}

void tilt_pelvis(Pose& p, double pitch_deg) {
  // The hip joints' offset from the pelvis, (±x, y, z) = (±0.09, −0.07, 0), turned by
  // Rx(pitch) (the trunk bends forward under Rx(+θ)); the pelvis moves by h − Rx h so they
  // stay where they were, in the heading frame the pose's offset is in.
  const double y = kJoints[l_hip].y, z = kJoints[l_hip].z, c = std::cos(rad(pitch_deg)), s = std::sin(rad(pitch_deg));
  p.pitch += pitch_deg;
  p.root_offset.y() += y - (c * y - s * z);
  p.root_offset.z() += z - (s * y + c * z);
  p.a[l_hip].flex += pitch_deg;
  p.a[r_hip].flex += pitch_deg;
}

double hip_for_foot_lift(double lift_m) {
  return deg(std::acos(std::clamp(1 - lift_m / (2 * kThigh), -1.0, 1.0)));
}

void set_humanoid_frame(BvhMotion& m, int f, const Pose& p, double yaw, const Eigen::Vector2d& pos) {
  // The pose's offset is in the heading frame (x left, z forward).
  const Eigen::Vector2d fwd(std::sin(rad(yaw)), std::cos(rad(yaw))), left(fwd.y(), -fwd.x());
  const Eigen::Vector2d offset = left * p.root_offset.x() + fwd * p.root_offset.z();
  auto row = m.frames.row(f);
  row(0) = pos.x() + offset.x();
  row(1) = kPelvisHeight + p.root_offset.y();
  row(2) = pos.y() + offset.y();
  row(3) = yaw;
  row(4) = p.pitch;
  row(5) = p.roll;
  for (int j = 1; j < kJointCount; ++j) {
    if (kJoints[j].end_site) continue;
    const std::array<double, 3> c = channels(j, p.a[j]);
    for (int k = 0; k < 3; ++k) row(m.joints[j].first_channel + k) = c[k];
  }
}

}  // namespace humanoid

BvhMotion generic_humanoid() {
  using namespace humanoid;
  BvhMotion m;
  m.source = "generic_humanoid";
  m.frame_time_s = 1.0 / 30;
  int channel = 0;
  for (int j = 0; j < kJointCount; ++j) {
    const JointDef& d = kJoints[j];
    BvhJoint b;
    b.name = d.name;
    b.parent = d.parent;
    b.offset = Eigen::Vector3d(d.x, d.y, d.z);
    b.end_site = d.end_site;
    if (j == pelvis)
      b.channels = {BvhChannel::x_position, BvhChannel::y_position, BvhChannel::z_position,
                    BvhChannel::y_rotation, BvhChannel::x_rotation, BvhChannel::z_rotation};
    else if (!d.end_site)
      b.channels = {BvhChannel::x_rotation, BvhChannel::z_rotation, BvhChannel::y_rotation};
    b.first_channel = channel;
    channel += static_cast<int>(b.channels.size());
    m.joints.push_back(std::move(b));
  }
  m.frames.resize(0, channel);
  return m;
}

double generic_pelvis_height() { return humanoid::kPelvisHeight; }

}  // namespace weft::capture
