// Dressing an existing character on a small synthetic one in millimetres, away from x = 0:
// landmarks from its skeleton, skinning and BODY_25 map, the skirt around its hips, and
// the `base:` config kind read strictly. The real ddc subject is in
// dressed_character_integration_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "capture/character/default_character.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::ScratchDir;
using Eigen::Vector3d;

namespace {

// Appends a closed, outward-facing capped cylinder around the vertical line (cx, ·, 0).
void add_cylinder(TriangleMesh& m, double cx, double r, double y0, double y1, int around, int rows) {
  const int base = m.num_vertices();
  const int n = around * rows + 2;
  m.V.conservativeResize(base + n, 3);
  for (int i = 0; i < rows; ++i)
    for (int k = 0; k < around; ++k) {
      const double a = 2 * std::numbers::pi * k / around;
      m.V.row(base + i * around + k) << cx + r * std::cos(a), y1 - (y1 - y0) * i / (rows - 1), r * std::sin(a);
    }
  const int top = base + n - 2, bottom = base + n - 1;
  m.V.row(top) << cx, y1, 0;
  m.V.row(bottom) << cx, y0, 0;
  std::vector<std::array<int, 3>> f;
  for (int i = 0; i + 1 < rows; ++i)
    for (int k = 0; k < around; ++k) {
      const int a = base + i * around + k, b = base + i * around + (k + 1) % around, c = a + around,
                d = b + around;
      f.push_back({a, b, c});
      f.push_back({b, d, c});
    }
  for (int k = 0; k < around; ++k) {
    f.push_back({top, base + (k + 1) % around, base + k});
    const int last = base + (rows - 1) * around;
    f.push_back({bottom, last + k, last + (k + 1) % around});
  }
  const int f0 = m.num_faces();
  m.F.conservativeResize(f0 + static_cast<int>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) m.F.row(f0 + static_cast<int>(i)) << f[i][0], f[i][1], f[i][2];
}

Joint joint(const std::string& name, int parent, const Vector3d& offset) {
  Joint j;
  j.name = name;
  j.parent = parent;
  j.offset = offset;
  j.axis = Vector3d::UnitZ();
  return j;
}

int body25(const char* name) {
  for (int k = 0; k < kBody25Count; ++k)
    if (std::string(kBody25Names[k]) == name) return k;
  return -1;
}

// A torso (radius 150 mm, 0–1700 mm, around x = 500 mm) and a hand hanging beside it
// (radius 40 mm at x = 900 mm, 500–1300 mm: within the skirt's heights, clear of its
// flare) skinned to a joint below a shoulder: millimetres.
struct TestCharacter {
  Character ch;
  int torso_vertices = 0;
};

TestCharacter test_character() {
  TestCharacter t;
  Character& ch = t.ch;
  ch.name = "cylinder";
  ch.metres_per_unit = 0.001;
  TriangleMesh& m = ch.body.mesh;
  m.V.resize(0, 3);
  m.F.resize(0, 3);
  add_cylinder(m, 500, 150, 0, 1700, 48, 69);
  t.torso_vertices = m.num_vertices();
  add_cylinder(m, 900, 40, 500, 1300, 16, 33);
  Skeleton& sk = ch.skeleton;
  sk.joints = {joint("hips", -1, {500, 900, 0}), joint("l_hip", 0, {80, -50, 0}), joint("r_hip", 0, {-80, -50, 0}),
               joint("shoulder", 0, {400, 450, 0}), joint("hand", 3, {0, -400, 0})};
  sk.dofs = {Dof{"hips_rz", {DofInfluence{0, 1.0}}}};
  ch.rest_dofs = Eigen::VectorXd::Zero(1);
  ch.bind = forward_kinematics(sk, ch.rest_dofs);
  ch.zero_pose = ch.bind;
  ch.body25[body25("LHip")].joints = {1};
  ch.body25[body25("RHip")].joints = {2};
  ch.body25[body25("RShoulder")].joints = {3};
  ch.body.weights.num_joints = sk.num_joints();
  for (int v = 0; v < m.num_vertices(); ++v)
    ch.body.weights.vertices.push_back(v < t.torso_vertices ? std::vector<SkinInfluence>{{0, 1.0}}
                                                            : std::vector<SkinInfluence>{{4, 0.7}, {0, 0.3}});
  return t;
}

}  // namespace

TEST(DressedCharacter, LandmarksComeFromSkeletonSkinningAndBody25) {
  const TestCharacter t = test_character();
  const std::vector<char> arm = arm_vertices_from_skinning(t.ch);
  ASSERT_EQ(static_cast<int>(arm.size()), t.ch.body.mesh.num_vertices());
  for (int v = 0; v < t.ch.body.mesh.num_vertices(); ++v)
    EXPECT_EQ(arm[v] != 0, v >= t.torso_vertices) << "vertex " << v;  // the hand: 0.7 on a joint below the shoulder
  EXPECT_LT((bind_pose_hip_centre(t.ch, "t") - Vector3d(500, 850, 0)).norm(), 1e-9);

  Character unmapped = t.ch;
  for (auto& s : unmapped.body25) s = {};
  EXPECT_TRUE(arm_vertices_from_skinning(unmapped).empty());
  expect_error([&] { bind_pose_hip_centre(unmapped, "u.yaml"); }, {"u.yaml", "RHip", "MidHip"});
}

