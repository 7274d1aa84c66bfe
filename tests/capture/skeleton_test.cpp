#include <gtest/gtest.h>

#include <cmath>

#include "capture/character/skeletool_io.h"
#include "capture/character/skeleton.h"
#include "capture/character/skinning.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::expect_error;
using weft::capture::testing::small_skeleton_text;

namespace {

TEST(Skeleton, ParsesJointsMarkersDofs) {
  const Skeleton s = parse_skeleton(small_skeleton_text(), "small.skeleton");
  ASSERT_EQ(s.num_joints(), 4);
  ASSERT_EQ(s.num_markers(), 1);
  ASSERT_EQ(s.num_dofs(), 3);
  EXPECT_EQ(s.joints[0].parent, -1);
  EXPECT_EQ(s.joints[2].parent, 1);
  EXPECT_EQ(s.joints[0].type, JointType::prismatic);
  EXPECT_TRUE(s.joints[2].axis.isApprox(Eigen::Vector3d(0, 0, 1)));  // normalised from (0,0,2)
  EXPECT_DOUBLE_EQ(s.joints[3].scale, 0.5);
  EXPECT_EQ(s.markers[0].joint, 2);
  EXPECT_TRUE(s.dofs[1].limited);
  EXPECT_DOUBLE_EQ(s.dofs[1].upper, 1);
  const Eigen::MatrixXd W = s.dof_to_joint_matrix();
  EXPECT_DOUBLE_EQ(W(0, 0), 1000);
  EXPECT_DOUBLE_EQ(W(2, 1), 0.5);
  EXPECT_DOUBLE_EQ(W(2, 2), 1);
  EXPECT_EQ(s.parents(), Eigen::Vector4i(-1, 0, 1, 2));
}

TEST(Skeleton, RoundTripsThroughWriter) {
  ScratchDir dir("skel");
  const Skeleton s = parse_skeleton(small_skeleton_text(), "small.skeleton");
  write_skeleton(dir.file("s.skeleton"), s);
  const Skeleton r = read_skeleton(dir.file("s.skeleton"));
  ASSERT_EQ(r.num_joints(), s.num_joints());
  for (int j = 0; j < s.num_joints(); ++j) {
    EXPECT_EQ(r.joints[j].name, s.joints[j].name);
    EXPECT_EQ(r.joints[j].parent, s.joints[j].parent);
    EXPECT_EQ(r.joints[j].offset, s.joints[j].offset);
  }
  EXPECT_EQ(r.dof_to_joint_matrix(), s.dof_to_joint_matrix());
}

// FK against a hand computation: a revolute joint at the origin about z, then a child
// 2 units along x that rotates about z as well.
TEST(Skeleton, ForwardKinematicsMatchesHandComputedTwoJointChain) {
  Skeleton s;
  s.joints.push_back({"shoulder", JointType::revolute, -1, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1), 1});
  s.joints.push_back({"elbow", JointType::revolute, 0, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 0, 1), 2});
  s.joints.push_back({"hand", JointType::prismatic, 1, Eigen::Vector3d(1.5, 0, 0), Eigen::Vector3d(1, 0, 0), 1});
  s.dofs.push_back({"a", {{0, 1.0}}, false, 0, 0});
  s.dofs.push_back({"b", {{1, 1.0}}, false, 0, 0});
  s.dofs.push_back({"slide", {{2, 1.0}}, false, 0, 0});
  const double a = 0.3, b = -0.7, slide = 0.25;
  const Transforms G = forward_kinematics(s, Eigen::Vector3d(a, b, slide));
  // elbow at R(a)·(2,0,0); hand at elbow + R(a+b)·(1.5+slide, 0, 0).
  const Eigen::Vector3d elbow(2 * std::cos(a), 2 * std::sin(a), 0);
  const Eigen::Vector3d hand = elbow + (1.5 + slide) * Eigen::Vector3d(std::cos(a + b), std::sin(a + b), 0);
  EXPECT_TRUE(G[0].translation().isZero());
  EXPECT_NEAR((G[1].translation() - elbow).norm(), 0, 1e-12);
  EXPECT_NEAR((G[2].translation() - hand).norm(), 0, 1e-12);
  EXPECT_NEAR((G[2].linear() - Eigen::AngleAxisd(a + b, Eigen::Vector3d::UnitZ()).toRotationMatrix()).norm(), 0, 1e-12);
}

