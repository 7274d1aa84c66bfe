// Every per-frame metric of the evaluations (frame_metrics(), capture/evaluation/
// frame_measures.h) has a known-answer case here, measured through the same functions
// `weft eval` and `weft train --evaluate` call: a prediction moved, turned, pushed into
// the body, held still in the air or dropped, against a truth built for it. The coverage
// test fails on a metric without a case, as the op registry's gradient checks do for ops.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <numbers>
#include <numeric>
#include <set>

#include "capture/evaluation/frame_measures.h"
#include "geometry/mesh.h"
#include "graph/error.h"
#include "tests/capture/sphere_and_sheet.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::sphere_and_sheet;

namespace {

// The sheet is 0.1 m or more outside this body.
const Character& far_apart() {
  static const Character ch = sphere_and_sheet(Eigen::Vector3d(0, 1, 0));
  return ch;
}

// The truth: the character at rest, three keypoints, the pivot at the sphere's centre.
PosedFrame truth_of(const Character& ch) {
  PosedFrame t;
  t.body = ch.body.mesh.V;
  t.cloth = ch.cloth->mesh.V;
  t.body25.resize(3, 3);
  t.body25 << 0, 1.5, 0, 0.2, 1.2, 0, -0.2, 1.2, 0;
  t.pivot = Eigen::Vector3d(0, 1, 0);
  t.root_rotation = Eigen::Matrix3d::Identity();
  return t;
}

Vertices moved(const Vertices& V, const Eigen::Vector3d& d) { return V.rowwise() + d.transpose(); }

// Geometry measures of `predicted` against the rest truth of far_apart().
FrameMeasures geometry(const std::function<void(PosedFrame&)>& change) {
  const PosedFrame t = truth_of(far_apart());
  PosedFrame p = t;
  change(p);
  FrameMeasures m;
  measure_geometry(far_apart(), p, t, true, m);
  return m;
}

// The out-of-balance force of the sheet at x(0), x(1), x(2) (1/30 s apart) with the body still.
FrameMeasures balance(const Character& ch, const std::function<Vertices(int)>& x) {
  FrameMeasures m;
  measure_balance(ch, SynthSimulationConfig{}, 30, ch.body.mesh.V, ch.body.mesh.V, x(0), x(1), x(2), m);
  return m;
}

// The weight (N) of each vertex of the sheet: lumped masses, a third of each triangle.
std::vector<double> vertex_weights() {
  const SynthSimulationConfig s;
  const double g = physics::SimulationSettings{}.gravity.norm(), triangle = 0.05 * 0.05 / 2;
  const TriangleMesh& m = far_apart().cloth->mesh;
  std::vector<double> w(m.V.rows(), 0.0);
  for (int f = 0; f < m.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) w[m.F(f, k)] += s.material.density * triangle / 3 * g;
  return w;
}

// The prediction: the sheet's centre vertex (12) moved `depth_m` inside the sphere
// (negative: outside), the rest 0.1 m or more outside.
FrameMeasures one_vertex_at(double depth_m) {
  const PosedFrame t = truth_of(far_apart());
  PosedFrame p = t;
  // The sphere's face nearest the direction (0, 0, 1): its centroid, pushed 5 mm inward.
  const TriangleMesh& s = far_apart().body.mesh;
  const Vertices normals = face_normals(s.V, s.F);
  int face = 0;
  for (int f = 1; f < s.num_faces(); ++f)
    if (normals(f, 2) > normals(face, 2)) face = f;
  const Eigen::Vector3d c = (s.V.row(s.F(face, 0)) + s.V.row(s.F(face, 1)) + s.V.row(s.F(face, 2))).transpose() / 3;
  p.cloth.row(12) = (c - depth_m * normals.row(face).transpose()).transpose();
  FrameMeasures m;
  measure_geometry(far_apart(), p, t, true, m);
  return m;
}
FrameMeasures one_vertex_inside() { return one_vertex_at(0.005); }

// The sheet's centre vertex 1 cm inside a ball of 2 cm; the other vertices 3 cm or more
// outside it.
const Character& centre_inside() {
  static const Character ch = sphere_and_sheet(Eigen::Vector3d(0, 1, 0.4 - 0.01), 0.02);
  return ch;
}

struct MetricCase {
  std::string metric;
  std::string what;
  std::function<void()> check;
};

std::vector<MetricCase> metric_cases() {
  std::vector<MetricCase> c;
  c.push_back({"pivot_error_mm", "the pivot 3 cm + 4 cm off", [] {
                 EXPECT_NEAR(geometry([](PosedFrame& p) { p.pivot += Eigen::Vector3d(0.03, 0, 0.04); }).pivot_error_mm,
                             50, 1e-9);
               }});
  c.push_back({"mpjpe_mm", "every keypoint 2 cm up; an unmapped (NaN) row left out", [] {
                 EXPECT_NEAR(geometry([](PosedFrame& p) {
                               p.body25 = moved(p.body25, {0, 0.02, 0});
                               p.body25.row(1).setConstant(kNotMeasured);
                             }).mpjpe_mm,
                             20, 1e-9);
               }});
  c.push_back({"mpjpe_root_relative_mm", "the skeleton moved whole is 0; one of 3 keypoints 3 cm off is 10", [] {
                 const FrameMeasures m = geometry([](PosedFrame& p) {
                   p.body25 = moved(p.body25, {0.1, 0.2, 0.3});
                   p.pivot += Eigen::Vector3d(0.1, 0.2, 0.3);
                   p.body25(2, 0) += 0.03;
                 });
                 EXPECT_NEAR(m.mpjpe_root_relative_mm, 10, 1e-9);
                 EXPECT_GT(m.mpjpe_mm, 300);
               }});
  c.push_back({"pa_mpjpe_mm", "scaled ×1.5, turned 40° and moved whole is 0; one of 4 keypoints off is not", [] {
                 // Four keypoints (three are collinear-free but a tetrahedron pins every axis).
                 const auto with4 = [](PosedFrame& f) {
                   f.body25.conservativeResize(4, 3);
                   f.body25.row(3) << 0, 1.2, 0.3;
                 };
                 const Eigen::Matrix3d R = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
                 PosedFrame t = truth_of(far_apart());
                 with4(t);
                 PosedFrame p = t;
                 p.body25 = ((1.5 * R * t.body25.transpose()).colwise() + Eigen::Vector3d(0.3, -0.1, 2)).transpose();
                 FrameMeasures m;
                 measure_geometry(far_apart(), p, t, true, m);
                 EXPECT_NEAR(m.pa_mpjpe_mm, 0, 1e-6);
                 EXPECT_GT(m.mpjpe_root_relative_mm, 100);
                 ASSERT_EQ(m.joint_errors_pa_mm.size(), 4u);
                 for (double e : m.joint_errors_pa_mm) EXPECT_NEAR(e, 0, 1e-6);
                 // One keypoint 4 cm off: the alignment spreads the error over the keypoints
                 // and lowers its sum of squares (the quantity it minimises) below the
                 // unaligned 40² mm², so the aligned RMS is under 20 mm, but not to 0. (The
                 // mean of distances may exceed the unaligned 10 mm: spread is not removed.)
                 p = t;
                 p.body25(3, 2) += 0.04;
                 FrameMeasures one;
                 measure_geometry(far_apart(), p, t, true, one);
                 EXPECT_NEAR(one.mpjpe_root_relative_mm, 10, 1e-9);
                 double squares = 0;
                 for (double e : one.joint_errors_pa_mm) squares += e * e;
                 EXPECT_LT(squares, 40.0 * 40.0 - 1);
                 EXPECT_GT(one.pa_mpjpe_mm, 1);
                 EXPECT_LT(one.pa_mpjpe_mm, 20);
                 p.body25.row(0).setConstant(kNotMeasured);
                 measure_geometry(far_apart(), p, t, true, one);
                 EXPECT_TRUE(std::isnan(one.joint_errors_pa_mm[0]));
                 // Three rows left of which one is off: still fitted, and two rows are too few.
                 EXPECT_TRUE(std::isfinite(one.pa_mpjpe_mm));
                 p.body25.row(1).setConstant(kNotMeasured);
                 measure_geometry(far_apart(), p, t, true, one);
                 EXPECT_TRUE(std::isnan(one.pa_mpjpe_mm));
               }});
  static const auto split = [](const Eigen::Matrix3d& world_to_camera) {
    PosedFrame t = truth_of(far_apart());
    t.view_rotation = world_to_camera;
    PosedFrame p = t;
    p.body25(0, 2) += 0.03;  // the first keypoint 3 cm along world z
    p.body25(1, 0) += 0.06;  // the second 6 cm along world x
    FrameMeasures m;
    measure_geometry(far_apart(), p, t, true, m);
    return m;
  };
  c.push_back({"mpjpe_depth_mm", "a camera looking along world z: a 3 cm error along z is depth; no camera: none", [] {
                 EXPECT_NEAR(split(Eigen::Matrix3d::Identity()).mpjpe_depth_mm, 10, 1e-9);
                 // A camera looking along world x (turned 90° about y): the 6 cm error is depth.
                 EXPECT_NEAR(split(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY()).toRotationMatrix())
                                 .mpjpe_depth_mm,
                             20, 1e-9);
                 EXPECT_TRUE(std::isnan(geometry([](PosedFrame&) {}).mpjpe_depth_mm));
               }});
  c.push_back({"mpjpe_image_plane_mm", "the same cameras: the other error is across the image", [] {
                 EXPECT_NEAR(split(Eigen::Matrix3d::Identity()).mpjpe_image_plane_mm, 20, 1e-9);
                 EXPECT_NEAR(split(Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitY()).toRotationMatrix())
                                 .mpjpe_image_plane_mm,
                             10, 1e-9);
               }});
  c.push_back({"root_rotation_error_deg", "turned 30° about the vertical; 180° for front/back", [] {
                 EXPECT_NEAR(geometry([](PosedFrame& p) {
                               p.root_rotation = Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitY())
                                                     .toRotationMatrix();
                             }).root_rotation_error_deg,
                             30, 1e-9);
                 EXPECT_NEAR(geometry([](PosedFrame& p) {
                               p.root_rotation =
                                   Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY()).toRotationMatrix();
                             }).root_rotation_error_deg,
                             180, 1e-6);
                 EXPECT_TRUE(std::isnan(geometry([](PosedFrame& p) { p.root_rotation.reset(); }).root_rotation_error_deg));
               }});
  c.push_back({"root_heading_error_deg", "turned 30° about the vertical: 30; tilted 40° forward: 0; front/back: 180", [] {
                 const auto heading = [](const Eigen::AngleAxisd& turn) {
                   return geometry([&](PosedFrame& p) { p.root_rotation = turn.toRotationMatrix(); })
                       .root_heading_error_deg;
                 };
                 EXPECT_NEAR(heading(Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitY())), 30, 1e-9);
                 EXPECT_NEAR(heading(Eigen::AngleAxisd(-std::numbers::pi / 6, Eigen::Vector3d::UnitY())), 30, 1e-9);
                 EXPECT_NEAR(heading(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitX())), 0, 1e-9);
                 EXPECT_NEAR(heading(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY())), 180, 1e-6);
                 EXPECT_TRUE(std::isnan(geometry([](PosedFrame& p) { p.root_rotation.reset(); }).root_heading_error_deg));
               }});
  c.push_back({"root_tilt_error_deg", "tilted 40° forward: 40; turned 30° about the vertical: 0; both: 40", [] {
                 const auto tilt = [](const Eigen::Matrix3d& turn) {
                   return geometry([&](PosedFrame& p) { p.root_rotation = turn; }).root_tilt_error_deg;
                 };
                 const double forward = 40 * std::numbers::pi / 180;
                 const Eigen::Matrix3d pitch = Eigen::AngleAxisd(forward, Eigen::Vector3d::UnitX()).toRotationMatrix();
                 const Eigen::Matrix3d yaw =
                     Eigen::AngleAxisd(std::numbers::pi / 6, Eigen::Vector3d::UnitY()).toRotationMatrix();
                 EXPECT_NEAR(tilt(pitch), 40, 1e-9);
                 EXPECT_NEAR(tilt(yaw), 0, 1e-9);
                 EXPECT_NEAR(tilt(Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitY()).toRotationMatrix()), 0,
                             1e-6);
                 // Turned first, then tilted: the swing–twist split gives each part back.
                 EXPECT_NEAR(tilt(pitch * yaw), 40, 1e-9);
                 EXPECT_NEAR(geometry([&](PosedFrame& p) { p.root_rotation = pitch * yaw; }).root_heading_error_deg, 30,
                             1e-9);
                 EXPECT_TRUE(std::isnan(geometry([](PosedFrame& p) { p.root_rotation.reset(); }).root_tilt_error_deg));
               }});
  c.push_back({"trunk_direction_error_deg", "the neck leaned 45° forward over the mid-hip: 45; moved whole: 0; "
               "no neck: not measured", [] {
                 const auto skeleton = [](PosedFrame& p) {  // BODY_25 rows: 1 Neck, 8 MidHip, the rest unmapped
                   p.body25 = Vertices::Constant(25, 3, kNotMeasured);
                   p.body25.row(8) << 0, 1, 0;
                   p.body25.row(1) << 0, 1.5, 0;
                 };
                 const auto trunk = [&](const std::function<void(PosedFrame&)>& change) {
                   PosedFrame t = truth_of(far_apart());
                   skeleton(t);
                   PosedFrame p = t;
                   change(p);
                   FrameMeasures m;
                   measure_geometry(far_apart(), p, t, true, m);
                   return m.trunk_direction_error_deg;
                 };
                 EXPECT_NEAR(trunk([](PosedFrame& p) { p.body25.row(1) << 0, 1.5, 0.5; }), 45, 1e-9);
                 EXPECT_NEAR(trunk([](PosedFrame& p) { p.body25 = moved(p.body25, {0.3, -0.2, 0.1}); }), 0, 1e-6);
                 EXPECT_NEAR(trunk([](PosedFrame& p) { p.body25.row(1) << 0, 0.5, 0; }), 180, 1e-9);
                 EXPECT_TRUE(std::isnan(trunk([](PosedFrame& p) { p.body25.row(1).setConstant(kNotMeasured); })));
                 EXPECT_TRUE(std::isnan(geometry([](PosedFrame&) {}).trunk_direction_error_deg));  // 3 rows only
               }});
  c.push_back({"body_error_mean_mm", "the body 5 mm to the side", [] {
                 EXPECT_NEAR(geometry([](PosedFrame& p) { p.body = moved(p.body, {0.005, 0, 0}); }).body_error_mean_mm,
                             5, 1e-9);
               }});
  c.push_back({"body_error_p95_mm", "vertex i moved i mm: NumPy's percentile", [] {
                 const FrameMeasures m = geometry([](PosedFrame& p) {
                   for (int i = 0; i < p.body.rows(); ++i) p.body(i, 0) += 1e-3 * i;
                 });
                 EXPECT_NEAR(m.body_error_p95_mm, 0.95 * double(far_apart().body.mesh.V.rows() - 1), 1e-6);
               }});
  c.push_back({"cloth_error_mean_mm", "the cloth 7 mm down", [] {
                 EXPECT_NEAR(
                     geometry([](PosedFrame& p) { p.cloth = moved(p.cloth, {0, -0.007, 0}); }).cloth_error_mean_mm, 7,
                     1e-9);
               }});
  c.push_back({"cloth_error_p95_mm", "cloth vertex i moved i mm out: 0.95 × 24", [] {
                 EXPECT_NEAR(geometry([](PosedFrame& p) {
                               for (int i = 0; i < p.cloth.rows(); ++i) p.cloth(i, 2) += 1e-3 * i;
                             }).cloth_error_p95_mm,
                             22.8, 1e-9);
               }});
  c.push_back({"cloth_chamfer_mm", "6 mm off its plane is 6; slid within its plane it is below the vertex error", [] {
                 EXPECT_NEAR(geometry([](PosedFrame& p) { p.cloth = moved(p.cloth, {0, 0, 0.006}); }).cloth_chamfer_mm,
                             6, 1e-9);
                 const FrameMeasures slid = geometry([](PosedFrame& p) { p.cloth = moved(p.cloth, {0.02, 0, 0}); });
                 EXPECT_NEAR(slid.cloth_error_mean_mm, 20, 1e-9);
                 EXPECT_LT(slid.cloth_chamfer_mm, 5);
               }});
  c.push_back({"penetration_mean_mm", "one vertex 5 mm inside: 5 mm over the vertices inside", [] {
                 EXPECT_NEAR(one_vertex_inside().penetration_mean_mm, 5, 1e-9);
                 EXPECT_EQ(geometry([](PosedFrame&) {}).penetration_mean_mm, 0.0);
               }});
  c.push_back({"penetration_mean_all_mm", "one of 25 vertices 5 mm inside: 0.2 mm", [] {
                 EXPECT_NEAR(one_vertex_inside().penetration_mean_all_mm, 0.2, 1e-9);
               }});
  c.push_back({"penetration_max_mm", "one vertex 5 mm inside", [] {
                 EXPECT_NEAR(one_vertex_inside().penetration_max_mm, 5, 1e-9);
               }});
  c.push_back({"penetrating_fraction", "one of 25 vertices inside", [] {
                 const FrameMeasures m = one_vertex_inside();
                 EXPECT_DOUBLE_EQ(m.penetrating_fraction, 1.0 / 25);
                 EXPECT_EQ(m.penetrating_vertices, 1);
                 // An anchor inside is the attachment's, not the garment's: left out, and
                 // the fraction is over the 24 free vertices.
                 Character held = far_apart();
                 held.attachment.anchors = Eigen::VectorXi::Constant(1, 12);
                 const PosedFrame t = truth_of(held);
                 PosedFrame p = t;
                 p.cloth.row(12) = Eigen::RowVector3d(0, 1, 0);  // the sphere's centre
                 p.cloth.row(0) += Eigen::RowVector3d(0, 0, 0.001);
                 FrameMeasures a;
                 measure_geometry(held, p, t, true, a);
                 EXPECT_EQ(a.penetrating_vertices, 0);
                 EXPECT_EQ(a.cloth_vertices, 24);
                 EXPECT_EQ(a.penetration_mean_all_mm, 0.0);
               }});
  c.push_back({"contact_fraction", "one of 25 vertices 2 mm outside: in contact; 6 mm outside or inside: not", [] {
                 const FrameMeasures near = one_vertex_at(-0.002);
                 EXPECT_DOUBLE_EQ(near.contact_fraction, 1.0 / 25);
                 EXPECT_EQ(near.penetrating_fraction, 0.0);
                 EXPECT_EQ(one_vertex_at(-0.006).contact_fraction, 0.0);
                 EXPECT_EQ(one_vertex_inside().contact_fraction, 0.0);
               }});
  // Held still in the air, out of contact, nothing pinned: every vertex is out of balance
  // by its weight. Dropped from rest (x = x0 + g t²/2): in balance, inertia = weight.
  const auto held = [] {
    return balance(far_apart(), [](int) { return far_apart().cloth->mesh.V; });
  };
  const auto dropped = [] {
    const Eigen::Vector3d g = physics::SimulationSettings{}.gravity;
    return balance(far_apart(), [g](int k) { return moved(far_apart().cloth->mesh.V, 0.5 * g * std::pow(k / 30.0, 2)); });
  };
  c.push_back({"oob_force_mean_n", "held still: the mean vertex weight; dropped: 0", [=] {
                 const std::vector<double> w = vertex_weights();
                 EXPECT_NEAR(held().oob_force_mean_n, std::accumulate(w.begin(), w.end(), 0.0) / w.size(), 1e-12);
                 EXPECT_LT(dropped().oob_force_mean_n, 1e-9);
               }});
  c.push_back({"oob_force_p95_n", "held still: the 95th percentile of the weights (an inner vertex's)", [=] {
                 EXPECT_NEAR(held().oob_force_p95_n, quantile(vertex_weights(), 0.95), 1e-12);
               }});
  c.push_back({"oob_force_p99_n", "held still: the 99th percentile of the weights", [=] {
                 EXPECT_NEAR(held().oob_force_p99_n, quantile(vertex_weights(), 0.99), 1e-12);
               }});
  c.push_back({"oob_force_max_n", "held still: the heaviest vertex's weight", [=] {
                 const std::vector<double> w = vertex_weights();
                 EXPECT_NEAR(held().oob_force_max_n, *std::max_element(w.begin(), w.end()), 1e-12);
               }});
  c.push_back({"oob_force_mean_rel", "held still: 1 × m g; dropped: 0", [=] {
                 EXPECT_NEAR(held().oob_force_mean_rel, 1, 1e-9);
                 EXPECT_LT(dropped().oob_force_mean_rel, 1e-8);
               }});
  c.push_back({"oob_force_max_rel", "held still: 1 × m g", [=] { EXPECT_NEAR(held().oob_force_max_rel, 1, 1e-9); }});
  c.push_back({"oob_force_outside_mean_n", "all outside: the mean; one vertex deep inside is left out", [=] {
                 const FrameMeasures h = held();
                 EXPECT_DOUBLE_EQ(h.oob_force_outside_mean_n, h.oob_force_mean_n);
                 const Character& inside = centre_inside();
                 const FrameMeasures m = balance(inside, [&](int) { return inside.cloth->mesh.V; });
                 EXPECT_GT(m.oob_force_max_n, 10 * h.oob_force_max_n) << "the collision penalty of the deep vertex";
                 EXPECT_LT(m.oob_force_outside_mean_n, m.oob_force_mean_n);
                 EXPECT_NEAR(m.oob_force_outside_mean_n, h.oob_force_mean_n, 0.2 * h.oob_force_mean_n);
               }});
  c.push_back({"oob_force_all_vertices_mean_n", "no anchors: the same as over the free vertices", [=] {
                 const FrameMeasures h = held();
                 EXPECT_DOUBLE_EQ(h.oob_force_all_vertices_mean_n, h.oob_force_mean_n);
               }});
  c.push_back({"oob_force_all_vertices_max_n", "no anchors: the same as over the free vertices", [=] {
                 const FrameMeasures h = held();
                 EXPECT_DOUBLE_EQ(h.oob_force_all_vertices_max_n, h.oob_force_max_n);
               }});
  c.push_back({"inertia_mean_n", "dropped: m a = m g, the mean weight; held still: 0", [=] {
                 const std::vector<double> w = vertex_weights();
                 EXPECT_NEAR(dropped().inertia_mean_n, std::accumulate(w.begin(), w.end(), 0.0) / w.size(), 1e-9);
                 EXPECT_EQ(held().inertia_mean_n, 0.0);
               }});
  c.push_back({"elastic_mean_n", "at its rest shape: 0; stretched by 10 %: more than its weight", [=] {
                 EXPECT_LT(held().elastic_mean_n, 1e-12);
                 const Vertices& x0 = far_apart().cloth->mesh.V;
                 const Eigen::RowVector3d c = x0.colwise().mean();
                 const Vertices stretched = ((x0.rowwise() - c) * 1.1).rowwise() + c;
                 const FrameMeasures m = balance(far_apart(), [&](int) { return stretched; });
                 EXPECT_GT(m.elastic_mean_n, held().oob_force_mean_n);
               }});
  c.push_back({"collision_mean_n", "out of contact: 0; one vertex 1 cm inside: its penalty over 25 vertices", [=] {
                 EXPECT_EQ(held().collision_mean_n, 0.0);
                 const Character& inside = centre_inside();
                 const FrameMeasures m = balance(inside, [&](int) { return inside.cloth->mesh.V; });
                 EXPECT_GT(m.collision_mean_n, 0.0);
                 EXPECT_NEAR(m.collision_mean_n * 25, m.oob_force_max_n, 0.1 * m.oob_force_max_n)
                     << "the one deep vertex's residual is its collision penalty";
               }});
  c.push_back({"friction_mean_n", "out of contact: 0; a vertex in the contact band sliding at 9 cm/s: > 0", [=] {
                 EXPECT_EQ(held().friction_mean_n, 0.0);
                 // The sheet's centre vertex 2 mm from a 2 cm ball (within the 4 mm band), sliding in x.
                 const Character near = sphere_and_sheet(Eigen::Vector3d(0, 1, 0.4 - 0.022), 0.02);
                 const FrameMeasures m =
                     balance(near, [&](int k) { return moved(near.cloth->mesh.V, {0.003 * k, 0, 0}); });
                 EXPECT_GT(m.collision_mean_n, 0.0);
                 EXPECT_GT(m.friction_mean_n, 0.0);
                 const FrameMeasures still = balance(near, [&](int) { return near.cloth->mesh.V; });
                 EXPECT_LT(still.friction_mean_n, 1e-12) << "no slip, no friction";
               }});
  c.push_back({"amv_iou", "the mean over views", [] {
                 FrameMeasures m;
                 measure_ious({1.0, 0.5, 0.2}, 1, m);
                 EXPECT_NEAR(m.amv_iou, 1.7 / 3, 1e-12);
               }});
  c.push_back({"rv_iou", "the mean over the views but the input one; undefined with one view", [] {
                 FrameMeasures m;
                 measure_ious({1.0, 0.5, 0.2}, 1, m);
                 EXPECT_NEAR(m.rv_iou, 0.6, 1e-12);
                 FrameMeasures one;
                 measure_ious({0.7}, 0, one);
                 EXPECT_TRUE(std::isnan(one.rv_iou));
               }});
  c.push_back({"sv_iou", "the input view's", [] {
                 FrameMeasures m;
                 measure_ious({1.0, 0.5, 0.2}, 1, m);
                 EXPECT_EQ(m.sv_iou, 0.5);
               }});
  return c;
}