TEST(DressedCharacter, SkirtAroundTheHipsInCharacterUnitsIgnoringTheArms) {
  TestCharacter t = test_character();
  const std::vector<char> arm = arm_vertices_from_skinning(t.ch);
  const Vector3d hips = bind_pose_hip_centre(t.ch, "t");
  GarmentSpec spec;
  spec.tube.top_y = hips.y() + 50;  // mm
  spec.tube.mid_x = hips.x();
  spec.tube.length = 450;
  spec.tube.flare = 0.35;
  spec.tube.clearance = 12;
  spec.tube.segments = 32;
  spec.tube.rings = 12;
  spec.graph_nodes = 40;

  // The axis is searched in the midline plane: this body does not cross x = 0.
  {
    Character c = t.ch;
    GarmentSpec at_zero = spec;
    at_zero.tube.mid_x = 0;
    expect_error([&] { dress_character(c, at_zero, arm, "t.yaml"); }, {"x = 0"});
  }
  const GarmentFit fit = dress_character(t.ch, spec, arm, "t.yaml");
  const Character& ch = t.ch;
  ASSERT_TRUE(ch.has_cloth());
  EXPECT_EQ(ch.cloth->path, "skirt.obj");
  EXPECT_EQ(ch.cloth->mesh.num_vertices(), 32 * 12);
  EXPECT_EQ(ch.cloth->graph.num_nodes(), 40);
  EXPECT_EQ(ch.cloth->graph.rigidity, Eigen::VectorXd::Constant(40, spec.rigidity));
  ASSERT_EQ(ch.attachment.size(), 32);
  EXPECT_EQ(fit.inside, 0);
  EXPECT_GE(fit.min_distance, 12 * (1 - 1e-9));
  for (int i = 0; i < ch.attachment.size(); ++i) {
    const Vector3d a = ch.cloth->mesh.V.row(ch.attachment.anchors(i)).transpose();
    EXPECT_NEAR(a.y(), 900, 1e-9);
    // Sized by the torso alone, also toward the hand at x = 860..940 mm.
    const double r = std::hypot(a.x() - 500, a.z());
    EXPECT_GT(r, 150 + 12 - 1e-9);
    EXPECT_LT(r, 150 + 12 + 15) << "anchor " << i;
    // Tied to the torso, not the hand, with the torso's skinning.
    EXPECT_LT(ch.attachment.body_vertices.row(i).maxCoeff(), t.torso_vertices);
    EXPECT_EQ(ch.cloth->weights.vertices[ch.attachment.anchors(i)][0].joint, 0);
  }

  // A hem below the body's lowest point is an error naming the config.
  TestCharacter low = test_character();
  GarmentSpec too_long = spec;
  too_long.tube.length = 1000;
  expect_error([&] { dress_character(low.ch, too_long, arm, "t.yaml"); }, {"t.yaml", "lowest point"});
}

TEST(DressedCharacterConfig, BaseConfigParsesInMetres) {
  ScratchDir dir("dressed_cfg");
  dir.write("ddc.yaml", "# stands for a character.yaml\n");
  const DefaultCharacterConfig c = parse_default_character_config(
      "base: ddc.yaml\ngarment: {type: skirt, top_offset: 0.05, length: 0.4, flare: 0.3, clearance: 0.01,\n"
      "          segments: 32, rings: 20, graph_nodes: 100, rigidity: 0.2}\n",
      dir.file("ddc_skirt.yaml"));
  EXPECT_EQ(c.base, std::filesystem::absolute(dir.file("ddc.yaml")).lexically_normal().string());
  EXPECT_EQ(c.name, "ddc_skirt");  // default: the config's stem
  EXPECT_EQ(c.garment, GarmentType::skirt);
  EXPECT_EQ(c.top_offset, 0.05);
  EXPECT_EQ(c.length, 0.4);
  EXPECT_EQ(c.flare, 0.3);
  EXPECT_EQ(c.clearance, 0.01);
  EXPECT_EQ(c.segments, 32);
  EXPECT_EQ(c.rings, 20);
  EXPECT_EQ(c.cloth_graph_nodes, 100);
  EXPECT_EQ(c.cloth_rigidity, 0.2);
}

TEST(DressedCharacterConfig, ErrorsNameKeyFileAndLine) {
  ScratchDir dir("dressed_cfg_errors");
  dir.write("ddc.yaml", "# stands for a character.yaml\n");
  dir.write("ddc.character", "# a Skeletool character\n");
  const std::string file = dir.file("x.yaml");
  auto parse = [&](const std::string& text) { parse_default_character_config(text, file); };
  expect_error([&] { parse("base: ddc.yaml\ngarment:\n  type: skirt\n  lenght: 0.4\n"); },
               {file + ":4:", "garment.lenght", "unknown key"});
  expect_error([&] { parse("base: ddc.yaml\nbsae: 1\n"); }, {file + ":2:", "bsae", "unknown key"});
  expect_error([&] { parse("base: ddc.yaml\nmesh: body.obj\n"); }, {file + ":2:", "mesh", "base"});
  expect_error([&] { parse("base: ddc.yaml\nheight_m: 1.7\n"); }, {file, "height_m", "base"});
  expect_error([&] { parse("base: missing.yaml\n"); }, {file + ":1:", "base", "missing.yaml"});
  expect_error([&] { parse("base: ddc.character\n"); }, {file + ":1:", "base", "character.yaml"});
  expect_error([&] { parse("base: ddc.yaml\ngarment: {type: dress}\n"); }, {file, "garment.type", "dress"});
  expect_error([&] { parse("base: ddc.yaml\ngarment: {length: -0.4}\n"); }, {file, "garment.length", "> 0"});
  expect_error([&] { parse("base: ddc.yaml\ngarment: {segments: 4}\n"); }, {file, "garment.segments", "8..4096"});
  expect_error([&] { parse("base: [ddc.yaml]\n"); }, {file + ":1:", "base"});
}