TEST(Skeleton, DofWeightsScaleJointParameters) {
  const Skeleton s = parse_skeleton(small_skeleton_text(), "small.skeleton");
  const Eigen::VectorXd p = joint_parameters(s, Eigen::Vector3d(0.002, 0.4, 0.1));
  EXPECT_DOUBLE_EQ(p(0), 2.0);          // 0.002 m × 1000
  EXPECT_DOUBLE_EQ(p(1), 0.4);
  EXPECT_DOUBLE_EQ(p(2), 0.2 + 0.1);    // 0.5 × bend + knee
  const Transforms G = forward_kinematics(s, Eigen::Vector3d(0.002, 0, 0));
  EXPECT_TRUE(G[0].translation().isApprox(Eigen::Vector3d(2, 0, 0)));
  // Markers: a zero-pose point carried by its joint.
  const Transforms Z = forward_kinematics(s, Eigen::Vector3d::Zero());
  const auto M0 = marker_positions(s, Z, Z);
  EXPECT_TRUE(M0.row(0).transpose().isApprox(s.markers[0].offset));
  const auto M = marker_positions(s, G, Z);
  EXPECT_TRUE(M.row(0).transpose().isApprox(s.markers[0].offset + Eigen::Vector3d(2, 0, 0)));
  EXPECT_DOUBLE_EQ(clamp_to_limits(s, Eigen::Vector3d(0, 5, 9))(1), 1.0);
}

TEST(Skeleton, MalformedSkeletonsNameFileAndLine) {
  auto with = [](const std::string& from, const std::string& to) {
    std::string t = small_skeleton_text();
    t.replace(t.find(from), from.size(), to);
    return t;
  };
  expect_error([&] { parse_skeleton(with("knee_rz   revolute  hip_rz", "knee_rz   revolute  ghost"), "s.skeleton"); },
               {"s.skeleton:5:", "unknown parent joint 'ghost'"});
  expect_error([&] { parse_skeleton(with("joints: 4", "joints: 5"), "s.skeleton"); }, {"s.skeleton:7:", "10 fields"});
  expect_error([&] { parse_skeleton(with("0 -2 0  0 0 2", "0 nan 0  0 0 2"), "s.skeleton"); },
               {"s.skeleton:5:", "finite number"});
  expect_error([&] { parse_skeleton(with("0 -2 0  0 0 2", "0 -2 0  0 0 0"), "s.skeleton"); },
               {"s.skeleton:5:", "zero axis"});
  expect_error([&] { parse_skeleton(with("revolute  root_tx", "spherical root_tx"), "s.skeleton"); },
               {"s.skeleton:4:", "unknown joint type"});
  expect_error([&] { parse_skeleton(with("      knee_rz 1\r\n", "      shin 1\r\n"), "s.skeleton"); },
               {"s.skeleton:20:", "unknown joint 'shin'"});
  expect_error([&] { parse_skeleton(with("dofs: 3", "dofs: 4"), "s.skeleton"); },
               {"s.skeleton", "unexpected end of file", "dof block 4 of 4"});
  expect_error([&] { parse_skeleton(with("scaling joints: 0", "scaling joints: 2"), "s.skeleton"); },
               {"s.skeleton:9:", "scaling joints"});
  const std::string t = small_skeleton_text();
  expect_error([&] { parse_skeleton(t.substr(0, t.size() / 2), "cut.skeleton"); }, {"cut.skeleton:"});
  expect_error([&] { parse_skeleton(t.substr(0, t.find("  foot")), "cut.skeleton"); },
               {"cut.skeleton:5:", "unexpected end of file", "joint line 4 of 4"});
}