TEST(FrameMetrics, EveryMetricHasAKnownAnswerCase) {
  std::set<std::string> covered;
  for (const MetricCase& c : metric_cases()) covered.insert(c.metric);
  std::string missing;
  for (const FrameMetric& m : frame_metrics())
    if (!covered.count(m.name)) missing += std::string(" ") + m.name;
  EXPECT_TRUE(missing.empty()) << "metrics of frame_metrics() without a case in metric_cases():" << missing;
}

TEST(FrameMetrics, EveryCaseNamesAMetricAndNamesAreUnique) {
  std::set<std::string> names;
  for (const FrameMetric& m : frame_metrics()) EXPECT_TRUE(names.insert(m.name).second) << m.name << " twice";
  for (const MetricCase& c : metric_cases()) EXPECT_TRUE(names.count(c.metric)) << c.metric << " is not a metric";
}

TEST(FrameMetrics, HeadingRotationKeepsTheTurnAboutTheVerticalAlone) {
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX()).toRotationMatrix();
  EXPECT_TRUE(heading_rotation(turn * tilt).isApprox(turn, 1e-12));
  EXPECT_TRUE(heading_rotation(tilt).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_NEAR(heading_error_deg(heading_rotation(turn * tilt), Eigen::Matrix3d::Identity()), 0.8 * 180 / std::numbers::pi,
              1e-9);
}

TEST(FrameMetrics, MeansOverFramesLeaveOutWhatWasNotMeasured) {
  FrameMetricMeans means;
  FrameMeasures a, b;
  a.mpjpe_mm = 10, b.mpjpe_mm = 30;
  a.sv_iou = 0.5;  // b: not measured
  means.add(a), means.add(b);
  EXPECT_DOUBLE_EQ(means.mean("mpjpe_mm"), 20);
  EXPECT_DOUBLE_EQ(means.mean("sv_iou"), 0.5);
  EXPECT_TRUE(std::isnan(means.mean("amv_iou")));
  EXPECT_THROW(means.mean("no_such_metric"), Error);
}

class FrameMetricCase : public ::testing::TestWithParam<size_t> {};

TEST_P(FrameMetricCase, GivesTheKnownAnswer) {
  const MetricCase c = metric_cases().at(GetParam());
  SCOPED_TRACE(c.metric + ": " + c.what);
  c.check();
}

INSTANTIATE_TEST_SUITE_P(AllMetrics, FrameMetricCase, ::testing::Range<size_t>(0, metric_cases().size()),
                         [](const ::testing::TestParamInfo<size_t>& info) { return metric_cases().at(info.param).metric; });

}  // namespace
