// The real ddc subject (../shared/data/ddc, CC BY-NC, never copied into the repository)
// dressed with a generated skirt through configs/characters/ddc_skirt.yaml: the skirt sits
// at the hips and clears the scanned body, the written folder references the ddc files
// and loads back to the same character, and the skinned skirt's anchors stay on the body
// through the captured walk.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <memory>
#include <set>
#include <sstream>

#include "capture/character/default_character.h"
#include "capture/character/skeletool_io.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using Eigen::Vector3d;

using weft::capture::testing::slurp;

namespace {

namespace fs = std::filesystem;

using weft::testing::kDdcDir;
const std::string kConfig = WEFT_SOURCE_DIR "/configs/characters/ddc_skirt.yaml";

#define REQUIRE_DDC() REQUIRE_DDC_DATA()

// Built once per test program (a few seconds).
const DefaultCharacterConfig& config() {
  static const DefaultCharacterConfig c = load_default_character_config(kConfig);
  return c;
}
const DefaultCharacter& dressed() {
  static const auto dc = std::make_unique<DefaultCharacter>(make_default_character(config()));
  return *dc;
}

}  // namespace

TEST(DressedDdc, SkirtSitsAtTheHipsAndClearsTheBody) {
  REQUIRE_DDC();
  const DefaultCharacterConfig& cfg = config();
  const DefaultCharacter& dc = dressed();
  const Character& ch = dc.character;
  ASSERT_TRUE(ch.has_cloth());
  EXPECT_DOUBLE_EQ(ch.metres_per_unit, 0.001);
  EXPECT_EQ(ch.body.mesh.num_vertices(), 5514);  // ddc's own body, unchanged
  EXPECT_EQ(ch.cloth->mesh.num_vertices(), cfg.segments * cfg.rings);
  ASSERT_EQ(ch.attachment.size(), cfg.segments);

  // The top ring at the hip joints' height (+ top_offset, metres → millimetres), around them.
  const Vector3d hips = bind_pose_hip_centre(ch, "ddc");
  const Vertices anchors = ch.attachment.targets(ch.body.mesh.V);
  Vector3d ring = Vector3d::Zero();
  for (int i = 0; i < ch.attachment.size(); ++i) {
    const Vector3d a = ch.cloth->mesh.V.row(ch.attachment.anchors(i)).transpose();
    EXPECT_NEAR(a.y(), hips.y() + cfg.top_offset / 0.001, 1e-6);
    ring += a / ch.attachment.size();
    // Each anchor is tied to a body point near it: the clearance plus the ring's smoothing.
    EXPECT_LT((a - anchors.row(i).transpose()).norm(), 60.0) << "anchor " << i;
  }
  EXPECT_LT(std::hypot(ring.x() - hips.x(), ring.z() - hips.z()), 60.0) << "mm";
  // The hem hangs `length` below the top ring.
  EXPECT_NEAR(ch.cloth->mesh.V.col(1).maxCoeff() - ch.cloth->mesh.V.col(1).minCoeff(), cfg.length / 0.001, 1e-6);

  // No garment vertex inside the scanned body, none closer than the clearance.
  const Eigen::VectorXd d = signed_distances(ch.body.mesh, ch.cloth->mesh.V);
  EXPECT_EQ((d.array() < 0).count(), 0);
  EXPECT_GE(d.minCoeff(), cfg.clearance / 0.001 * (1 - 1e-6)) << "mm";
  EXPECT_EQ(dc.garment_inside, 0);
  EXPECT_NEAR(dc.garment_min_distance, d.cwiseAbs().minCoeff(), 1e-9);
  std::printf("ddc skirt: top ring at %.1f mm (hips %.1f mm), closest to the body %.2f mm, %d inside\n",
              ch.cloth->mesh.V(0, 1), hips.y(), d.minCoeff(), static_cast<int>((d.array() < 0).count()));

  // Arms and hands by skinning weight: ddc's bind pose holds them out (a T-pose), all above
  // the skirt; their faces are inactive.
  const long arm = std::count(dc.arm_vertices.begin(), dc.arm_vertices.end(), char(1));
  EXPECT_GT(arm, 500);
  EXPECT_LT(arm, ch.body.mesh.num_vertices() / 3);
  for (int v = 0; v < ch.body.mesh.num_vertices(); ++v)
    if (dc.arm_vertices[v]) ASSERT_GT(ch.body.mesh.V(v, 1), ch.cloth->mesh.V(0, 1)) << "arm vertex " << v;
  EXPECT_EQ(ch.inactive_body_faces, faces_of_vertices(ch.body.mesh, dc.arm_vertices));
}

