#include "capture/motion/skeleton_bvh.h"

#include <Eigen/Geometry>
#include <cmath>

#include "graph/error.h"

namespace weft::capture {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Z X Y Euler angles (radians) of R = Rz(a) Rx(b) Ry(c), the solution nearest `previous`
// (both branches, each angle shifted by multiples of 2π).
Eigen::Vector3d zxy_angles(const Eigen::Matrix3d& R, const Eigen::Vector3d* previous) {
  const Eigen::Vector3d e = R.eulerAngles(2, 0, 1);
  if (!previous) return e;
  const Eigen::Vector3d alternatives[2] = {e, Eigen::Vector3d(e[0] + kPi, kPi - e[1], e[2] + kPi)};
  Eigen::Vector3d best = e;
  double best_distance = INFINITY;
  for (Eigen::Vector3d a : alternatives) {
    for (int k = 0; k < 3; ++k) a[k] += 2 * kPi * std::round(((*previous)[k] - a[k]) / (2 * kPi));
    const double d = (a - *previous).squaredNorm();
    if (d < best_distance) best_distance = d, best = a;
  }
  return best;
}

}  // namespace

BvhMotion skeleton_motion_bvh(const Skeleton& s, const std::vector<Transforms>& globals, double frame_time_s,
                              std::vector<int>* bvh_joint_of) {
  WEFT_CHECK(s.num_joints() > 0, "skeleton_motion_bvh: empty skeleton");
  WEFT_CHECK(frame_time_s > 0, "skeleton_motion_bvh: frame time ", frame_time_s, " s, expected > 0");
  for (const Transforms& g : globals)
    WEFT_CHECK(int(g.size()) == s.num_joints(), "skeleton_motion_bvh: ", g.size(), " transforms for ",
               s.num_joints(), " joints");
  const int J = s.num_joints();
  std::vector<int> children(size_t(J), 0);
  for (const Joint& j : s.joints)
    if (j.parent >= 0) ++children[size_t(j.parent)];
  auto zero_offset = [&](int j) { return s.joints[size_t(j)].offset.norm() * s.joints[size_t(j)].scale <= 1e-12; };

  // Which BVH joint each skeleton joint belongs to, and each BVH joint's chain end.
  std::vector<int> member(size_t(J), -1), source, end;
  for (int j = 0; j < J; ++j) {
    const int parent = s.joints[size_t(j)].parent;
    const bool absorbed = parent >= 0 && zero_offset(j) && children[size_t(parent)] == 1 && j > 0;
    if (absorbed) {
      member[size_t(j)] = member[size_t(parent)];
      end[size_t(member[size_t(j)])] = j;
    } else {
      member[size_t(j)] = int(source.size());
      source.push_back(j);
      end.push_back(j);
    }
  }
  const int B = int(source.size()), F = int(globals.size());

  BvhMotion m;
  m.source = "skeleton";
  m.frame_time_s = frame_time_s;
  // Local transforms per frame.
  std::vector<std::vector<Eigen::Isometry3d>> local(static_cast<size_t>(B));
  for (auto& l : local) l.resize(size_t(F));
  std::vector<int> parent_of(static_cast<size_t>(B), -1);
  for (int b = 0; b < B; ++b) {
    const int p = s.joints[size_t(source[size_t(b)])].parent;
    parent_of[size_t(b)] = p < 0 ? -1 : member[size_t(p)];
    for (int f = 0; f < F; ++f) {
      const Eigen::Isometry3d& G = globals[size_t(f)][size_t(end[size_t(b)])];
      local[size_t(b)][size_t(f)] =
          parent_of[size_t(b)] < 0 ? G : globals[size_t(f)][size_t(end[size_t(parent_of[size_t(b)])])].inverse() * G;
    }
  }
  int column = 0;
  std::vector<bool> moves(static_cast<size_t>(B), false);
  for (int b = 0; b < B; ++b) {
    BvhJoint joint;
    joint.name = s.joints[size_t(end[size_t(b)])].name;
    joint.parent = parent_of[size_t(b)];
    const Eigen::Vector3d t0 = F > 0 ? Eigen::Vector3d(local[size_t(b)][0].translation()) : Eigen::Vector3d::Zero();
    bool varies = b == 0;
    for (int f = 1; f < F && !varies; ++f)
      varies = (local[size_t(b)][size_t(f)].translation() - t0).norm() > 1e-9 * std::max(1.0, t0.norm());
    moves[size_t(b)] = varies;
    joint.offset = varies ? Eigen::Vector3d::Zero() : t0;
    if (varies) joint.channels = {BvhChannel::x_position, BvhChannel::y_position, BvhChannel::z_position};
    for (BvhChannel c : {BvhChannel::z_rotation, BvhChannel::x_rotation, BvhChannel::y_rotation}) joint.channels.push_back(c);
    joint.first_channel = column;
    column += int(joint.channels.size());
    m.joints.push_back(joint);
  }
  m.frames.resize(F, column);
  for (int b = 0; b < B; ++b) {
    const BvhJoint& joint = m.joints[size_t(b)];
    Eigen::Vector3d previous;
    for (int f = 0; f < F; ++f) {
      const Eigen::Isometry3d& L = local[size_t(b)][size_t(f)];
      int c = joint.first_channel;
      if (moves[size_t(b)])
        for (int k = 0; k < 3; ++k) m.frames(f, c++) = L.translation()[k];
      const Eigen::Vector3d a = zxy_angles(L.linear(), f > 0 ? &previous : nullptr);
      previous = a;
      for (int k = 0; k < 3; ++k) m.frames(f, c++) = a[k] * 180.0 / kPi;
    }
  }
  if (bvh_joint_of) *bvh_joint_of = member;
  return m;
}

}  // namespace weft::capture
