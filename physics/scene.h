#pragma once
// Simulation scenes for `weft sim`: a YAML file describing the cloth, its material, the
// obstacles and the solver (format in docs/SIMULATION.md), loaded strictly (unknown keys,
// wrong types, missing files and non-physical values are errors naming the key and the
// file), and run frame by frame with per-frame metrics.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "physics/cloth_simulator.h"
#include "physics/cloth_metrics.h"

namespace weft::physics {

struct SceneObstacle {
  enum class Kind { sphere, mesh, mesh_sequence } kind = Kind::sphere;
  SphereObstacle sphere{};
  std::string path;                 // mesh file, or the sequence's printf-style pattern
  std::vector<int> inactive_faces;  // faces left out of collisions
  double friction = 0.3;            // Coulomb μ against the cloth (spheres: also in sphere)
};

struct Scene {
  std::string file;  // the YAML it came from
  int frames = 100;
  SimulationSettings settings;
  ClothMesh cloth;
  std::vector<int> pins;
  // The state the run starts from (cloth.initial): positions at frame 0 and one frame
  // before it (velocity by their difference), 3n metres; both the rest shape by default.
  Positions initial, initial_previous;
  std::vector<SceneObstacle> obstacles;
};

Scene load_scene(const std::string& path);

// Per-frame record of a run (the keys of metrics.json's `frames`).
struct FrameRecord {
  int frame = 0;
  StepStatus status = StepStatus::converged;
  int newton_iterations = 0;
  double gradient_norm = 0, energy = 0, step_ms = 0;
  FrameMetrics metrics;
};

// One frame's entry of metrics.json (`frame`, `status`, `newton_iterations`, …; keys in
// docs/SIMULATION.md). Without timing, `step_ms` is left out: the entry is then the same in
// every run.
nlohmann::json frame_record_json(const FrameRecord& record, bool with_timing = true);

struct SceneRun {
  std::vector<FrameRecord> frames;
  std::string metrics_json;  // the document written to metrics.json
};

// Runs the scene; when out_dir is not empty writes out_dir/cloth_%04d.obj (frame 0 is the
// initial state) and out_dir/metrics.json. `progress(frame, record)` is called per frame.
SceneRun run_scene(const Scene& scene, const std::string& out_dir,
                   const std::function<void(const FrameRecord&)>& progress = {});

// The path of frame `frame` of a sequence pattern such as "body_%04d.obj".
std::string sequence_path(const std::string& pattern, int frame);

}  // namespace weft::physics
