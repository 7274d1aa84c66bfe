// Known answers of the evaluation's per-frame measures (capture/evaluation/frame_measures.h)
// on constructed cases: a mesh exactly on its mask has IoU 1, a cloth vertex 5 mm inside a
// sphere body penetrates 0.5 cm, a free-falling cloth is in balance while a cloth held
// still in the air is out of balance by its weight; and the capture folder's reader
// refuses malformed capture.json files with an error naming the file and the key.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "capture/evaluation/capture_folder.h"
#include "capture/evaluation/evaluation_report.h"
#include "capture/evaluation/frame_measures.h"
#include "capture/render/renderer.h"
#include "capture/studio/studio_rig.h"
#include "tests/capture/sphere_and_sheet.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
namespace physics = weft::physics;
using weft::capture::testing::expect_error;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::sphere_and_sheet;

namespace {

Vertices translated(const Vertices& V, const Eigen::Vector3d& d) { return V.rowwise() + d.transpose(); }

}  // namespace

TEST(CaptureEvaluation, MeshExactlyOnItsMaskHasIoUOne) {
  const Character ch = sphere_and_sheet(Eigen::Vector3d(0, 1, 0), 0.3, 16, 32);
  const std::vector<Camera> cams = {
      look_at_camera("front", Eigen::Vector3d(0, 1.2, 3), Eigen::Vector3d(0, 1, 0), 160, 120, 40),
      look_at_camera("side", Eigen::Vector3d(3, 1.1, 0.5), Eigen::Vector3d(0, 1, 0), 120, 160, 45)};
  const Vertices& body = ch.body.mesh.V;
  const Vertices& cloth = ch.cloth->mesh.V;
  std::vector<cv::Mat> masks;
  for (const Camera& c : cams) {
    std::vector<RenderMesh> meshes(2);
    meshes[0].mesh = &ch.body.mesh;
    meshes[1].mesh = &ch.cloth->mesh;
    masks.push_back(render(c, meshes).mask);
    ASSERT_GT(cv::countNonZero(masks.back()), 500);
  }
  for (double iou : silhouette_ious(ch, body, &cloth, cams, masks)) EXPECT_DOUBLE_EQ(iou, 1.0);
  // The same meshes moved by 5 cm overlap the masks only partly.
  const Vertices body_moved = translated(body, {0.05, 0, 0}), cloth_moved = translated(cloth, {0.05, 0, 0});
  for (double iou : silhouette_ious(ch, body_moved, &cloth_moved, cams, masks)) {
    EXPECT_GT(iou, 0.5);
    EXPECT_LT(iou, 0.97);
  }
  // Against empty masks: nothing in common.
  std::vector<cv::Mat> empty;
  for (const Camera& c : cams) empty.push_back(cv::Mat::zeros(c.height, c.width, CV_8UC1));
  for (double iou : silhouette_ious(ch, body, &cloth, cams, empty)) EXPECT_EQ(iou, 0.0);
}

TEST(CaptureEvaluation, ClothVertexFiveMillimetresInsideASpherePenetratesHalfACentimetre) {
  const Eigen::Vector3d centre(0, 1, 0);
  const Character ch = sphere_and_sheet(centre, 0.3, 16, 32);
  // A face near the equator: its centroid moved 5 mm inward along its outward normal.
  const TriangleMesh& s = ch.body.mesh;
  const Vertices normals = face_normals(s.V, s.F);
  int face = 0;
  double best = 1;
  for (int f = 0; f < s.num_faces(); ++f) {
    const double y = (s.V.row(s.F(f, 0)) + s.V.row(s.F(f, 1)) + s.V.row(s.F(f, 2))).y() / 3 - centre.y();
    if (std::abs(y) < best) best = std::abs(y), face = f;
  }
  const Eigen::Vector3d c = (s.V.row(s.F(face, 0)) + s.V.row(s.F(face, 1)) + s.V.row(s.F(face, 2))).transpose() / 3;
  Eigen::Vector3d n = normals.row(face).transpose();
  ASSERT_GT(n.dot(c - centre), 0) << "uv_sphere faces point outward";
  // The garment: one vertex 5 mm inside, the rest 1 cm or more outside the sphere.
  Vertices cloth = ch.cloth->mesh.V;
  for (int i = 0; i < cloth.rows(); ++i) {
    const Eigen::Vector3d d = (cloth.row(i).transpose() - centre).normalized();
    cloth.row(i) = (centre + d * (0.32 + 0.01 * i)).transpose();
  }
  cloth.row(7) = (c - 0.005 * n).transpose();
  const Penetration p = cloth_penetration(ch, ch.body.mesh.V, cloth);
  EXPECT_EQ(p.vertices_inside, 1);
  EXPECT_NEAR(p.depth_sum / p.vertices_inside * 100, 0.5, 1e-9);  // cm
  EXPECT_NEAR(p.max_depth * 1e3, 5.0, 1e-9);                      // mm
  // In a character measured in millimetres the same geometry gives the same depths (metres out).
  Character mm = ch;
  mm.metres_per_unit = 1e-3;
  const Penetration q = cloth_penetration(mm, ch.body.mesh.V * 1e3, cloth * 1e3);
  EXPECT_EQ(q.vertices_inside, 1);
  EXPECT_NEAR(q.max_depth * 1e3, 5.0, 1e-9);
}

