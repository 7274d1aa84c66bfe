// The default character built from Debian's MakeHuman body (assimp-testmodels): the file's
// numbers, the fitted skeleton, skinning weights, garments and the written folder.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "geometry/closest_point.h"
#include "capture/character/default_character.h"
#include "capture/motion/motion_retarget.h"
#include "capture/motion/procedural_motion.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using Eigen::Vector3d;

using weft::capture::testing::slurp;

using weft::capture::testing::kHuman;
using weft::capture::testing::repo_file;

namespace {



// Built once per test program: each character takes a few seconds.
const DefaultCharacter& built(const std::string& config) {
  static std::map<std::string, std::unique_ptr<DefaultCharacter>> cache;
  auto& slot = cache[config];
  if (!slot) slot = std::make_unique<DefaultCharacter>(make_default_character(load_default_character_config(repo_file(config))));
  return *slot;
}
const DefaultCharacter& skirt() { return built("configs/characters/makehuman_skirt.yaml"); }
const DefaultCharacter& dress() { return built("configs/characters/makehuman_dress.yaml"); }

Vector3d joint(const Character& ch, const std::string& name) {
  const int j = ch.skeleton.joint_index(name);
  EXPECT_GE(j, 0) << name;
  return ch.bind[j].translation();
}

}  // namespace

TEST(DefaultCharacterFile, MakeHumanBodyHasTheDocumentedNumbers) {
  REQUIRE_HUMAN();
  const LoadedBody b = load_body_mesh(kHuman, 0);
  EXPECT_EQ(b.file_vertices, 14517);          // after JoinIdenticalVertices (split at UV seams)
  EXPECT_EQ(b.mesh.num_vertices(), 13380);    // welded by position: MakeHuman's base mesh
  EXPECT_EQ(b.mesh.num_faces(), 26756);       // 13,378 quads, triangulated
  EXPECT_NEAR(b.file_height, 1.659, 0.002);   // metres
  EXPECT_TRUE(b.mesh.has_uv());
  EXPECT_EQ(b.extra.rows(), 1076);            // the eyeballs
  // Closed and manifold: every edge has exactly two faces.
  std::map<std::pair<int, int>, int> count;
  for (int f = 0; f < b.mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = b.mesh.F(f, k), c = b.mesh.F(f, (k + 1) % 3);
      ++count[{std::min(a, c), std::max(a, c)}];
    }
  for (const auto& [e, n] : count) ASSERT_EQ(n, 2);
  // Scaled to a target height, feet on the floor.
  const LoadedBody tall = load_body_mesh(kHuman, 1.8);
  EXPECT_NEAR(tall.mesh.V.col(1).maxCoeff(), 1.8, 1e-9);
  EXPECT_NEAR(tall.mesh.V.col(1).minCoeff(), 0.0, 1e-12);
}

TEST(DefaultCharacterFit, JointsLieInsideTheBody) {
  REQUIRE_HUMAN();
  const Character& ch = skirt().character;
  const TriangleMesh& body = ch.body.mesh;
  EXPECT_LT(winding_number(body.V, body.F, Vector3d(0, 2.0, 0)), 0.01);  // the test itself
  EXPECT_GT(winding_number(body.V, body.F, joint(ch, "chest")), 0.99);
  for (int j = 0; j < ch.skeleton.num_joints(); ++j)
    EXPECT_TRUE(inside_mesh(body.V, body.F, ch.bind[j].translation())) << ch.skeleton.joints[j].name;
}