TEST(DressedDdc, WrittenFolderReferencesTheDdcFilesAndLoadsBack) {
  REQUIRE_DDC();
  const DefaultCharacter& dc = dressed();
  const Character& ch = dc.character;
  ScratchDir dir("dressed_ddc");
  const std::string yaml = write_default_character(dc, config(), dir.file("out"));

  // Only the generated files are written; the ddc files are referenced by absolute path.
  std::set<std::string> written;
  for (const auto& e : fs::directory_iterator(dir.file("out"))) written.insert(e.path().filename().string());
  EXPECT_EQ(written, (std::set<std::string>{"character.yaml", "skirt.obj", "anchors.txt", "inactive_faces.txt"}));
  const std::string text = slurp(yaml);
  const std::string ddc_dir = fs::canonical(kDdcDir).string();
  for (const char* file : {"ddc.skeleton", "ddc.motion", "ddc.obj", "ddc.skin", "segmentation.txt", "ddc_graph.obj"})
    EXPECT_NE(text.find(" " + ddc_dir + "/" + file + "\n"), std::string::npos) << file << " in\n" << text;

  const Character back = load_character(yaml);
  EXPECT_EQ(back.name, "ddc_skirt");
  EXPECT_DOUBLE_EQ(back.metres_per_unit, 0.001);
  EXPECT_EQ(back.rest_dofs, ch.rest_dofs);
  EXPECT_EQ(back.body.mesh.V, ch.body.mesh.V);
  EXPECT_EQ(back.body.weights.dense(), ch.body.weights.dense());
  EXPECT_EQ(back.body.labels, ch.body.labels);
  EXPECT_EQ(back.body.graph.rigidity, ch.body.graph.rigidity);
  EXPECT_EQ(back.inactive_body_faces, ch.inactive_body_faces);
  ASSERT_TRUE(back.has_cloth());
  EXPECT_LT((back.cloth->mesh.V - ch.cloth->mesh.V).cwiseAbs().maxCoeff(), 1e-9);  // OBJ text round trip
  EXPECT_EQ(back.cloth->mesh.F, ch.cloth->mesh.F);
  EXPECT_EQ(back.cloth->graph.num_nodes(), ch.cloth->graph.num_nodes());
  EXPECT_EQ(back.cloth->graph.rigidity, ch.cloth->graph.rigidity);
  EXPECT_LT((back.cloth->weights.dense() - ch.cloth->weights.dense()).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_EQ(back.attachment.anchors, ch.attachment.anchors);
  EXPECT_EQ(back.attachment.triangles, ch.attachment.triangles);
  for (int k = 0; k < kBody25Count; ++k) {
    EXPECT_EQ(back.body25[k].joints, ch.body25[k].joints) << kBody25Names[k];
    EXPECT_EQ(back.body25[k].markers, ch.body25[k].markers) << kBody25Names[k];
  }
}

TEST(DressedDdc, AnchorsStayOnTheBodyThroughTheWalk) {
  REQUIRE_DDC();
  ScratchDir dir("dressed_ddc_walk");
  const Character ch = load_character(write_default_character(dressed(), config(), dir.file("out")));
  const Motion rest = read_motion(kDdcDir + "/ddc.motion", ch.skeleton.num_dofs());
  const Motion walk = read_motion(kDdcDir + "/walk_0000_0299.motion", ch.skeleton.num_dofs());
  std::vector<Eigen::VectorXd> poses{rest.dofs.row(0).transpose()};
  for (int f = 0; f < walk.num_frames(); f += 10) poses.push_back(walk.dofs.row(f).transpose());

  // Skinned (not simulated), each anchor keeps its bind-pose distance to its attachment
  // target within a few millimetres.
  double worst = 0, hips_travel = 0;
  const Vector3d hips0 = bind_pose_hip_centre(ch, "ddc");
  for (const Eigen::VectorXd& dofs : poses) {
    const PosedCharacter p = pose_character(ch, dofs);
    const Vertices targets = ch.attachment.targets(p.body);
    for (int i = 0; i < ch.attachment.size(); ++i) {
      const double d = (p.cloth.row(ch.attachment.anchors(i)) - targets.row(i)).norm();
      worst = std::max(worst, std::abs(d - ch.attachment.rest_distance(i)));
    }
    hips_travel = std::max(hips_travel, (0.5 * (p.body25.row(9) + p.body25.row(12)).transpose() - hips0).norm());
  }
  std::printf("ddc skirt anchors over %zu poses: worst change of distance to the body %.2f mm (hips moved up to %.0f mm)\n",
              poses.size(), worst, hips_travel);
  EXPECT_GT(hips_travel, 100.0);  // the poses do move the body
  EXPECT_LT(worst, 5.0) << "mm";
}
