// Building blocks of the default character on small synthetic shapes: strict config
// parsing, cross-sections, the inside test, the skeleton builder and the tube garment.
// The real MakeHuman body is tested in default_character_integration_test.cpp.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "capture/character/default_character.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using Eigen::Vector3d;

namespace {

// A closed, outward-facing cylinder of radius r around the y axis from y0 to y1 (capped).
TriangleMesh cylinder(double r, double y0, double y1, int around = 32, int rows = 20, double cx = 0) {
  TriangleMesh m;
  const int n = around * rows + 2;
  m.V.resize(n, 3);
  for (int i = 0; i < rows; ++i)
    for (int k = 0; k < around; ++k) {
      const double a = 2 * std::numbers::pi * k / around;
      m.V.row(i * around + k) << cx + r * std::cos(a), y1 - (y1 - y0) * i / (rows - 1), r * std::sin(a);
    }
  const int top = n - 2, bottom = n - 1;
  m.V.row(top) << cx, y1, 0;
  m.V.row(bottom) << cx, y0, 0;
  std::vector<std::array<int, 3>> f;
  for (int i = 0; i + 1 < rows; ++i)
    for (int k = 0; k < around; ++k) {
      const int a = i * around + k, b = i * around + (k + 1) % around, c = a + around, d = b + around;
      f.push_back({a, b, c});
      f.push_back({b, d, c});
    }
  for (int k = 0; k < around; ++k) {
    f.push_back({top, (k + 1) % around, k});
    const int last = (rows - 1) * around;
    f.push_back({bottom, last + k, last + (k + 1) % around});
  }
  m.F.resize(static_cast<Eigen::Index>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) m.F.row(static_cast<Eigen::Index>(i)) << f[i][0], f[i][1], f[i][2];
  return m;
}

}  // namespace

TEST(DefaultCharacterConfig, ParsesEveryKey) {
  const DefaultCharacterConfig c = parse_default_character_config(
      "name: x\nmesh: body.obj\nheight_m: 1.8\nbody: {graph_nodes: 200, nodes_per_vertex: 3}\n"
      "garment:\n  type: dress\n  straps: true\n  length: 0.7\n  flare: 0.2\n  clearance: 0.02\n  top_offset: 0.05\n"
      "  segments: 48\n  rings: 30\n  graph_nodes: 100\n  rigidity: 0.3\n",
      "/cfg/c.yaml");
  EXPECT_EQ(c.name, "x");
  EXPECT_EQ(c.mesh, "/cfg/body.obj");  // relative to the config's folder
  EXPECT_EQ(c.height_m, 1.8);
  EXPECT_EQ(c.body_graph_nodes, 200);
  EXPECT_EQ(c.nodes_per_vertex, 3);
  EXPECT_EQ(c.garment, GarmentType::dress);
  EXPECT_TRUE(c.straps);
  EXPECT_EQ(c.length, 0.7);
  EXPECT_EQ(c.flare, 0.2);
  EXPECT_EQ(c.clearance, 0.02);
  EXPECT_EQ(c.top_offset, 0.05);
  EXPECT_EQ(c.segments, 48);
  EXPECT_EQ(c.rings, 30);
  EXPECT_EQ(c.cloth_graph_nodes, 100);
  EXPECT_EQ(c.cloth_rigidity, 0.3);
}

TEST(DefaultCharacterConfig, UnknownKeysAndBadValuesNameKeyAndFile) {
  expect_error([] { parse_default_character_config("name: x\nheigth_m: 1.7\n", "a.yaml"); },
               {"a.yaml", "heigth_m", "unknown key"});
  expect_error([] { parse_default_character_config("garment: {type: skirt, lenght: 0.4}\n", "b.yaml"); },
               {"b.yaml", "garment.lenght"});
  expect_error([] { parse_default_character_config("garment: {type: trousers}\n", "c.yaml"); },
               {"c.yaml", "garment.type", "trousers"});
  expect_error([] { parse_default_character_config("height_m: -2\n", "d.yaml"); }, {"d.yaml", "height_m", "> 0"});
  expect_error([] { parse_default_character_config("garment: {type: skirt, straps: true}\n", "s.yaml"); },
               {"s.yaml", "garment.straps", "dress"});
  expect_error([] { parse_default_character_config("garment: {segments: 4}\n", "e.yaml"); },
               {"e.yaml", "garment.segments"});
  expect_error([] { parse_default_character_config("height_m: tall\n", "f.yaml"); }, {"f.yaml", "height_m"});
  expect_error([] { load_default_character_config("/nonexistent/g.yaml"); }, {"/nonexistent/g.yaml"});
}

TEST(DefaultCharacterGeometry, SlicesGiveOneContourPerComponent) {
  TriangleMesh two = cylinder(0.1, 0, 1, 32, 10, -0.3);
  const TriangleMesh right = cylinder(0.05, 0, 1, 32, 10, 0.3);
  const int n = two.num_vertices();
  two.V.conservativeResize(n + right.num_vertices(), 3);
  two.V.bottomRows(right.num_vertices()) = right.V;
  const int m = two.num_faces();
  two.F.conservativeResize(m + right.num_faces(), 3);
  two.F.bottomRows(right.num_faces()) = right.F.array() + n;
  const auto sections = slice_mesh(two, Vector3d::UnitY(), 0.5);
  ASSERT_EQ(sections.size(), 2u);
  for (const Section& s : sections) {
    const bool big = s.centroid.x() < 0;
    EXPECT_NEAR(s.centroid.x(), big ? -0.3 : 0.3, 1e-9);
    EXPECT_NEAR(s.centroid.y(), 0.5, 1e-12);
    EXPECT_NEAR(s.centroid.z(), 0.0, 1e-9);
    // A regular 32-gon inscribed in the circle.
    const double r = big ? 0.1 : 0.05;
    EXPECT_NEAR(s.area, 0.5 * 32 * r * r * std::sin(2 * std::numbers::pi / 32), 1e-9);
    EXPECT_EQ(s.points.size(), 64u);  // one point per crossed edge: 32 vertical, 32 diagonals
  }
  EXPECT_TRUE(slice_mesh(two, Vector3d::UnitY(), 1.5).empty());
}