TEST(DefaultCharacterFit, SkeletonHasTheDocumentedJointsAndDofs) {
  REQUIRE_HUMAN();
  const Skeleton& s = skirt().character.skeleton;
  for (const auto& n : kBodyJointNames) EXPECT_GE(s.joint_index(n), 0) << n;
  for (const auto& n : kBodyEndSiteNames) EXPECT_GE(s.joint_index(n), 0) << n;
  EXPECT_EQ(kBodyJointNames.size(), 21u);
  // 6 root + 14 ball joints × 3 + knees, elbows, toes × 1 each side.
  EXPECT_EQ(s.num_dofs(), 6 + 14 * 3 + 6);
  EXPECT_EQ(s.num_joints(), s.num_dofs() + 5);
  for (const Dof& d : s.dofs) {
    ASSERT_EQ(d.joints.size(), 1u) << d.name;
    EXPECT_EQ(d.joints[0].weight, 1.0);
  }
  for (const char* n : {"l_knee_rx", "r_knee_rx", "l_elbow_flex", "r_elbow_flex"}) {
    const Dof& d = s.dofs[s.dof_index(n)];
    EXPECT_TRUE(d.limited) << n;
    EXPECT_LE(d.lower, 0.0);
    EXPECT_GT(d.upper, 2.0);
  }
  // Ball joints: rx, ry, rz with zero offsets between them.
  const int rz = s.joint_index("l_shoulder");
  EXPECT_EQ(s.joints[rz].offset.norm(), 0.0);
  EXPECT_EQ(s.joints[s.joints[rz].parent].name, "l_shoulder_ry");
  // Positive knee and elbow angles flex: the ankle moves back, the wrist to the front.
  const Character& ch = skirt().character;
  Eigen::VectorXd q = Eigen::VectorXd::Zero(s.num_dofs());
  q(s.dof_index("l_knee_rx")) = 1.0;
  q(s.dof_index("l_elbow_flex")) = 1.0;
  const Transforms G = forward_kinematics(s, q);
  EXPECT_LT(G[s.joint_index("l_ankle")].translation().z(), joint(ch, "l_ankle").z() - 0.1);
  EXPECT_GT(G[s.joint_index("l_wrist")].translation().z(), joint(ch, "l_wrist").z() + 0.05);
}

TEST(DefaultCharacterFit, LeftAndRightAreMirrorImages) {
  REQUIRE_HUMAN();
  const Character& ch = skirt().character;
  for (const auto& n : kBodyJointNames) {
    if (n.rfind("l_", 0) != 0) continue;
    const Vector3d l = joint(ch, n), r = joint(ch, "r_" + n.substr(2));
    EXPECT_LT((l - Vector3d(-r.x(), r.y(), r.z())).norm(), 0.005) << n;
    EXPECT_GT(l.x(), 0.0) << n;  // the character's left is +x
  }
  for (const char* mid : {"hips", "spine", "chest", "neck", "head"}) EXPECT_NEAR(joint(ch, mid).x(), 0.0, 0.005) << mid;
}

TEST(DefaultCharacterFit, HeightsAndProportionsAreAnatomical) {
  REQUIRE_HUMAN();
  const Character& ch = skirt().character;
  const double H = skirt().fit.height;
  EXPECT_NEAR(H, 1.66, 1e-9);
  auto frac = [&](const char* n) { return joint(ch, n).y() / H; };
  // Ranges around adult anthropometry (Drillis & Contini: hip 0.53, knee 0.285,
  // shoulder 0.818, ankle 0.039 of the height), wide enough for fitting error.
  EXPECT_GT(frac("l_hip"), 0.48);
  EXPECT_LT(frac("l_hip"), 0.56);
  EXPECT_GT(frac("l_knee"), 0.24);
  EXPECT_LT(frac("l_knee"), 0.31);
  EXPECT_GT(frac("l_ankle"), 0.03);
  EXPECT_LT(frac("l_ankle"), 0.07);
  EXPECT_GT(frac("l_shoulder"), 0.76);
  EXPECT_LT(frac("l_shoulder"), 0.84);
  EXPECT_GT(frac("neck"), frac("chest"));
  EXPECT_GT(frac("head"), frac("neck"));
  EXPECT_GT(frac("head_end"), 0.93);
  auto len = [&](const char* a, const char* b) { return (joint(ch, a) - joint(ch, b)).norm() / H; };
  EXPECT_GT(len("l_hip", "l_knee") + len("l_knee", "l_ankle"), 0.40);   // leg 0.245 + 0.246
  EXPECT_LT(len("l_hip", "l_knee") + len("l_knee", "l_ankle"), 0.52);
  EXPECT_GT(len("l_shoulder", "l_elbow"), 0.13);                         // upper arm 0.186
  EXPECT_LT(len("l_shoulder", "l_elbow"), 0.21);
  EXPECT_GT(len("l_elbow", "l_wrist"), 0.09);                            // forearm 0.146
  EXPECT_LT(len("l_elbow", "l_wrist"), 0.17);
  EXPECT_GT(len("l_shoulder", "r_shoulder"), 0.15);
  EXPECT_LT(len("l_shoulder", "r_shoulder"), 0.25);
  // Feet point forward (+z) and rest on the floor.
  EXPECT_GT(joint(ch, "l_toe").z(), joint(ch, "l_ankle").z() + 0.05);
  EXPECT_LT(joint(ch, "l_toe").y(), 0.04);
}

