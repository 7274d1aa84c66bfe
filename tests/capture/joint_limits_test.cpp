// Joint limits of the generated skeleton (capture/character/joint_limits.h): the defaults
// bound hips, spine, neck and head with the documented signs (checked by moving a stick
// figure to each limit), the root and shoulders stay free, a hip turned by 180° is
// clamped, and a config's joint_limits override them or fail with one error naming the
// file, line and key.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "capture/character/body_skeleton_fit.h"
#include "capture/character/default_character.h"
#include "capture/character/joint_limits.h"
#include "tests/capture/stick_figure.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using Eigen::Vector3d;
using weft::capture::testing::stick_figure_skeleton;

namespace {

constexpr double kDeg = std::numbers::pi / 180;


const Dof& dof(const Skeleton& s, const std::string& name) {
  const int d = s.dof_index(name);
  EXPECT_GE(d, 0) << name;
  return s.dofs[d];
}

// Where joint `j` moves when dof `d` goes to its lower (−1) or upper (+1) limit.
Vector3d moved(const Skeleton& s, const std::string& d, int end, const std::string& j) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(s.num_dofs());
  const Dof& x = dof(s, d);
  q(s.dof_index(d)) = end < 0 ? x.lower : x.upper;
  const int ji = s.joint_index(j);
  return forward_kinematics(s, q)[ji].translation() -
         forward_kinematics(s, Eigen::VectorXd::Zero(s.num_dofs()))[ji].translation();
}

}  // namespace

TEST(JointLimits, DefaultsBoundHipsSpineAndNeckAndLeaveTheRootFree) {
  const Skeleton s = stick_figure_skeleton();
  for (const char* j : {"l_hip", "r_hip", "spine", "chest", "neck", "head", "l_ankle", "r_clavicle", "l_wrist"})
    for (const char* a : {"_rx", "_ry", "_rz"}) {
      const Dof& d = dof(s, std::string(j) + a);
      EXPECT_TRUE(d.limited) << d.name;
      EXPECT_LT(d.lower, 0.0) << d.name;  // the bind pose lies strictly inside
      EXPECT_GT(d.upper, 0.0) << d.name;
    }
  for (const char* n : {"hips_tx", "hips_ty", "hips_tz", "hips_rx", "hips_ry", "hips_rz", "l_shoulder_rx",
                        "r_shoulder_rz"})
    EXPECT_FALSE(dof(s, n).limited) << n;
  // No twist of the hips or the trunk reaches 90°: a pelvis turned round cannot be undone.
  for (const char* n : {"l_hip_ry", "r_hip_ry", "spine_ry", "chest_ry"}) {
    EXPECT_LT(dof(s, n).upper, 60 * kDeg) << n;
    EXPECT_GT(dof(s, n).lower, -60 * kDeg) << n;
  }
  // Together, spine and chest twist less than 90° either way.
  EXPECT_LT(dof(s, "spine_ry").upper + dof(s, "chest_ry").upper, 90 * kDeg);
  // A hip turned by 180° is clamped to its limit.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(s.num_dofs());
  q(s.dof_index("l_hip_ry")) = std::numbers::pi;
  q(s.dof_index("hips_ry")) = std::numbers::pi;
  const Eigen::VectorXd c = clamp_to_limits(s, q);
  EXPECT_EQ(c(s.dof_index("l_hip_ry")), dof(s, "l_hip_ry").upper);
  EXPECT_EQ(c(s.dof_index("hips_ry")), std::numbers::pi);  // the root is free
}

TEST(JointLimits, SignsAreTheDocumentedOnes) {
  const Skeleton s = stick_figure_skeleton();
  // Hip flexion (rx < 0) is the large one and brings the knee forward; extension back.
  EXPECT_LT(dof(s, "l_hip_rx").lower, -110 * kDeg);
  EXPECT_GT(moved(s, "l_hip_rx", -1, "l_knee").z(), 0.3);
  EXPECT_LT(moved(s, "l_hip_rx", +1, "l_knee").z(), -0.1);
  // Abduction is the larger sideways range on both sides, outward.
  EXPECT_GT(moved(s, "l_hip_rz", +1, "l_knee").x(), 0.25);
  EXPECT_LT(moved(s, "r_hip_rz", -1, "r_knee").x(), -0.25);
  EXPECT_LT(std::abs(moved(s, "l_hip_rz", -1, "l_knee").x()), std::abs(moved(s, "l_hip_rz", +1, "l_knee").x()));
  // The trunk bends forward (rx > 0) more than back.
  EXPECT_GT(moved(s, "spine_rx", +1, "neck").z(), 0.25);
  EXPECT_GT(dof(s, "spine_rx").upper, -dof(s, "spine_rx").lower);
  // Ankles point the toes down (rx > 0, plantar flexion) more than up.
  EXPECT_LT(moved(s, "l_ankle_rx", +1, "l_toe").y(), -0.05);
  EXPECT_GT(dof(s, "l_ankle_rx").upper, -dof(s, "l_ankle_rx").lower);
  // The clavicles rise more than they drop, on both sides.
  EXPECT_GT(moved(s, "l_clavicle_rz", +1, "l_shoulder").y(), 0.08);
  EXPECT_GT(moved(s, "r_clavicle_rz", -1, "r_shoulder").y(), 0.08);
}