TEST(CaptureEvaluation, FreeFallingClothIsInBalanceAndClothHeldStillIsOutByItsWeight) {
  // The body far from the garment: no contact; no anchors: no pins; only gravity acts.
  const Character ch = sphere_and_sheet(Eigen::Vector3d(0, -100, 0), 0.3, 16, 32);
  const SynthSimulationConfig simulation;
  const double fps = 30, h = 1 / fps;
  const Eigen::Vector3d g = physics::SimulationSettings{}.gravity;
  const Vertices& x0 = ch.cloth->mesh.V;  // the rest shape: no internal force
  const Vertices& body = ch.body.mesh.V;
  const auto fallen = [&](int k) { return translated(x0, 0.5 * g * (k * h) * (k * h)); };
  const physics::FrameMetrics falling =
      cloth_out_of_balance(ch, simulation, fps, body, body, fallen(0), fallen(1), fallen(2)).free;
  EXPECT_LT(falling.oob_force_max_rel, 1e-8);
  EXPECT_LT(falling.oob_force_max, 1e-9);
  // Starting from rest 1 s into the fall changes nothing: the acceleration is still g.
  const physics::FrameMetrics later =
      cloth_out_of_balance(ch, simulation, fps, body, body, fallen(30), fallen(31), fallen(32)).free;
  EXPECT_LT(later.oob_force_max_rel, 1e-6);

  const ClothBalance balance = cloth_out_of_balance(ch, simulation, fps, body, body, x0, x0, x0);
  const physics::FrameMetrics& held = balance.free;
  // Nothing is pinned: every vertex is free.
  EXPECT_EQ(balance.all.oob_force_mean, held.oob_force_mean);
  EXPECT_NEAR(held.oob_force_mean_rel, 1.0, 1e-9);
  EXPECT_NEAR(held.oob_force_max_rel, 1.0, 1e-9);
  // In newtons: the heaviest vertex's weight (lumped mass of its share of 0.04 m² at the density).
  const double total_weight = simulation.material.density * 0.2 * 0.2 * g.norm();
  EXPECT_GT(held.oob_force_max, total_weight / 25);
  EXPECT_LT(held.oob_force_max, total_weight / 4);
  EXPECT_GT(held.oob_force_mean, 0.0);
}

TEST(CaptureEvaluation, VertexDistancesQuantilesAndJointErrors) {
  Vertices a = Vertices::Zero(4, 3), b = Vertices::Zero(4, 3);
  b.col(0) << 1, 2, 3, 4;  // metres
  const std::vector<double> d = vertex_distances_mm(a, b, 1.0);
  EXPECT_EQ(d, (std::vector<double>{1000, 2000, 3000, 4000}));
  EXPECT_DOUBLE_EQ(quantile(d, 0.5), 2500);
  EXPECT_DOUBLE_EQ(quantile(d, 0.95), 3850);  // NumPy: np.percentile([1,2,3,4], 95) = 3.85
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
  // Joints: unmapped rows (NaN) are left out.
  Vertices p = Vertices::Zero(3, 3), q = Vertices::Zero(3, 3);
  q(0, 1) = 10, q(1, 2) = 20;  // millimetres
  p.row(2).setConstant(std::nan(""));
  EXPECT_DOUBLE_EQ(mean_joint_error_mm(p, q, 1e-3), 15.0);
  p.setConstant(std::nan(""));
  EXPECT_TRUE(std::isnan(mean_joint_error_mm(p, q, 1e-3)));
}