TEST(DefaultCharacterFit, Body25KeypointsAreMappedAndPlausible) {
  REQUIRE_HUMAN();
  const Character& ch = skirt().character;
  const PosedCharacter p = pose_character(ch, ch.rest_dofs);
  ASSERT_TRUE(p.body25.allFinite());
  auto kp = [&](const char* n) -> Vector3d { return p.body25.row(body25_index(n)).transpose(); };
  EXPECT_GT(kp("Nose").y(), kp("Neck").y());
  EXPECT_GT(kp("Nose").z(), kp("LEar").z());          // faces +z
  EXPECT_GT(kp("LEye").x(), 0.0);
  EXPECT_LT(kp("REye").x(), 0.0);
  EXPECT_NEAR(kp("LEye").y(), kp("REye").y(), 1e-3);
  EXPECT_GT(kp("LEar").x(), kp("LEye").x());
  EXPECT_GT(kp("LBigToe").z(), kp("LHeel").z() + 0.15);  // a foot is ~0.15 H long
  EXPECT_LT(kp("LSmallToe").z(), kp("LBigToe").z());
  EXPECT_GT(kp("LSmallToe").x(), kp("LBigToe").x());
  // Face and foot markers lie on the surface (vertices or eyeballs), within 2 cm.
  const ClosestTriangleQuery q(ch.body.mesh.V, ch.body.mesh.F);
  for (const char* n : {"Nose", "LEar", "REar", "LBigToe", "LSmallToe", "LHeel", "RHeel"})
    EXPECT_LT(q.closest(kp(n)).distance, 0.02) << n;
}

TEST(DefaultCharacterFit, SkinningWeightsAreNormalisedAndLocal) {
  REQUIRE_HUMAN();
  const DefaultCharacter& dc = skirt();
  const Character& ch = dc.character;
  const SkinningWeights& w = ch.body.weights;
  ASSERT_EQ(w.num_vertices(), ch.body.mesh.num_vertices());
  const Skeleton& s = ch.skeleton;
  int hand = 0, head = 0, thigh = 0;
  for (int v = 0; v < w.num_vertices(); ++v) {
    double sum = 0;
    for (const auto& inf : w.vertices[v]) sum += inf.weight;
    ASSERT_NEAR(sum, 1.0, 1e-9);
    const Vector3d x = ch.body.mesh.V.row(v).transpose();
    const std::string top = s.joints[w.vertices[v][0].joint].name;
    // Past the wrist along the hand: the wrist drives it.
    const Vector3d wr = joint(ch, "l_wrist"), he = joint(ch, "l_hand_end");
    if (dc.arm_vertices[v] && x.x() > 0 && (x - wr).dot((he - wr).normalized()) > 0.03) {
      ++hand;
      EXPECT_EQ(top, "l_wrist") << "vertex " << v;
    }
    if (x.y() > joint(ch, "head").y() + 0.06) {
      ++head;
      EXPECT_EQ(top, "head") << "vertex " << v;
    }
    const Vector3d hip = joint(ch, "l_hip"), knee = joint(ch, "l_knee");
    if (x.x() > 0 && std::abs(x.y() - 0.5 * (hip.y() + knee.y())) < 0.03 && !dc.arm_vertices[v]) {
      ++thigh;
      EXPECT_EQ(top, "l_hip") << "vertex " << v;
    }
  }
  EXPECT_GT(hand, 100);
  EXPECT_GT(head, 300);
  EXPECT_GT(thigh, 20);
}

