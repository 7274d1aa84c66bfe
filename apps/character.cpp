// `weft character`: generates the synthetic studio's default character (a body from a
// mesh file with a fitted skeleton and a generated garment) and writes it as a folder
// that `weft pose --character DIR/character.yaml` loads.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "capture/character/default_character.h"

namespace weft::apps {

namespace {

struct CharacterArgs {
  std::string config, out;
};

void run_character(const CharacterArgs& a) {
  const auto t0 = std::chrono::steady_clock::now();
  const capture::DefaultCharacterConfig cfg = capture::load_default_character_config(a.config);
  const capture::DefaultCharacter dc = capture::make_default_character(cfg);
  const std::string yaml = capture::write_default_character(dc, cfg, a.out);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const capture::Character& ch = dc.character;
  if (cfg.base.empty()) {
    spdlog::info("body: {} ({} vertices in the file, {} welded, {} triangles), {:.3f} m tall (scale {:.4f})",
                 cfg.mesh, dc.loaded.file_vertices, ch.body.mesh.num_vertices(), ch.body.mesh.num_faces(),
                 dc.fit.height, dc.loaded.scale);
    spdlog::info("skeleton: {} joints ({} anatomical + {} end sites as {} 1-dof joints), {} dofs, {} markers; "
                 "crotch {:.3f} m, waist {:.3f} m, armpits {:.3f} m, neck {:.3f} m",
                 capture::kBodyJointNames.size() + capture::kBodyEndSiteNames.size(),
                 capture::kBodyJointNames.size(), capture::kBodyEndSiteNames.size(), ch.skeleton.num_joints(),
                 ch.skeleton.num_dofs(), ch.skeleton.num_markers(), dc.fit.crotch_y, dc.fit.waist_y, dc.fit.armpit_y,
                 dc.fit.neck_y);
  } else {
    const long arm = std::count(dc.arm_vertices.begin(), dc.arm_vertices.end(), char(1));
    spdlog::info("base: {} ({} body vertices, {} triangles, {} arm and hand vertices by skinning; {} joints, "
                 "{} dofs; metres_per_unit {}); garment top at {:.3f} m",
                 cfg.base, ch.body.mesh.num_vertices(), ch.body.mesh.num_faces(), arm, ch.skeleton.num_joints(),
                 ch.skeleton.num_dofs(), ch.metres_per_unit, dc.garment_top_y * ch.metres_per_unit);
  }
  spdlog::info("inactive body faces (arms, hands): {}", ch.inactive_body_faces.size());
  if (ch.has_cloth())
    spdlog::info("{}: {} vertices, {} triangles, {} anchors, {} graph nodes; closest to the body {:.1f} mm, "
                 "{} vertices inside",
                 capture::garment_name(cfg.garment), ch.cloth->mesh.num_vertices(), ch.cloth->mesh.num_faces(),
                 ch.attachment.size(), ch.cloth->graph.num_nodes(), 1e3 * ch.metres_per_unit * dc.garment_min_distance,
                 dc.garment_inside);
  spdlog::info("wrote {} in {:.2f} s", yaml, seconds);
}

}  // namespace

void add_character_command(CLI::App& app) {
  auto args = std::make_shared<CharacterArgs>();
  auto* cmd = app.add_subcommand(
      "character",
      "Generate a character from a body mesh (default: the MakeHuman body of Debian's\n"
      "assimp-testmodels): a skeleton fitted to the geometry, BODY_25 map, skinning weights,\n"
      "embedded graphs and a skirt or dress. Writes a folder with character.yaml, body.obj,\n"
      "body.skeleton, rest.motion and the garment (docs/CHARACTER.md). Metres.\n"
      "A config with `base: character.yaml` dresses that character with a skirt instead\n"
      "(e.g. configs/characters/ddc_skirt.yaml); its files are referenced, not copied.");
  cmd->add_option("--config", args->config, "Generation config, e.g. configs/characters/makehuman_skirt.yaml")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "Output folder (created if missing)")->required();
  cmd->callback([args] { run_character(*args); });
}

}  // namespace weft::apps
