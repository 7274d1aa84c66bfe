#pragma once
// The synthetic studio's default character: the MakeHuman base body of Debian's
// assimp-testmodels (or any closed A-pose body assimp reads), scaled to a height, with a
// skeleton fitted to its geometry (capture/character/body_skeleton_fit.h), bone-distance skinning
// weights, a BODY_25 map, embedded graphs and a generated skirt or dress (optionally with
// shoulder straps) anchored at its top ring. Built in memory and written as a character
// folder that load_character reads (docs/CHARACTER.md, "Generated characters"). Metres.
// A config with `base:` instead of `mesh:` dresses an existing character.yaml (e.g. ddc,
// millimetres) with a generated skirt instead (docs/CHARACTER.md, "Dressing an existing
// character"): the same three functions, the base's own units.
#include <string>

#include "capture/character/appearance.h"
#include "capture/character/body_skeleton_fit.h"
#include "capture/character/character.h"
#include "capture/character/dressed_character.h"
#include "capture/character/joint_limits.h"

namespace weft::capture {

struct DefaultCharacterConfig {
  std::string file;          // the config it was read from (for messages); may be empty
  std::string name = "makehuman";
  std::string mesh = "/usr/share/assimp/models/Collada/human.zae";  // absolute, or relative to the config
  std::string base;          // instead of mesh: an existing character.yaml to dress (absolute path)
  double height_m = 1.66;    // the body is scaled to this height
  int body_graph_nodes = 500;
  int nodes_per_vertex = 4;
  // Garment (metres, converted with the character's metres_per_unit; flare is a ratio).
  GarmentType garment = GarmentType::skirt;
  double length = 0.45;      // top ring to hem
  double flare = 0.35;       // radius gained per metre of drop beyond what the body needs
  double clearance = 0.012;  // minimum distance to the body in the bind pose
  double top_offset = 0;     // skirt: top ring this far above the waist (base: the hip joints); dress: below the armpits
  bool straps = false;       // dress only: two shoulder straps sewn to the top ring
  int segments = 64;         // vertices around
  int rings = 48;            // rings top to hem
  int cloth_graph_nodes = 300;
  double cloth_rigidity = 0.1;
  // Per-vertex colours painted on the body and garment (capture/character/appearance.h);
  // with base: the garment only (the base keeps its own texture).
  AppearanceConfig appearance;
  // Overrides of the generated skeleton's joint limits (joint_limits.h; not with base).
  std::vector<DofLimit> joint_limits;
};

// Strict YAML (unknown keys and bad values are errors naming the key, the file and the
// line); see configs/characters/makehuman_skirt.yaml for every key, ddc_skirt.yaml for base.
DefaultCharacterConfig load_default_character_config(const std::string& path);
DefaultCharacterConfig parse_default_character_config(const std::string& yaml_text, const std::string& name);

struct DefaultCharacter {
  Character character;        // complete: skeleton, body, cloth, attachment, BODY_25
  BodySkeletonFit fit;        // the fitted joint positions and landmark heights (empty with base)
  LoadedBody loaded;          // the source mesh as read (file vertex count and height; empty with base)
  std::vector<char> arm_vertices;  // arm and hand vertices (arm_vertices in body_skeleton_fit.h;
                                   // with base: arm_vertices_from_skinning)
  double garment_top_y = 0;         // the garment's top ring height (character units)
  double garment_min_distance = 0;  // garment to body in the bind pose (character units)
  int garment_inside = 0;           // garment vertices inside the body (0 expected)
};

DefaultCharacter make_default_character(const DefaultCharacterConfig& config);

// Writes `dir`/character.yaml, body.obj, body.skeleton, rest.motion, the garment
// (<skirt|dress>.obj), anchors.txt and inactive_faces.txt; `dir` is created if missing.
// With base: character.yaml (the base's, its files referenced by absolute path, never
// copied), the garment, anchors.txt and inactive_faces.txt. Returns the character.yaml path.
std::string write_default_character(const DefaultCharacter& character, const DefaultCharacterConfig& config,
                                    const std::string& dir);

}  // namespace weft::capture
