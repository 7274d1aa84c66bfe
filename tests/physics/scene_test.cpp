// Scene files: strict parsing with errors naming key and file, grid ids, a small run
// writing OBJ frames and metrics.json.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "geometry/mesh_io.h"
#include "graph/error.h"
#include "physics/scene.h"

namespace weft::physics {
namespace {

namespace fs = std::filesystem;

class SceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("weft_scene_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p.string();
  }
  // Expects load_scene to fail with a message holding every fragment.
  void expect_error(const std::string& yaml, std::vector<std::string> fragments) {
    const std::string path = write("scene.yaml", yaml);
    try {
      load_scene(path);
      ADD_FAILURE() << "no error for:\n" << yaml;
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      for (const auto& f : fragments) EXPECT_NE(msg.find(f), std::string::npos) << msg;
    }
  }
  fs::path dir_;
};

const char* kGrid = R"(
time_step: 0.02
frames: 3
cloth:
  grid: {size: [0.5, 0.4], resolution: [5, 4], origin: [0, 1, 0], plane: xz}
  material: {density: 0.2, youngs_modulus: 1.0e5, poisson_ratio: 0.3, bending_stiffness: 1.0e-5, thickness: 0.001}
  pins: [0, 4]
)";

TEST_F(SceneTest, GridVertexIdsAreRowTimesNxPlusColumn) {
  const Scene s = load_scene(write("scene.yaml", kGrid));
  ASSERT_EQ(s.cloth.num_vertices(), 20);
  const auto v = [&](int i) { return s.cloth.rest_vertex(i); };
  EXPECT_TRUE(v(0).isApprox(Vec3(0, 1, 0)));
  EXPECT_TRUE(v(4).isApprox(Vec3(0.5, 1, 0)));     // nx − 1: end of the first row
  EXPECT_TRUE(v(15).isApprox(Vec3(0, 1, 0.4)));    // (ny − 1)·nx
  EXPECT_TRUE(v(19).isApprox(Vec3(0.5, 1, 0.4)));  // nx·ny − 1
  EXPECT_EQ(s.pins, (std::vector<int>{0, 4}));
}

