// The garment's simulation settings travel with the data: the section `weft synth` writes
// into dataset.yaml (and `weft train` into model.yaml) reads back to the same settings, and
// a dataset without it is one error naming dataset.yaml, the key and the way out.
#include <gtest/gtest.h>

#include "capture/garment/garment_config.h"
#include "files/strict_yaml.h"
#include "test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::ScratchDir;

namespace {

// Every field away from its default, with values whose decimal forms are not short.
SynthSimulationConfig unusual_settings() {
  SynthSimulationConfig s;
  s.enabled = false;
  s.substeps = 3;
  s.settle_frames = 7;
  s.material.density = 0.1 + 0.2;  // 0.30000000000000004
  s.material.youngs_modulus = 1.0 / 3.0 * 1e5;
  s.material.poisson_ratio = 0.499;
  s.material.bending_stiffness = 2.5e-7;
  s.material.thickness = 7e-4;
  s.material.membrane = physics::MembraneModel::stvk;
  s.material.compression_ratio = 0.25;
  s.material.min_area_ratio = 0.125;
  s.collision_thickness = 0.0035;
  s.collision_stiffness = 12345.678;
  s.pin_stiffness = 2.0e4;
  s.friction = 0.45;
  s.max_iterations = 77;
  s.tolerance = 3e-4;
  s.max_penetration = 0.02;
  s.collision_second_sheet_deg = 30.5;
  s.collision_smooth_creases = !SynthSimulationConfig{}.collision_smooth_creases;
  s.per_vertex_step_limits = !SynthSimulationConfig{}.per_vertex_step_limits;
  s.max_body_motion = 0.0125;
  s.max_step_halvings = 2;
  return s;
}

SynthSimulationConfig read_back(const std::string& text) {
  StrictYaml y;
  y.file = "written.yaml";
  const YAML::Node root = y.parse(text);
  SynthSimulationConfig s;
  parse_simulation_config(y, root["simulation"], s);
  return s;
}

}  // namespace

TEST(GarmentConfig, TheWrittenSectionReadsBackToTheSameSettings) {
  const SynthSimulationConfig s = unusual_settings();
  EXPECT_EQ(read_back(simulation_config_yaml(s)), s);
  EXPECT_EQ(read_back(simulation_config_yaml(SynthSimulationConfig{})), SynthSimulationConfig{});
}

TEST(GarmentConfig, ADatasetCarriesItsSimulationOrSaysHowToGetIt) {
  ScratchDir dir("garment_config");
  dir.write("dataset.yaml", "format: weft-synth/1\nframes: 3\n" + simulation_config_yaml(unusual_settings()));
  const std::string folder = dir.file("");
  ASSERT_TRUE(find_dataset_simulation(folder).has_value());
  EXPECT_EQ(read_dataset_simulation(folder), unusual_settings());

  dir.write("dataset.yaml", "format: weft-synth/1\nframes: 3\n");
  EXPECT_FALSE(find_dataset_simulation(folder).has_value());
  expect_error([&] { read_dataset_simulation(folder); }, {"dataset.yaml", "simulation", "weft synth"});

  dir.write("dataset.yaml", "format: weft-synth/1\nsimulation:\n  material: {poisson_ratio: 0.5}\n");
  expect_error([&] { read_dataset_simulation(folder); },
               {"dataset.yaml:3", "simulation.material.poisson_ratio", "[0, 0.5)"});
}

// The settings that decide whether a frame fails: a value out of range or of the wrong
// type is one error naming the file, the line and the key, and what was expected.
TEST(GarmentConfig, BadFailedFrameSettingsNameTheLineAndTheKey) {
  const auto parse = [](const std::string& section) {
    StrictYaml y;
    y.file = "recipe.yaml";
    const YAML::Node root = y.parse("name: x\nsimulation:\n" + section);
    SynthSimulationConfig s;
    parse_simulation_config(y, root["simulation"], s);
    return s;
  };
  EXPECT_EQ(parse("  max_body_motion: 0.02\n").max_body_motion, 0.02);
  expect_error([&] { parse("  max_body_motion: 2\n"); }, {"recipe.yaml:3", "simulation.max_body_motion"});
  expect_error([&] { parse("  max_body_motion: fast\n"); }, {"recipe.yaml:3", "simulation.max_body_motion"});
  expect_error([&] { parse("  max_step_halvings: 11\n"); }, {"recipe.yaml:3", "simulation.max_step_halvings"});
  expect_error([&] { parse("  max_step_halvings: -1\n"); }, {"recipe.yaml:3", "simulation.max_step_halvings"});
  expect_error([&] { parse("  collision: {second_sheet_deg: 180}\n"); },
               {"recipe.yaml:3", "simulation.collision.second_sheet_deg"});
  EXPECT_FALSE(parse("  collision: {smooth_creases: false}\n").collision_smooth_creases);
  expect_error([&] { parse("  collision: {smooth_creases: 1.5}\n"); },
               {"recipe.yaml:3", "simulation.collision.smooth_creases", "true or false"});
  expect_error([&] { parse("  solver: {per_vertex_step_limits: maybe}\n"); },
               {"recipe.yaml:3", "simulation.solver.per_vertex_step_limits", "true or false"});
  expect_error([&] { parse("  solver: {per_vertex_step_limit: true}\n"); },
               {"recipe.yaml:3", "per_vertex_step_limit"});
}