TEST(Skeletool, SkinMapsBonesToLastJointOfTheirName) {
  const Skeleton s = parse_skeleton(small_skeleton_text(), "small.skeleton");
  EXPECT_EQ(skin_bone_joint(s, "hip"), 1);
  EXPECT_EQ(skin_bone_joint(s, "foot"), 3);
  EXPECT_EQ(skin_bone_joint(s, "root"), 0);
  EXPECT_EQ(skin_bone_joint(s, "ro"), -1);
  // Vertex index run into the weight digits, as in ddc.skin: parsed as written.
  const std::string text =
      "Skeletool character skinning file V1.0\r\nbones:\r\n   root hip knee\r\nvertex weights:\r\n"
      "0 1 0.750 2 0.250\r\n1 2 0.51 0 0.51\r\n2 0 2.55001e-0712 1 1\r\n";
  const SkinningWeights w = parse_skin(text, "t.skin", s, 3);
  ASSERT_EQ(w.num_vertices(), 3);
  EXPECT_EQ(w.vertices[0][0].joint, 1);
  EXPECT_DOUBLE_EQ(w.vertices[0][0].weight, 0.75);
  EXPECT_EQ(w.vertices[1][0].joint, 2);  // first listed stays first (DQS reference)
  EXPECT_DOUBLE_EQ(w.vertices[1][0].weight, 0.5);  // normalised
  ASSERT_EQ(w.vertices[2].size(), 1u);  // 2.55e-712 underflows to 0 and is dropped
  EXPECT_NEAR(w.vertices[2][0].weight, 1.0, 1e-12);
  const auto csr = w.csr();
  EXPECT_EQ(csr.offsets, (std::vector<int>{0, 2, 4, 5}));
  EXPECT_NEAR(w.dense().rowwise().sum().maxCoeff(), 1.0, 1e-12);
  expect_error([&] { parse_skin(text, "t.skin", s, 4); }, {"t.skin", "expected 4"});
  expect_error([&] { parse_skin(text + "3 7 1\r\n", "t.skin", s, 4); }, {"t.skin:8:", "bone index 7 out of range"});
  expect_error([&] { parse_skin(text + "1 0 1\r\n", "t.skin", s, -1); }, {"t.skin:8:", "already listed"});
  expect_error([&] { parse_skin(text + "9 0 1\r\n", "t.skin", s, 3); }, {"t.skin:8:", "vertex index 9 out of range"});
  std::string bad = text;
  bad.replace(bad.find("hip"), 3, "arm");
  expect_error([&] { parse_skin(bad, "t.skin", s, 3); }, {"t.skin:3:", "bone 'arm'"});
}

TEST(Skeletool, MotionRoundTripAndErrors) {
  ScratchDir dir("motion");
  Motion m;
  m.frame_ids = {0, 1};
  m.dofs.resize(2, 3);
  m.dofs << 0.1, -0.2, 0.3, 1e-9, 2.5, -7;
  write_motion(dir.file("m.motion"), m);
  const Motion r = read_motion(dir.file("m.motion"), 3);
  EXPECT_EQ(r.dofs, m.dofs);
  EXPECT_EQ(r.frame_ids, m.frame_ids);
  expect_error([&] { parse_motion("Skeletool Motion File V1.0\n0 1 2 3\n1 1 2\n", "w.motion", 3); },
               {"w.motion:3:", "3 dof values, found 3 fields"});
  expect_error([&] { parse_motion("Skeletool Motion File V1.0\n0 1 inf 3\n", "w.motion", 3); }, {"w.motion:2:", "finite"});
  expect_error([&] { parse_motion("Skeletool Motion File V1.0\n", "w.motion", 3); }, {"w.motion", "no frames"});
  expect_error([&] { parse_motion("hello\n", "w.motion", 3); }, {"w.motion:1:", "Skeletool Motion"});
}

TEST(Skeletool, CharacterFileResolvesPathsRelativeToItself) {
  ScratchDir dir("character");
  const std::string p = dir.write("c.character",
                                  "skeletool character file v1.0\r\nskeleton\r\n  a.skeleton\r\nmesh\r\n  sub/a.obj\r\n");
  const SkeletoolCharacterFiles f = read_skeletool_character(p);
  EXPECT_EQ(f.skeleton, dir.file("a.skeleton"));
  EXPECT_EQ(f.mesh, dir.file("sub/a.obj"));
  EXPECT_TRUE(f.skin.empty());
  const std::string bad = dir.write("b.character", "skeletool character file v1.0\nskeleton\n a\ntexture\n t.png\n");
  expect_error([&] { read_skeletool_character(bad); }, {"b.character:4:", "unknown keyword 'texture'"});
}

}  // namespace