TEST_F(SceneTest, ErrorsNameTheKeyAndTheFile) {
  expect_error(std::string(kGrid) + "colision: {thickness: 0.01}\n", {"colision", "unknown key"});
  expect_error(R"(
frames: lots
cloth: {grid: {size: [1, 1], resolution: [4, 4]}}
)", {"frames", "integer"});
  expect_error(R"(
cloth:
  grid: {size: [1, 1], resolution: [4, 4]}
  material: {poisson_ratio: 0.5}
)", {"cloth.material.poisson_ratio"});
  expect_error(R"(
cloth:
  grid: {size: [1, 1], resolution: [4, 4]}
  material: {density: -0.1}
)", {"cloth.material.density"});
  expect_error(R"(
cloth:
  grid: {size: [1, 1], resolution: [4, 4]}
  material: {membrane: neo_hookean}
)", {"cloth.material.membrane", "neo_hookean", "stvk or tension_field"});
  expect_error(R"(
cloth:
  grid: {size: [1, 1], resolution: [4, 4]}
  material: {compression_ratio: 2}
)", {"cloth.material.compression_ratio", "[0, 1]"});
  write("three.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
  expect_error(R"(
cloth:
  grid: {size: [1, 1], resolution: [4, 4]}
  initial: {positions: three.obj}
)", {"cloth.initial.positions", "three.obj", "3 vertices", "16"});
  expect_error(R"(
cloth:
  grid: {size: [1, 1], resolution: [4, 4]}
  initial: {previous: three.obj}
)", {"cloth.initial.positions", "missing key"});
  expect_error(R"(
cloth: {mesh: missing.obj}
)", {"cloth.mesh", "missing.obj"});
  expect_error(R"(
cloth: {grid: {size: [1, 1], resolution: [4, 4]}}
obstacles:
  - mesh: body.obj
)", {"obstacles[0].mesh", "body.obj"});
  expect_error(R"(
cloth: {grid: {size: [1, 1], resolution: [4, 4]}, pins: [16]}
)", {"cloth.pins", "16"});
  expect_error(R"(
cloth: {grid: {size: [1, 1], resolution: [4, 4]}}
obstacles:
  - sphere: {center: [0, 0], radius: 0.3}
)", {"obstacles[0].sphere.center"});
  expect_error(R"(
cloth: {grid: {size: [1, 1], resolution: [4, 4]}}
obstacles:
  - sphere: {center: [0, 0, 0], radius: 0.3}
    friction: -0.1
)", {"'obstacles[0].friction' must be >= 0, got -0.1"});
  expect_error(R"(
cloth: {grid: {size: [1, 1], resolution: [4, 4]}}
obstacles:
  - sphere: {center: [0, 0, 0], radius: 0.3}
  - sphere: {center: [0, 1, 0], radius: 0.3}
    friction: rough
)", {"obstacles[1].friction", "must be a number", "rough"});
  expect_error(std::string(kGrid) + "collision: {friction_velocity: 0}\n",
               {"collision.friction_velocity", "> 0"});
}

TEST_F(SceneTest, ObstacleFrictionIsReadPerObstacle) {
  const Scene s = load_scene(write("scene.yaml", std::string(kGrid) + R"(
obstacles:
  - sphere: {center: [0, 0, 0], radius: 0.3}
    friction: 0.7
  - sphere: {center: [0, 2, 0], radius: 0.3}
  - sphere: {center: [0, 4, 0], radius: 0.3}
    friction: 0
collision: {friction_velocity: 0.002}
)"));
  ASSERT_EQ(s.obstacles.size(), 3u);
  EXPECT_EQ(s.obstacles[0].sphere.friction, 0.7);
  EXPECT_EQ(s.obstacles[1].sphere.friction, 0.3);  // the default
  EXPECT_EQ(s.obstacles[2].sphere.friction, 0.0);  // off
  EXPECT_EQ(s.settings.friction_velocity, 0.002);
}

TEST_F(SceneTest, RunWritesFramesAndMetrics) {
  // A floor triangle facing up (+y), far below the cloth.
  write("floor.obj", "v -5 -1 -5\nv 5 -1 -5\nv -5 -1 5\nf 1 3 2\n");
  const std::string yaml = std::string(kGrid) + R"(
obstacles:
  - sphere: {center: [0.25, 0.7, 0.2], radius: 0.2}
  - mesh: floor.obj
collision: {thickness: 0.01, stiffness: 1.0e4}
solver: {max_iterations: 30, tolerance: 1.0e-4}
)";
  const Scene scene = load_scene(write("scene.yaml", yaml));
  const fs::path out = dir_ / "out";
  const SceneRun run = run_scene(scene, out.string());
  for (int f = 0; f <= 3; ++f) {
    char name[32];
    std::snprintf(name, sizeof(name), "cloth_%04d.obj", f);
    EXPECT_TRUE(fs::exists(out / name)) << name;
  }
  EXPECT_FALSE(fs::exists(out / "metrics.json.tmp"));
  std::ifstream in(out / "metrics.json");
  const nlohmann::json doc = nlohmann::json::parse(in);
  ASSERT_EQ(doc["frames"].size(), 3u);
  for (const char* key : {"frame", "status", "newton_iterations", "gradient_norm", "energy",
                          "min_signed_distance", "penetration_mean", "penetration_max",
                          "oob_force_mean", "oob_force_max", "step_ms"})
    EXPECT_TRUE(doc["frames"][0].contains(key)) << key;
  EXPECT_EQ(doc["frames"][2]["frame"], 3);
  EXPECT_EQ(doc["frames"][0]["status"], "converged");
  EXPECT_TRUE(doc.contains("summary"));
  // The written frame is the simulated state: pinned corner stays, the rest falls.
  const TriangleMesh last = read_obj((out / "cloth_0003.obj").string());
  EXPECT_NEAR(last.V(0, 1), 1.0, 1e-3);
  EXPECT_LT(last.V(19, 1), 1.0 - 1e-3);
}

TEST_F(SceneTest, RunStartsFromTheGivenStateAndVelocity) {
  // Without gravity or obstacles, a cloth given at its rest shape moved up by 1 cm, and
  // 1 cm lower one frame before, keeps rising at 0.5 m/s: it starts from that state and
  // velocity, not from rest.
  std::string rest_up, rest;
  const Scene plain = load_scene(write("plain.yaml", R"(
time_step: 0.02
frames: 2
gravity: [0, 0, 0]
cloth: {grid: {size: [0.5, 0.4], resolution: [5, 4], origin: [0, 1, 0], plane: xz}}
)"));
  for (int i = 0; i < plain.cloth.num_vertices(); ++i) {
    const Vec3 v = plain.cloth.rest_vertex(i);
    rest += "v " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " + std::to_string(v.z()) + "\n";
    rest_up += "v " + std::to_string(v.x()) + " " + std::to_string(v.y() + 0.01) + " " + std::to_string(v.z()) + "\n";
  }
  write("up.obj", rest_up);
  write("at_rest.obj", rest);
  const Scene scene = load_scene(write("scene.yaml", R"(
time_step: 0.02
frames: 2
gravity: [0, 0, 0]
cloth:
  grid: {size: [0.5, 0.4], resolution: [5, 4], origin: [0, 1, 0], plane: xz}
  initial: {positions: up.obj, previous: at_rest.obj}
)"));
  const fs::path out = dir_ / "out";
  run_scene(scene, out.string());
  EXPECT_NEAR(read_obj((out / "cloth_0000.obj").string()).V(7, 1), 1.01, 1e-6);
  EXPECT_NEAR(read_obj((out / "cloth_0002.obj").string()).V(7, 1), 1.03, 1e-6);
}

TEST(SequencePath, FormatsTheFrameNumber) {
  EXPECT_EQ(sequence_path("dir/body_%04d.obj", 7), "dir/body_0007.obj");
  EXPECT_EQ(sequence_path("b%d.obj", 12), "b12.obj");
  EXPECT_THROW(sequence_path("body.obj", 1), Error);
  EXPECT_THROW(sequence_path("%s_%d.obj", 1), Error);
}

}  // namespace
}  // namespace weft::physics