TEST(DefaultCharacterGeometry, WindingNumberSeparatesInsideFromOutside) {
  const TriangleMesh c = cylinder(0.2, 0, 1);
  EXPECT_NEAR(winding_number(c.V, c.F, Vector3d(0, 0.5, 0)), 1.0, 1e-9);
  EXPECT_NEAR(winding_number(c.V, c.F, Vector3d(0.19, 0.1, 0)), 1.0, 1e-9);
  EXPECT_NEAR(winding_number(c.V, c.F, Vector3d(0.3, 0.5, 0)), 0.0, 1e-9);
  EXPECT_NEAR(winding_number(c.V, c.F, Vector3d(0, 1.2, 0)), 0.0, 1e-9);
}

TEST(DefaultCharacterGeometry, TubeGarmentClearsAndFlaresAroundACylinder) {
  const TriangleMesh body = cylinder(0.15, 0, 1.2, 48, 30);
  TubeGarmentOptions o;
  o.top_y = 1.0;
  o.length = 0.5;
  o.flare = 0.4;
  o.clearance = 0.02;
  o.segments = 40;
  o.rings = 21;
  const TubeGarment g = generate_tube_garment(body, {}, o);
  ASSERT_EQ(g.mesh.num_vertices(), 40 * 21);
  EXPECT_EQ(g.anchors.size(), 40u);
  EXPECT_EQ(g.inside, 0);
  EXPECT_GE(g.min_distance, o.clearance * 0.999);
  const Eigen::VectorXd sd = signed_distances(body, g.mesh.V);
  EXPECT_GE(sd.minCoeff(), o.clearance * 0.999);
  // The top ring hugs the body (radius + clearance, a little more between samples);
  // the hem has gained flare × length.
  const double top_r = std::hypot(g.mesh.V(0, 0), g.mesh.V(0, 2));
  const double hem_r = std::hypot(g.mesh.V(20 * 40, 0), g.mesh.V(20 * 40, 2));
  EXPECT_GT(top_r, 0.15 + 0.02 - 1e-9);
  EXPECT_LT(top_r, 0.15 + 0.03);
  EXPECT_NEAR(hem_r - top_r, o.flare * o.length, 0.01);
  EXPECT_NEAR(g.mesh.V.col(1).minCoeff(), 0.5, 1e-12);
  // The exclusion list must have one entry per body vertex.
  expect_error([&] { generate_tube_garment(body, std::vector<char>(3, 0), o); }, {"excluded"});
}

TEST(DefaultCharacterGeometry, SkeletonBuilderChainsAndMarkers) {
  std::map<std::string, Vector3d> pos;
  // A stick figure: 1.7 m, left at +x, facing +z.
  pos["hips"] = {0, 0.9, 0};
  pos["spine"] = {0, 1.05, 0};
  pos["chest"] = {0, 1.25, 0};
  pos["neck"] = {0, 1.45, 0};
  pos["head"] = {0, 1.52, 0};
  pos["head_end"] = {0, 1.68, 0};
  for (const double s : {1.0, -1.0}) {
    const std::string p = s > 0 ? "l_" : "r_";
    pos[p + "clavicle"] = {s * 0.03, 1.4, 0};
    pos[p + "shoulder"] = {s * 0.18, 1.4, 0};
    pos[p + "elbow"] = {s * 0.38, 1.2, 0};
    pos[p + "wrist"] = {s * 0.55, 1.03, 0};
    pos[p + "hand_end"] = {s * 0.62, 0.96, 0};
    pos[p + "hip"] = {s * 0.1, 0.9, 0};
    pos[p + "knee"] = {s * 0.12, 0.48, 0};
    pos[p + "ankle"] = {s * 0.13, 0.07, 0};
    pos[p + "toe"] = {s * 0.13, 0.02, 0.14};
    pos[p + "toe_end"] = {s * 0.13, 0.02, 0.19};
  }
  const std::map<std::string, Vector3d> markers{{"nose", {0, 1.6, 0.1}}, {"l_heel", {0.13, 0.02, -0.05}}};
  const Skeleton s = build_body_skeleton(pos, markers);
  EXPECT_EQ(s.num_dofs(), 54);
  EXPECT_EQ(s.num_joints(), 59);
  const Transforms G = forward_kinematics(s, Eigen::VectorXd::Zero(s.num_dofs()));
  for (const auto& [name, p] : pos) EXPECT_LT((G[s.joint_index(name)].translation() - p).norm(), 1e-12) << name;
  ASSERT_EQ(s.num_markers(), 2);
  EXPECT_EQ(s.joints[s.markers[s.marker_index("nose")].joint].name, "head");
  EXPECT_EQ(s.joints[s.markers[s.marker_index("l_heel")].joint].name, "l_ankle");
  // Turning the root about y by 90° carries the left hand from +x to −z.
  Eigen::VectorXd q = Eigen::VectorXd::Zero(s.num_dofs());
  q(s.dof_index("hips_ry")) = std::numbers::pi / 2;
  const Transforms R = forward_kinematics(s, q);
  EXPECT_LT(R[s.joint_index("l_wrist")].translation().z(), -0.5);
  expect_error([&] { build_body_skeleton({{"hips", {0, 1, 0}}}, {}); }, {"spine"});
}
