#include <gtest/gtest.h>

#include "capture/character/character.h"
#include "geometry/mesh_io.h"
#include "capture/motion/pose_sequence.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::ScratchDir;
using weft::capture::testing::expect_error;
using weft::capture::testing::small_skeleton_text;

namespace {

// A thin vertical strip along the small skeleton's leg (y from 1 down to -4).
TriangleMesh strip(double x0, int rows) {
  TriangleMesh m;
  m.V.resize(2 * rows, 3);
  for (int i = 0; i < rows; ++i) {
    const double y = 1.0 - 5.0 * i / (rows - 1);
    m.V.row(2 * i) << x0, y, 0.1;
    m.V.row(2 * i + 1) << x0 + 0.2, y, -0.1;
  }
  m.F.resize(2 * (rows - 1), 3);
  for (int i = 0; i + 1 < rows; ++i) {
    m.F.row(2 * i) << 2 * i, 2 * i + 2, 2 * i + 1;
    m.F.row(2 * i + 1) << 2 * i + 1, 2 * i + 2, 2 * i + 3;
  }
  return m;
}

struct CharacterFiles {
  ScratchDir dir{"character"};
  std::string yaml;
  explicit CharacterFiles(const std::string& extra = "") {
    dir.write("s.skeleton", small_skeleton_text());
    write_obj(dir.file("body.obj"), strip(-0.1, 11));
    write_obj(dir.file("cloth.obj"), strip(-0.15, 6));
    dir.write("anchors.txt", "0\n1\n");
    dir.write("labels.txt", std::string(11, '0').replace(0, 0, "") + "");
    std::string labels;
    for (int i = 0; i < 22; ++i) labels += (i < 11 ? "0\n" : "18\n");
    dir.write("labels.txt", labels);
    dir.write("rest.motion", "Skeletool Motion File V1.0\n0 0 0 0\n");
    yaml = dir.write("c.yaml",
                     "name: strip\nmetres_per_unit: 0.001\nskeleton: s.skeleton\nrest_pose: rest.motion\n"
                     "body:\n  mesh: body.obj\n  labels: labels.txt\n  graph_nodes: 6\n"
                     "  rigidity: {default: 1.0, labels: {0: 0.25}}\n  inactive_labels: [18]\n"
                     "cloth:\n  mesh: cloth.obj\n  graph_nodes: 4\n  anchors: anchors.txt\n"
                     "body25:\n  RKnee: knee_rz\n  RBigToe: toe\n  MidHip: [root_tx, hip_rz]\n" + extra);
  }
};

TEST(Character, LoadsYamlWithGeneratedWeightsGraphsAndAttachment) {
  CharacterFiles files;
  const Character ch = load_character(files.yaml);
  EXPECT_EQ(ch.name, "strip");
  EXPECT_DOUBLE_EQ(ch.metres_per_unit, 0.001);
  EXPECT_EQ(ch.skeleton.num_joints(), 4);
  ASSERT_TRUE(ch.has_cloth());
  EXPECT_EQ(ch.body.weights.num_vertices(), 22);  // bone-distance weights
  EXPECT_EQ(ch.cloth->weights.num_vertices(), 12);  // transferred from the body
  EXPECT_EQ(ch.body.graph.num_nodes(), 6);
  EXPECT_EQ(ch.cloth->graph.num_nodes(), 4);
  EXPECT_EQ(ch.attachment.size(), 2);
  // Vertices 0..10 (the top) are label 0 with rigidity 0.25, the rest label 18 (default 1).
  const Eigen::VectorXd& r = ch.body.graph.rigidity;
  EXPECT_GE(r.minCoeff(), 0.25 - 1e-12);
  EXPECT_LE(r.maxCoeff(), 1.0 + 1e-12);
  for (int k = 0; k < ch.body.graph.num_nodes(); ++k) {
    if (ch.body.graph.nodes(k, 1) > 0.6) EXPECT_NEAR(r(k), 0.25, 1e-12) << k;
    if (ch.body.graph.nodes(k, 1) < -1.6) EXPECT_NEAR(r(k), 1.0, 1e-12) << k;
  }
  // Inactive: the faces whose three vertices all carry label 18.
  std::vector<int> expected;
  for (int f = 0; f < ch.body.mesh.num_faces(); ++f)
    if (ch.body.mesh.F.row(f).minCoeff() >= 11) expected.push_back(f);
  EXPECT_FALSE(expected.empty());
  EXPECT_EQ(ch.inactive_body_faces, expected);
  EXPECT_EQ(ch.body25[10].joints, std::vector<int>{2});
  EXPECT_EQ(ch.body25[22].markers, std::vector<int>{0});
  EXPECT_TRUE(ch.body25[0].empty());
  // Posing at the bind pose reproduces the template; moving the root translates all.
  const PosedCharacter rest = pose_character(ch, ch.rest_dofs);
  EXPECT_NEAR((rest.body - ch.body.mesh.V).cwiseAbs().maxCoeff(), 0, 1e-12);
  EXPECT_NEAR((rest.cloth - ch.cloth->mesh.V).cwiseAbs().maxCoeff(), 0, 1e-12);
  EXPECT_TRUE(std::isnan(rest.body25(0, 0)));
  EXPECT_TRUE(rest.body25.row(8).isApprox(Eigen::RowVector3d(0, 0.5, 0)));  // mean of two joints
  const PosedCharacter moved = pose_character(ch, Eigen::Vector3d(0.001, 0, 0));
  EXPECT_NEAR(((moved.body - ch.body.mesh.V).rowwise() - Eigen::RowVector3d(1, 0, 0)).cwiseAbs().maxCoeff(), 0, 1e-12);
}

TEST(Character, PoseSequenceWritesMeshesAndOverlays) {
  CharacterFiles files;
  const Character ch = load_character(files.yaml);
  Motion motion;
  motion.frame_ids = {0, 1, 2};
  motion.dofs.resize(3, 3);
  motion.dofs << 0, 0, 0, 0, 0.3, 0, 0, 0.6, 0.2;
  Camera cam;
  cam.name = "front";
  cam.K << 50, 0, 32, 0, 50, 24, 0, 0, 1;
  cam.t << 0, 1.5, 12;
  cam.width = 64;
  cam.height = 48;
  PoseSequenceOptions o;
  o.out_dir = files.dir.file("out");
  o.first_frame = 1;
  o.cameras = {cam};
  int calls = 0;
  o.progress = [&](int done, int total) { ++calls; EXPECT_EQ(total, 2); };
  const PoseSequenceSummary s = pose_sequence(ch, motion, o);
  EXPECT_EQ(s.frames, 2);
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(s.meshes_written, 4);
  EXPECT_EQ(s.images_written, 2);
  const TriangleMesh b2 = read_obj(files.dir.file("out/body_0002.obj"));
  EXPECT_EQ(b2.F, ch.body.mesh.F);
  EXPECT_FALSE(b2.V.isApprox(ch.body.mesh.V));
  EXPECT_TRUE(std::filesystem::exists(files.dir.file("out/cloth_0001.obj")));
  EXPECT_FALSE(std::filesystem::exists(files.dir.file("out/body_0000.obj")));
  const cv::Mat overlay = render_overlay(cam, {&ch.body.mesh}, {&ch.body.mesh.V}, {cv::Scalar(0, 0, 255)});
  EXPECT_EQ(overlay.cols, 64);
  EXPECT_GT(cv::countNonZero(overlay.reshape(1) != 128), 0);  // something was drawn
  EXPECT_TRUE(std::filesystem::exists(files.dir.file("out/overlay_front_0001.png")));
  o.first_frame = 5;
  expect_error([&] { pose_sequence(ch, motion, o); }, {"frames 5:3"});
}

TEST(Character, BadYamlNamesFileAndKey) {
  {
    CharacterFiles files("colour: red\n");
    expect_error([&] { load_character(files.yaml); }, {"c.yaml:", "colour", "unknown key"});
  }
  {
    CharacterFiles files;
    files.dir.write("c2.yaml", "skeleton: s.skeleton\nbody:\n  mesh: body.obj\n  skinn: x.skin\n");
    expect_error([&] { load_character(files.dir.file("c2.yaml")); }, {"c2.yaml:4:", "body.skinn", "unknown key"});
    files.dir.write("c3.yaml", "skeleton: s.skeleton\nbody:\n  mesh: nothere.obj\n");
    expect_error([&] { load_character(files.dir.file("c3.yaml")); }, {"c3.yaml:3:", "body.mesh", "file not found"});
    files.dir.write("c4.yaml", "skeleton: s.skeleton\nbody:\n  mesh: body.obj\nbody25:\n  Knee: knee_rz\n");
    expect_error([&] { load_character(files.dir.file("c4.yaml")); }, {"c4.yaml:5:", "not a BODY_25 keypoint"});
    files.dir.write("c5.yaml", "skeleton: s.skeleton\nbody:\n  mesh: body.obj\nbody25:\n  RKnee: kneecap\n");
    expect_error([&] { load_character(files.dir.file("c5.yaml")); }, {"c5.yaml:5:", "'kneecap'"});
    files.dir.write("c6.yaml", "skeleton: s.skeleton\nbody: [1, 2\n");
    expect_error([&] { load_character(files.dir.file("c6.yaml")); }, {"c6.yaml:"});
    files.dir.write("c7.yaml", "skeleton: s.skeleton\nbody:\n  mesh: body.obj\n  labels: anchors.txt\n");
    expect_error([&] { load_character(files.dir.file("c7.yaml")); }, {"c7.yaml:4:", "2 labels", "22"});
    files.dir.write("c8.yaml", "skeleton: s.skeleton\nbody:\n  mesh: body.obj\n  graph_nodes: many\n");
    expect_error([&] { load_character(files.dir.file("c8.yaml")); }, {"c8.yaml:4:", "graph_nodes", "integer"});
    expect_error([&] { load_character(files.dir.file("s.skeleton")); }, {"s.skeleton", "unknown character format"});
  }
}

}  // namespace