TEST(JointLimits, ConfigOverridesTheDefaults) {
  const DefaultCharacterConfig c = parse_default_character_config(
      "name: x\njoint_limits:\n  l_hip: {ry: [-30, 20], rx: free}\n  l_knee: {rx: [0, 150]}\n", "/cfg/c.yaml");
  ASSERT_EQ(c.joint_limits.size(), 3u);
  Skeleton s = stick_figure_skeleton();
  apply_dof_limits(s, c.joint_limits, "c.yaml");
  EXPECT_NEAR(dof(s, "l_hip_ry").lower, -30 * kDeg, 1e-12);
  EXPECT_NEAR(dof(s, "l_hip_ry").upper, 20 * kDeg, 1e-12);
  EXPECT_FALSE(dof(s, "l_hip_rx").limited);
  EXPECT_NEAR(dof(s, "l_knee_rx").upper, 150 * kDeg, 1e-12);
  EXPECT_TRUE(dof(s, "r_hip_ry").limited);  // untouched: the default
  // A locked axis ([0, 0]) stays limited (fixed at the bind pose), not free.
  apply_dof_limits(s, parse_default_character_config("joint_limits: {head: {rz: [0, 0]}}\n", "d.yaml").joint_limits,
                   "d.yaml");
  EXPECT_TRUE(dof(s, "head_rz").limited);
  EXPECT_EQ(clamp_to_limits(s, Eigen::VectorXd::Constant(s.num_dofs(), 0.3))(s.dof_index("head_rz")), 0.0);
}

TEST(JointLimits, BadLimitsNameFileLineAndKey) {
  expect_error([] { parse_default_character_config("name: x\njoint_limits:\n  l_hip: {ry: [30, -20]}\n", "/c/a.yaml"); },
               {"a.yaml:3:", "joint_limits.l_hip.ry", "min > max"});
  expect_error([] { parse_default_character_config("joint_limits:\n  l_tail: {rx: [-10, 10]}\n", "b.yaml"); },
               {"b.yaml:2:", "joint_limits.l_tail", "unknown key"});
  expect_error([] { parse_default_character_config("joint_limits:\n  l_knee: {ry: [-10, 10]}\n", "c.yaml"); },
               {"c.yaml:2:", "joint_limits.l_knee.ry", "unknown key", "rx"});
  expect_error([] { parse_default_character_config("joint_limits:\n  hips: {ry: [-10, 10]}\n", "d.yaml"); },
               {"d.yaml:2:", "joint_limits.hips", "unknown key"});
  expect_error([] { parse_default_character_config("joint_limits:\n  neck: {rx: [10, 40]}\n", "e.yaml"); },
               {"e.yaml:2:", "joint_limits.neck.rx", "must contain 0"});
  expect_error([] { parse_default_character_config("joint_limits:\n  neck: {rx: 40}\n", "f.yaml"); },
               {"f.yaml:2:", "joint_limits.neck.rx", "[min, max]"});
  expect_error([] { parse_default_character_config("joint_limits:\n  neck: {rx: [-10, wide]}\n", "g.yaml"); },
               {"g.yaml:2:", "joint_limits.neck.rx[1]"});
  expect_error([] { parse_default_character_config("base: ddc.yaml\njoint_limits: {neck: {rx: [-10, 10]}}\n", "i.yaml"); },
               {"i.yaml:2:", "joint_limits", "not with 'base'"});
  // Exactly one weft::Error, of weft's type.
  EXPECT_THROW(parse_default_character_config("joint_limits: {spine: {rx: [5, -5]}}\n", "h.yaml"), weft::Error);
}