TEST(CaptureEvaluation, LinePlotDrawsEverySeriesWithGaps) {
  const std::string svg = svg_line_plot("error", "mm", {0, 1, 2, 5, 6},
                                        {{"a", {1, 2, NAN, 3, 4}, "red"}, {"b", {NAN, NAN, 1, NAN, NAN}, "blue"}});
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  // a: the run 0–1, then 5–6 after the gap in values and ids; b: one isolated point.
  size_t polylines = 0;
  for (size_t at = svg.find("<polyline"); at != std::string::npos; at = svg.find("<polyline", at + 1)) ++polylines;
  EXPECT_EQ(polylines, 2u);
  EXPECT_NE(svg.find("<circle"), std::string::npos);
  EXPECT_NE(svg.find(">error<"), std::string::npos);
  // A series measured on every other frame is one line.
  const std::string sampled =
      svg_line_plot("iou", "", {0, 1, 2, 3, 4}, {{"s", {0.5, NAN, 0.6, NAN, 0.7}, "red", true}});
  EXPECT_EQ(sampled.find("<circle"), std::string::npos);
  EXPECT_NE(sampled.find("<polyline"), std::string::npos);
}

namespace {

const char* kValidCapture = R"({"format": "weft-capture/1", "model": "/m", "character": "/c/character.yaml",
  "metres_per_unit": 1.0, "synth_config": "", "input": "/in", "camera": "/cam.yaml", "view": "cam03", "fps": 30,
  "collisions_resolved": false,
  "frames": [{"id": 5, "source": "0005.png", "pivot": [0.1, 0.9, 0.0], "translation_from": "keypoints"},
             {"id": 6, "source": "0006.png", "pivot": [0.1, 0.9, 0.1], "translation_from": "keypoints"}],
  "timing": {"total_s": 1.0}})";

std::string with(std::string text, const std::string& from, const std::string& to) {
  const size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return text.replace(at, from.size(), to);
}

}  // namespace

TEST(CaptureEvaluation, CaptureFolderReadsTheFormat) {
  ScratchDir dir("capture_folder");
  dir.write("capture.json", kValidCapture);
  const CaptureFolder c = read_capture_folder(dir.file(""));
  EXPECT_EQ(c.view, "cam03");
  EXPECT_EQ(c.character, "/c/character.yaml");
  ASSERT_EQ(c.frames.size(), 2u);
  EXPECT_EQ(c.frames[1].id, 6);
  EXPECT_EQ(c.frames[1].pivot, Eigen::Vector3d(0.1, 0.9, 0.1));
  EXPECT_FALSE(c.collisions_resolved);
}

TEST(CaptureEvaluation, MalformedCaptureFoldersAreErrorsNamingTheFileAndKey) {
  ScratchDir dir("capture_folder_bad");
  expect_error([&] { read_capture_folder(dir.file("nowhere")); }, {"nowhere", "no such capture folder"});
  expect_error([&] { read_capture_folder(dir.file("")); }, {"capture.json", "missing"});
  const auto bad = [&](const std::string& text, std::initializer_list<std::string> parts) {
    dir.write("capture.json", text);
    expect_error([&] { read_capture_folder(dir.file("")); }, parts);
  };
  bad("{\"format\": ", {"capture.json", "invalid JSON"});
  bad(with(kValidCapture, "weft-capture/1", "weft-capture/2"),
      {"capture.json", "weft-capture/2", "expected 'weft-capture/1'"});
  bad(with(kValidCapture, "\"view\": \"cam03\",", ""), {"capture.json", "missing key 'view'"});
  bad(with(kValidCapture, "\"fps\": 30", "\"fps\": \"30\""), {"capture.json", "'fps'", "expected a number"});
  bad(with(kValidCapture, "\"id\": 6", "\"id\": 5"), {"capture.json", "frames[1]", "id 5 appears twice"});
  bad(with(kValidCapture, "[0.1, 0.9, 0.0]", "[0.1, 0.9]"), {"capture.json", "frames[0]", "pivot has 2 values"});
  bad(with(kValidCapture, "\"id\": 5, ", ""), {"capture.json", "frames[0]", "missing key 'id'"});
  bad(with(kValidCapture, "\"frames\": [", "\"frames\": 3, \"x\": ["),
      {"capture.json", "'frames'", "expected an array"});
}