TEST(DefaultCharacterGarment, SkirtAndDressClearTheBody) {
  REQUIRE_HUMAN();
  for (const DefaultCharacter* dc : {&skirt(), &dress()}) {
    const Character& ch = dc->character;
    ASSERT_TRUE(ch.has_cloth());
    const TriangleMesh& cloth = ch.cloth->mesh;
    EXPECT_GE(cloth.num_vertices(), 2000);
    EXPECT_LE(cloth.num_vertices(), 4000);
    const double clearance = 0.012;  // both configs
    const Eigen::VectorXd sd = signed_distances(ch.body.mesh, cloth.V);
    EXPECT_GE(sd.minCoeff(), clearance * 0.999) << ch.name;  // outside, arms and hands included
    EXPECT_EQ(dc->garment_inside, 0);
    // Anchors: the top ring (and the dress's straps), close to the body surface.
    ASSERT_GE(ch.attachment.size(), 64);
    for (int i = 0; i < ch.attachment.size(); ++i) {
      if (i < 64) EXPECT_EQ(ch.attachment.anchors(i), i);
      EXPECT_LT(ch.attachment.rest_distance(i), 3 * clearance) << "anchor " << i;
    }
    // One piece: the straps are sewn to the top ring.
    const auto adj = vertex_adjacency(cloth.F, cloth.num_vertices());
    std::vector<char> seen(cloth.num_vertices(), 0);
    std::vector<int> stack{0};
    seen[0] = 1;
    int reached = 1;
    while (!stack.empty()) {
      const int v = stack.back();
      stack.pop_back();
      for (int u : adj[v])
        if (!seen[u]) seen[u] = 1, ++reached, stack.push_back(u);
    }
    EXPECT_EQ(reached, cloth.num_vertices()) << ch.name;
    // Outward-facing triangles: the normals point away from the axis.
    const Vertices N = face_normals(cloth.V, cloth.F);
    int outward = 0;
    for (int f = 0; f < cloth.num_faces(); ++f) {
      const Vector3d c = (cloth.V.row(cloth.F(f, 0)) + cloth.V.row(cloth.F(f, 1)) + cloth.V.row(cloth.F(f, 2))) / 3;
      const Vector3d radial(c.x() - 0.0, 0, c.z() - joint(ch, "hips").z());
      outward += N.row(f).dot(radial) > 0;
    }
    EXPECT_GT(outward, 0.95 * cloth.num_faces());
  }
  // The skirt starts at the waist, the dress under the arms; the hems at their lengths.
  EXPECT_NEAR(skirt().character.cloth->mesh.V(0, 1), skirt().fit.waist_y, 1e-9);
  EXPECT_NEAR(skirt().character.cloth->mesh.V.col(1).minCoeff(), skirt().fit.waist_y - 0.45, 1e-9);
  EXPECT_NEAR(dress().character.cloth->mesh.V(0, 1), dress().fit.armpit_y - 0.04, 1e-9);
  // The dress's straps go over the shoulders (above the clavicles), both sides, and part
  // of each is anchored there.
  const Character& d = dress().character;
  EXPECT_EQ(skirt().character.attachment.size(), 64);
  int left = 0, right = 0;
  for (int i = 64; i < d.attachment.size(); ++i) {
    const Vector3d p = d.cloth->mesh.V.row(d.attachment.anchors(i)).transpose();
    EXPECT_GT(p.y(), joint(d, "l_clavicle").y());
    (p.x() > 0 ? left : right)++;
  }
  EXPECT_GT(left, 10);
  EXPECT_GT(right, 10);
  EXPECT_GT(d.cloth->mesh.V.col(1).maxCoeff(), joint(d, "l_shoulder").y());
}

TEST(DefaultCharacterGarment, ArmsAreInactiveAndTheTorsoIsNot) {
  REQUIRE_HUMAN();
  const DefaultCharacter& dc = skirt();
  const Character& ch = dc.character;
  ASSERT_FALSE(ch.inactive_body_faces.empty());
  EXPECT_TRUE(std::is_sorted(ch.inactive_body_faces.begin(), ch.inactive_body_faces.end()));
  const Vector3d wr = joint(ch, "l_wrist"), el = joint(ch, "l_elbow");
  for (int f : ch.inactive_body_faces) {
    const Vector3d c = ch.body.mesh.V.row(ch.body.mesh.F(f, 0)).transpose();
    ASSERT_GT(std::abs(c.x()), 0.1) << "face " << f;  // never the torso's middle
    ASSERT_GT(c.y(), dc.fit.crotch_y);                // never the legs
  }
  // The wrist and the elbow are surrounded by inactive faces.
  const ClosestTriangleQuery q(ch.body.mesh.V, ch.body.mesh.F);
  for (const Vector3d& p : {wr, el}) {
    const int f = q.closest(p).face;
    EXPECT_TRUE(std::binary_search(ch.inactive_body_faces.begin(), ch.inactive_body_faces.end(), f));
  }
}

