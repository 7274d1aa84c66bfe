// The training losses: values by hand, the laws they encode (rigid motions cost no
// ARAP energy, attached anchors cost nothing), and silhouette boundary selection.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "capture/deformation/losses.h"
#include "graph/error.h"
#include "ops/ops.h"

namespace weft::capture {
namespace {

TEST(Losses, LandmarkLossWeightsSquaredPixelErrorsByConfidence) {
  const Tensor p = Tensor::from_data({1, 2, 2}, std::vector<double>{10, 10, 0, 0}, DType::F64);
  const Tensor d = Tensor::from_data({1, 2, 2}, std::vector<double>{13, 14, 50, 50}, DType::F64);
  const Tensor c = Tensor::from_data({1, 2}, std::vector<double>{0.5, 0.0}, DType::F64);
  EXPECT_DOUBLE_EQ(landmark_loss(p, d, c).item(), 0.5 * 25);
  EXPECT_THROW(landmark_loss(p, d, Tensor::ones({2, 2}, DType::F64)), Error);
}

TEST(Losses, LumbopelvicTargetGivesThePelvisItsShareOfTheTrunksLean) {
  const Eigen::Vector3d up = Eigen::Vector3d::UnitY();
  const double deg = std::numbers::pi / 180;
  // The trunk leaned 45° forward (toward +z) from upright: with the lumbar spine taking
  // 60 %, the pelvis's up axis leans 18° forward.
  const Eigen::Vector3d trunk(0, std::cos(45 * deg), std::sin(45 * deg));
  const Eigen::Vector3d t = lumbopelvic_target(2 * trunk, 0.3 * up, 0.6);
  EXPECT_NEAR(std::acos(t.dot(up)) / deg, 18, 1e-9);
  EXPECT_NEAR(t.x(), 0, 1e-12);
  EXPECT_GT(t.z(), 0);
  // Relative to the rest direction: a rest trunk leaning 5° back, the same trunk now: the
  // pelvis takes 40 % of 50°.
  const Eigen::Vector3d rest(0, std::cos(5 * deg), -std::sin(5 * deg));
  EXPECT_NEAR(std::acos(lumbopelvic_target(trunk, rest, 0.6).dot(up)) / deg, 20, 1e-9);
  // The whole lean to the lumbar spine: the pelvis stays upright; none: it leans with the trunk.
  EXPECT_TRUE(lumbopelvic_target(trunk, up, 1.0).isApprox(up, 1e-12));
  EXPECT_TRUE(lumbopelvic_target(trunk, up, 0.0).isApprox(trunk, 1e-12));
  // No trunk (a NaN keypoint): upright.
  EXPECT_EQ(lumbopelvic_target(Eigen::Vector3d::Constant(NAN), up, 0.6), up);
}

TEST(Losses, LumbopelvicLossIsTheSquaredDistanceOfThePelvisUpAxis) {
  // Two frames: the identity (up axis +y) against +y (0) and a rotation of 90° about x (up
  // axis +z) against +y: ‖(0, −1, 1)‖² = 2; mean over frames 1.
  std::vector<double> R = {1, 0, 0, 0, 1, 0, 0, 0, 1,  1, 0, 0, 0, 0, -1, 0, 1, 0};
  const Tensor rotations = Tensor::from_data({2, 3, 3}, R, DType::F64);
  const Tensor targets = Tensor::from_data({2, 3}, {0, 1, 0, 0, 1, 0}, DType::F64);
  EXPECT_NEAR(lumbopelvic_loss(rotations, targets).item(), 1.0, 1e-12);
  EXPECT_THROW(lumbopelvic_loss(rotations, Tensor::from_data({2, 2}, {0, 1, 0, 1}, DType::F64)), Error);
}

TEST(Losses, ArapEnergyVanishesForARigidMotionOfTheGraph) {
  EmbeddedGraph g;
  g.nodes.resize(4, 3);
  g.nodes << 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1;
  g.edges.resize(4, 2);
  g.edges << 0, 1, 0, 2, 0, 3, 1, 2;
  g.rigidity = Eigen::VectorXd::Ones(4);
  const ArapTerms terms = arap_terms(g, DType::F64);
  Generator gen(2);
  const Tensor angles = Tensor::rand({1, 1, 3}, gen, DType::F64, -1, 1);
  const Tensor R1 = ops::euler_to_rotation(angles);
  Tensor R = Tensor::empty({1, 4, 3, 3}, DType::F64), t = Tensor::empty({1, 4, 3}, DType::F64);
  const Eigen::Vector3d c(0.3, -0.2, 0.5);
  for (int j = 0; j < 4; ++j) {
    Eigen::Matrix3d Rm;
    for (int k = 0; k < 9; ++k) {
      R.data<double>()[9 * j + k] = R1.data<double>()[k];
      Rm(k / 3, k % 3) = R1.data<double>()[k];
    }
    const Eigen::Vector3d gj = g.nodes.row(j).transpose();
    const Eigen::Vector3d tj = Rm * gj + c - gj;  // node j moves to R g_j + c
    for (int a = 0; a < 3; ++a) t.data<double>()[3 * j + a] = tj[a];
  }
  EXPECT_NEAR(arap_loss(terms, R, t).item(), 0.0, 1e-24);
  t.data<double>()[0] += 0.1;  // bend the graph: energy appears
  EXPECT_GT(arap_loss(terms, R, t).item(), 1e-4);
}

TEST(Losses, AttachmentLossIsZeroWhenAnchorsSitOnTheirTriangles) {
  Attachment a;
  a.anchors.resize(1);
  a.anchors << 1;
  a.triangles.resize(1);
  a.triangles << 0;
  a.body_vertices.resize(1, 3);
  a.body_vertices << 0, 1, 2;
  a.barycentric.resize(1, 3);
  a.barycentric << 0.2, 0.3, 0.5;
  const AttachmentTerms terms = attachment_terms(a, DType::F64);
  const Tensor body = Tensor::from_data({1, 3, 3}, std::vector<double>{0, 0, 0, 1, 0, 0, 0, 1, 0}, DType::F64);
  Tensor cloth = Tensor::from_data({1, 2, 3}, std::vector<double>{5, 5, 5, 0.3, 0.5, 0}, DType::F64);
  EXPECT_NEAR(attachment_loss(terms, cloth, body).item(), 0.0, 1e-24);
  cloth.set({0, 1, 2}, 0.2);  // 0.2 off the triangle
  EXPECT_NEAR(attachment_loss(terms, cloth, body).item(), 0.04, 1e-12);
}

// A UV sphere of radius r around the origin.
TriangleMesh sphere(double r, int rings, int segments) {
  TriangleMesh m;
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double th = M_PI * i / rings, ph = 2 * M_PI * j / segments;
      v.emplace_back(r * std::sin(th) * std::cos(ph), r * std::cos(th), r * std::sin(th) * std::sin(ph));
    }
  m.V.resize(static_cast<int>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) m.V.row(static_cast<int>(i)) = v[i].transpose();
  std::vector<Eigen::Vector3i> f;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      const int c = a + segments, d = b + segments;
      f.emplace_back(a, c, b);
      f.emplace_back(b, c, d);
    }
  m.F.resize(static_cast<int>(f.size()), 3);
  for (size_t i = 0; i < f.size(); ++i) m.F.row(static_cast<int>(i)) = f[i].transpose();
  return m;
}

