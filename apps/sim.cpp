// `weft sim SCENE.yaml --out DIR`: runs a cloth simulation scene (docs/SIMULATION.md) and
// writes DIR/cloth_%04d.obj per frame and DIR/metrics.json.
#include <spdlog/spdlog.h>

#include "apps/commands.h"
#include "physics/scene.h"

namespace weft::apps {

void add_sim_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("sim", "Run a cloth simulation scene (YAML; see docs/SIMULATION.md)");
  auto scene_path = std::make_shared<std::string>();
  auto out_dir = std::make_shared<std::string>();
  auto every = std::make_shared<int>(0);
  cmd->add_option("scene", *scene_path, "Scene file (YAML)")->required();
  cmd->add_option("--out", *out_dir, "Output directory for cloth_%04d.obj and metrics.json")
      ->required();
  cmd->add_option("--log-every", *every, "Log progress every N frames (0: about ten lines)");
  cmd->callback([scene_path, out_dir, every] {
    const physics::Scene scene = physics::load_scene(*scene_path);
    spdlog::info("sim: {} vertices, {} triangles, {} frames of {} s ({} sub-steps)",
                 scene.cloth.num_vertices(), scene.cloth.triangles.size(), scene.frames,
                 scene.settings.time_step, scene.settings.substeps);
    const int n = *every > 0 ? *every : std::max(1, scene.frames / 10);
    const auto run = physics::run_scene(scene, *out_dir, [&](const physics::FrameRecord& r) {
      if (r.frame % n == 0 || r.frame == scene.frames || r.status != physics::StepStatus::converged)
        spdlog::info("frame {}/{}: {} in {} Newton iterations, {:.1f} ms, min distance {:.4g} m",
                     r.frame, scene.frames, physics::to_string(r.status), r.newton_iterations,
                     r.step_ms, r.metrics.min_signed_distance);
    });
    int converged = 0;
    for (const auto& r : run.frames) converged += r.status == physics::StepStatus::converged;
    spdlog::info("sim: {}/{} frames converged; wrote {}/cloth_*.obj and {}/metrics.json",
                 converged, run.frames.size(), *out_dir, *out_dir);
  });
}

}  // namespace weft::apps