TEST(DefaultCharacterFolder, WrittenFolderLoadsAndRoundTrips) {
  REQUIRE_HUMAN();
  const DefaultCharacterConfig cfg = load_default_character_config(repo_file("configs/characters/makehuman_skirt.yaml"));
  const DefaultCharacter& dc = skirt();
  ScratchDir dir("default_character");
  const std::string yaml = write_default_character(dc, cfg, dir.file("out"));
  const Character a = dc.character, b = load_character(yaml);
  EXPECT_EQ(b.name, "makehuman_skirt");
  EXPECT_EQ(b.metres_per_unit, 1.0);
  ASSERT_EQ(b.skeleton.num_joints(), a.skeleton.num_joints());
  ASSERT_EQ(b.skeleton.num_dofs(), a.skeleton.num_dofs());
  ASSERT_EQ(b.skeleton.num_markers(), a.skeleton.num_markers());
  for (int j = 0; j < a.skeleton.num_joints(); ++j) {
    EXPECT_EQ(b.skeleton.joints[j].name, a.skeleton.joints[j].name);
    EXPECT_LT((b.bind[j].matrix() - a.bind[j].matrix()).norm(), 1e-12);
  }
  EXPECT_EQ(b.body.mesh.V, a.body.mesh.V);
  EXPECT_EQ(b.body.mesh.F, a.body.mesh.F);
  EXPECT_TRUE(b.body.mesh.has_uv());
  EXPECT_LT((b.body.weights.dense() - a.body.weights.dense()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(b.body.graph.nodes, a.body.graph.nodes);
  EXPECT_EQ(b.body.graph.rigidity, a.body.graph.rigidity);
  EXPECT_EQ(b.inactive_body_faces, a.inactive_body_faces);
  ASSERT_TRUE(b.has_cloth());
  EXPECT_EQ(b.cloth->mesh.V, a.cloth->mesh.V);
  EXPECT_EQ(b.cloth->mesh.F, a.cloth->mesh.F);
  EXPECT_LT((b.cloth->weights.dense() - a.cloth->weights.dense()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(b.cloth->graph.nodes, a.cloth->graph.nodes);
  EXPECT_EQ(b.cloth->graph.rigidity, a.cloth->graph.rigidity);
  EXPECT_EQ(b.attachment.anchors, a.attachment.anchors);
  EXPECT_EQ(b.attachment.triangles, a.attachment.triangles);
  for (int k = 0; k < kBody25Count; ++k) {
    EXPECT_EQ(b.body25[k].joints, a.body25[k].joints) << kBody25Names[k];
    EXPECT_EQ(b.body25[k].markers, a.body25[k].markers) << kBody25Names[k];
  }
  // Posing the loaded character at rest gives back the bind pose.
  const PosedCharacter p = pose_character(b, b.rest_dofs);
  EXPECT_LT((p.body - b.body.mesh.V).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((p.cloth - b.cloth->mesh.V).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(DefaultCharacterFolder, OutputIsDeterministic) {
  REQUIRE_HUMAN();
  const DefaultCharacterConfig cfg = load_default_character_config(repo_file("configs/characters/makehuman_dress.yaml"));
  ScratchDir dir("default_character_det");
  write_default_character(dress(), cfg, dir.file("a"));
  write_default_character(make_default_character(cfg), cfg, dir.file("b"));
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.file("a"))) {
    const std::string name = e.path().filename().string();
    EXPECT_EQ(slurp(e.path().string()), slurp(dir.file("b/" + name))) << name;
    ++files;
  }
  EXPECT_EQ(files, 7);  // character.yaml body.obj body.skeleton rest.motion dress.obj anchors.txt inactive_faces.txt
}

// The random motion (configs/motions/random_poses.yaml), retargeted onto the generated
// character, stays within its joint limits (joint_limits.h) and still follows the source:
// the limits cut only what a human could not do.
TEST(DefaultCharacterFit, RandomPosesRetargetWithinTheJointLimits) {
  REQUIRE_HUMAN();
  const Character& ch = skirt().character;
  const Skeleton& s = ch.skeleton;
  for (const char* n : {"l_hip_ry", "r_hip_rz", "spine_ry", "chest_rx", "neck_ry", "head_rz"})
    EXPECT_TRUE(s.dofs[s.dof_index(n)].limited) << n;
  RetargetOptions o;
  o.fps = 10;
  o.end_s = 12;
  const RetargetResult r =
      retarget_motion(generate_motion(load_motion_spec(repo_file("configs/motions/random_poses.yaml"))),
                      load_retarget_mapping(repo_file("configs/retarget/humanoid_to_makehuman.yaml")), ch, o);
  ASSERT_TRUE(r.motion.dofs.allFinite());
  double at_limit = 0;
  for (int f = 0; f < r.motion.num_frames(); ++f)
    for (int d = 0; d < s.num_dofs(); ++d) {
      const Dof& dof = s.dofs[d];
      if (!dof.limited) continue;
      const double v = r.motion.dofs(f, d);
      EXPECT_GE(v, dof.lower - 1e-9) << dof.name << " frame " << f;
      EXPECT_LE(v, dof.upper + 1e-9) << dof.name << " frame " << f;
      at_limit += std::min(v - dof.lower, dof.upper - v) < 1e-6;
    }
  std::printf("random_poses → makehuman, %d frames: bone direction error mean %.2f°, max %.2f°, %.0f dof values at a limit\n",
              r.motion.num_frames(), r.mean_direction_error_deg, r.max_direction_error_deg, at_limit);
  EXPECT_LT(r.mean_direction_error_deg, 8.0);
}