TEST(Losses, SilhouetteBoundaryOfASphereIsItsVisibleContour) {
  const TriangleMesh s = sphere(1.0, 40, 80);
  Camera cam;
  cam.K << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  cam.t = Eigen::Vector3d(0, 0, 5);  // sphere 5 units in front
  cam.width = 640, cam.height = 480;
  const std::vector<int> b = boundary_vertices(cam, s.V, s.F, 0.3);
  ASSERT_GT(b.size(), 20u);
  // Contour radius in the image: f·r/√(d² − r²) = 500/√24 ≈ 102 px around (320, 240).
  const double contour = 500 / std::sqrt(24.0);
  for (int v : b) {
    const Eigen::Vector2d px = cam.project(s.V.row(v).transpose());
    EXPECT_NEAR((px - Eigen::Vector2d(320, 240)).norm(), contour, 0.1 * contour);
    EXPECT_LE(s.V(v, 2), 0.35) << "hidden back-side vertex selected";
  }
}

TEST(Losses, SilhouetteLossSamplesTheDistanceTransform) {
  // D = x (pixels from the left edge): points at x = 2 and 3 with ρ = 1 and 0.
  Tensor dt = Tensor::empty({1, 4, 6}, DType::F64);
  for (int y = 0; y < 4; ++y)
    for (int x = 0; x < 6; ++x) dt.set({0, y, x}, x);
  const Tensor pts = Tensor::from_data({1, 2, 2}, std::vector<double>{2.5, 1.0, 3.0, 2.0}, DType::F64);
  const Tensor rho = Tensor::from_data({1, 2}, std::vector<double>{1, 0}, DType::F64);
  EXPECT_NEAR(silhouette_loss(pts, dt, rho).item(), 2.5 * 2.5, 1e-12);
}

}  // namespace
}  // namespace weft::capture
