// The real ddc subject (../shared/data/ddc, CC BY-NC, never copied into the repository):
// loads it through configs/characters/ddc.yaml and poses its 300 captured frames.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>

#include "capture/character/character.h"
#include "geometry/mesh_io.h"
#include "capture/character/skeletool_io.h"
#include "tests/test_requirements.h"

using namespace weft;
using namespace weft::capture;

namespace {

using weft::testing::kDdcDir;
const std::string kConfig = WEFT_SOURCE_DIR "/configs/characters/ddc.yaml";

#define REQUIRE_DDC() REQUIRE_DDC_DATA()

TEST(Ddc, LoadsTheTemplate) {
  REQUIRE_DDC();
  const Character ch = load_character(kConfig);
  EXPECT_EQ(ch.skeleton.num_joints(), 173);
  EXPECT_EQ(ch.skeleton.num_markers(), 97);
  EXPECT_EQ(ch.skeleton.num_dofs(), 107);
  EXPECT_EQ(ch.body.mesh.num_vertices(), 5514);
  EXPECT_EQ(ch.body.mesh.num_faces(), 11024);
  EXPECT_TRUE(ch.body.mesh.has_uv());
  EXPECT_EQ(ch.body.graph.num_nodes(), 852);
  EXPECT_EQ(ch.body.labels.size(), 5514u);
  EXPECT_DOUBLE_EQ(ch.metres_per_unit, 0.001);
  for (int k = 0; k < kBody25Count; ++k) EXPECT_FALSE(ch.body25[k].empty()) << kBody25Names[k];
  // Every vertex is influenced; weights sum to 1; LeftForeArm drives LeftForeArm_rz.
  for (const auto& v : ch.body.weights.vertices) {
    ASSERT_FALSE(v.empty());
    double s = 0;
    for (const auto& i : v) s += i.weight;
    EXPECT_NEAR(s, 1.0, 1e-12);
  }
  EXPECT_EQ(skin_bone_joint(ch.skeleton, "LeftForeArm"), ch.skeleton.joint_index("LeftForeArm_rz"));
  for (int v = 0; v < ch.body.mesh.num_vertices(); ++v)
    ASSERT_NEAR(ch.body.graph.vertex_weights.row(v).sum(), 1.0, 1e-12) << "vertex " << v;
  EXPECT_EQ(ch.body.graph.edges.rows(), 2550);  // the unique edges of ddc_graph.obj's 1700 faces
  // Rigidity: clothing nodes (0.2) and skin nodes (1.0) both present.
  EXPECT_NEAR(ch.body.graph.rigidity.minCoeff(), 0.2, 1e-12);
  EXPECT_NEAR(ch.body.graph.rigidity.maxCoeff(), 1.0, 1e-12);
  // The Skeletool .character imports the same skeleton, mesh and weights.
  const Character sk = load_character(kDdcDir + "/ddc.character");
  EXPECT_EQ(sk.body.mesh.V, ch.body.mesh.V);
  EXPECT_EQ(sk.rest_dofs, ch.rest_dofs);
  EXPECT_EQ(sk.body.weights.dense(), ch.body.weights.dense());
}

TEST(Ddc, PosesTheCapturedWalk) {
  REQUIRE_DDC();
  const Character ch = load_character(kConfig);
  const Motion walk = read_motion(kDdcDir + "/walk_0000_0299.motion", ch.skeleton.num_dofs());
  ASSERT_EQ(walk.num_frames(), 300);

  // The rest pose reproduces the template (within 1e-4 mm), with either skinning.
  for (SkinningMethod m : {SkinningMethod::dual_quaternion, SkinningMethod::linear_blend}) {
    const PosedCharacter rest = pose_character(ch, ch.rest_dofs, m);
    EXPECT_LT((rest.body - ch.body.mesh.V).cwiseAbs().maxCoeff(), 1e-4);
  }

  // Bones: pairs (parent, joint) with a non-zero offset. A prismatic parent moves the
  // child along its axis, so pairs under a prismatic joint whose parameter varies during
  // the walk (the root translation) are not bones; `*Scale` joints are prismatic too but
  // constant over a sequence, so their bones count.
  Eigen::MatrixXd P(walk.num_frames(), ch.skeleton.num_joints());
  for (int f = 0; f < walk.num_frames(); ++f)
    P.row(f) = joint_parameters(ch.skeleton, walk.dofs.row(f).transpose()).transpose();
  std::vector<std::pair<int, int>> bones;
  for (int j = 0; j < ch.skeleton.num_joints(); ++j) {
    const Joint& joint = ch.skeleton.joints[j];
    if (joint.parent < 0 || joint.offset.norm() * joint.scale < 1e-9) continue;
    const bool parent_slides = ch.skeleton.joints[joint.parent].type == JointType::prismatic &&
                               P.col(joint.parent).maxCoeff() - P.col(joint.parent).minCoeff() > 0;
    if (!parent_slides) bones.emplace_back(joint.parent, j);
  }
  ASSERT_GT(bones.size(), 50u);
  auto bone_lengths = [&](const Transforms& G) {
    Eigen::VectorXd L(bones.size());
    for (size_t b = 0; b < bones.size(); ++b)
      L(b) = (G[bones[b].second].translation() - G[bones[b].first].translation()).norm();
    return L;
  };
  const Eigen::VectorXd L0 = bone_lengths(forward_kinematics(ch.skeleton, walk.dofs.row(0).transpose()));

  const int lf = ch.skeleton.joint_index("LeftFootEE"), rf = ch.skeleton.joint_index("RightFootEE");
  const int la = ch.skeleton.joint_index("LeftFoot_rx"), ra = ch.skeleton.joint_index("RightFoot_rx");
  std::vector<double> lowest_foot(walk.num_frames());
  double max_bone_change = 0;
  double max_body_speed = 0;
  Vertices previous;
  const auto t0 = std::chrono::steady_clock::now();
  for (int f = 0; f < walk.num_frames(); ++f) {
    const PosedCharacter p = pose_character(ch, walk.dofs.row(f).transpose());
    ASSERT_TRUE(p.body.allFinite()) << "frame " << f;
    ASSERT_TRUE(p.markers.allFinite()) << "frame " << f;
    ASSERT_TRUE(p.body25.allFinite()) << "frame " << f;  // every keypoint is mapped
    // y is up: the nose is above the neck, the neck above the mid-hip, in every frame.
    EXPECT_GT(p.body25(0, 1), p.body25(1, 1)) << "frame " << f;
    EXPECT_GT(p.body25(1, 1), p.body25(8, 1)) << "frame " << f;
    max_bone_change = std::max(max_bone_change, (bone_lengths(p.joints) - L0).cwiseAbs().maxCoeff());
    // Feet: the lowest of the toe tips and ankles (y is up in ddc).
    lowest_foot[f] = std::min({p.joints[lf].translation().y(), p.joints[rf].translation().y(),
                               p.joints[la].translation().y(), p.joints[ra].translation().y()});
    if (f > 0) max_body_speed = std::max(max_body_speed, (p.body - previous).rowwise().norm().maxCoeff());
    previous = p.body;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RecordProperty("pose_300_frames_ms", static_cast<int>(1000 * seconds));
  std::printf("posed 300 ddc frames (FK + DQS of 5514 vertices) in %.1f ms\n", 1000 * seconds);
  EXPECT_LT(max_bone_change, 1e-6) << "mm";

  // The floor the motion implies: the median lowest-foot height over the sequence. A
  // walking subject always has a foot on it, so every frame's lowest foot point stays
  // within a few centimetres of it (toe lift and heel strike included).
  std::vector<double> sorted = lowest_foot;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double floor_y = sorted[sorted.size() / 2];
  for (int f = 0; f < walk.num_frames(); ++f)
    EXPECT_NEAR(lowest_foot[f], floor_y, 40.0) << "frame " << f << " (mm)";
  // The template's own floor: its lowest vertex sits at the same height as the walk's.
  EXPECT_NEAR(ch.body.mesh.V.col(1).minCoeff(), floor_y, 60.0);
  // Captured at video rate: no vertex jumps more than 10 cm between frames.
  EXPECT_LT(max_body_speed, 100.0);
}

TEST(Ddc, TemplateRoundTripsThroughPly) {
  REQUIRE_DDC();
  const TriangleMesh m = read_obj(kDdcDir + "/ddc.obj");
  const std::string tmp = (std::filesystem::temp_directory_path() / ("weft_ddc_" + std::to_string(::getpid()) + ".ply")).string();
  write_ply(tmp, m);
  const TriangleMesh r = read_ply(tmp);
  std::filesystem::remove(tmp);
  EXPECT_EQ(r.V, m.V);
  EXPECT_EQ(r.F, m.F);
}

}  // namespace
