// `weft synth`: writes a synthetic multi-view dataset with 3D ground truth (the
// synthetic capture studio, capture/studio/synthetic_studio.h; layout in docs/DATASET.md).
#include <spdlog/spdlog.h>

#include <map>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "capture/evaluation/frame_measures.h"
#include "capture/studio/synthetic_studio.h"

namespace weft::apps {

namespace {

struct SynthArgs {
  std::string config, out;
  long long seed = -1;
  int frames = 0;
  bool skin_only = false;
};

void run_synth(const SynthArgs& a) {
  capture::SynthConfig cfg = capture::load_synth_config(a.config);
  if (a.seed >= 0) cfg.seed = static_cast<uint64_t>(a.seed);
  if (a.frames > 0)
    for (capture::SynthMotionConfig& m : cfg.motions) m.frames = a.frames;
  if (a.skin_only) cfg.simulation.enabled = false;
  spdlog::info("synth '{}': {} frames at {} fps{}, seed {}, character {}", cfg.name, cfg.frames(), cfg.fps(),
               cfg.motions.size() > 1 ? fmt::format(" in {} clips", cfg.motions.size()) : std::string(), cfg.seed,
               cfg.character);
  std::map<std::string, std::unique_ptr<ProgressBar>> bars;
  const capture::SynthSummary s =
      capture::synthesize_dataset(cfg, a.out, [&](const capture::SynthProgress& p) {
        auto& bar = bars[p.stage];
        if (!bar) bar = std::make_unique<ProgressBar>(p.stage);
        bar->update(p.done, p.total);
      });
  spdlog::info("character: {} body vertices, garment {} vertices ({:.1f} s); motion {:.1f} s",
               s.body_vertices, s.cloth_vertices, s.seconds_character, s.seconds_motion);
  int unconverged = 0, newton = 0;
  double pen = 0;
  std::vector<double> oob;  // per simulated frame: its largest vertex out-of-balance force ÷ that vertex's m g
  for (const auto& r : s.reports) {
    unconverged += r.status == "max_iterations";
    newton += r.newton_iterations;
    pen = std::max(pen, r.penetration_max);
    if (r.status != "skinned" && r.status != "settled") oob.push_back(r.oob_force_max_rel);
  }
  if (cfg.simulation.enabled)
    spdlog::info("simulation: {:.1f} s ({:.0f} ms per simulated frame, settling included), {} Newton iterations, {} frames at the iteration cap, "
                 "{} failed; deepest penetration {:.1f} mm; each frame's largest out-of-balance force at its end "
                 "(÷ the vertex's m g; a frame of sub-steps is judged per sub-step) median {:.2g}, p95 {:.2g}, max {:.2g}",
                 s.seconds_simulation,
                 1e3 * s.seconds_simulation /
                     std::max(1, static_cast<int>(s.segments.size()) * (cfg.simulation.settle_frames - 1) + s.frames),
                 newton, unconverged,
                 s.failed_frames, 1e3 * pen, capture::quantile(oob, 0.5), capture::quantile(oob, 0.95),
                 capture::quantile(oob, 1.0));
  spdlog::info("rendering: {} views of {} frames = {} images in {:.1f} s ({:.0f} views/s), writing {:.1f} s",
               s.views, s.frames, s.images, s.seconds_rendering, s.views_per_second(), s.seconds_writing);
  spdlog::info("splits: train {}, val {}, test {} frames; {} failed frames left out", s.train.size(), s.val.size(),
               s.test.size(), s.failed_frames);
  spdlog::info("wrote {} in {:.1f} s (dataset.yaml, cameras.yaml, images/, masks/, parts/, dt/, keypoints/, gt/, "
               "metrics.json)", a.out, s.seconds_total);
}

}  // namespace

void add_synth_command(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  auto* cmd = app.add_subcommand(
      "synth",
      "Write a synthetic capture dataset with 3D ground truth: a generated character driven by a\n"
      "motion, its garment simulated over the motion, rendered into a calibrated studio rig (or\n"
      "one moving 'in the wild' camera): images, masks, part masks, distance transforms, noisy\n"
      "BODY_25 keypoints (OpenPose JSON), cameras, body and cloth meshes per frame and the\n"
      "simulator's metrics. Deterministic for a seed. Layout: docs/DATASET.md.");
  cmd->add_option("--config", args->config, "Dataset config, e.g. configs/synth/tiny.yaml")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "Output folder (created if missing)")->required();
  cmd->add_option("--seed", args->seed, "Overrides the config's seed");
  cmd->add_option("--frames", args->frames,
                  "Overrides motion.frames, or every clip's frames with motions: (e.g. a quick look at a big config)")
      ->check(CLI::PositiveNumber);
  cmd->add_flag("--skin-only", args->skin_only,
                "Skin the garment instead of simulating it (simulation.enabled: false): fast previews and "
                "rendering benchmarks; the cloth is then not ground truth");
  cmd->callback([args] { run_synth(*args); });
}

}  // namespace weft::apps
