#pragma once
// The synthetic capture studio: the library side of `weft synth`. From a config
// (configs/synth/*.yaml, docs/DATASET.md) it builds the default character, drives it with
// a motion (procedural, motion capture in BVH, or a Skeletool .motion), simulates the
// garment over the motion with the body as a moving obstacle and the waistband pinned,
// renders every frame into a studio rig of calibrated cameras (or one moving "in the wild"
// camera), and writes images, masks, part masks, distance transforms, noisy BODY_25
// keypoints, ground-truth meshes and the simulator's metrics. Deterministic for a seed:
// every file but timing.json is identical between runs. Several motion clips may make one
// dataset: their frames are concatenated, and each clip is a simulation segment of its own
// (the garment settles again on its first pose), so no simulation crosses a clip boundary.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "capture/character/default_character.h"
#include "capture/render/renderer.h"
#include "capture/studio/scene_dressing.h"
#include "capture/studio/studio_rig.h"
#include "capture/studio/synthetic_keypoints.h"
#include "capture/garment/garment_config.h"

namespace weft::capture {

struct SynthMotionConfig {
  // Exactly one source.
  std::string procedural;  // a motion spec (configs/motions/*.yaml)
  std::string bvh;         // a BVH clip (e.g. /usr/share/assimp/models/BVH/01_01.bvh)
  std::string mapping;     // retarget mapping for procedural and bvh (configs/retarget/*.yaml)
  std::string skeletool;   // a Skeletool .motion with the character's dofs
  double fps = 30;         // capture rate (frames per second)
  double start_s = 0;      // where in the motion the dataset starts (s)
  int frames = 10;         // frames written
  int stride = 1;          // motion frames per dataset frame
  // ≥ 0: keeps a travelling subject in the studio by taking away the root's horizontal path
  // smoothed over σ = in_place_s seconds of dataset frames (a Gaussian-weighted local line
  // fit: a steady walk becomes a walk on a treadmill; 0 takes away all horizontal root
  // motion). < 0 (the default): the motion's own path.
  double in_place_s = -1;
};

enum class CameraRigKind { studio, wild };

struct SynthCameraConfig {
  CameraRigKind kind = CameraRigKind::studio;
  StudioRigConfig studio;
  WildCameraConfig wild;
};

struct SynthRenderConfig {
  // solid (`green`: a green screen), clutter (procedural) or image (`photos`: a crop of one
  // of `photos` per clip and view, capture/studio/scene_dressing.h)
  BackgroundKind background = BackgroundKind::solid;
  std::vector<std::string> photos;  // background: photos (a folder's images, or one file)
  StudioLightingConfig lighting;    // ambient, headlight, directional lights drawn per clip
  int supersample = 1;
  double dt_scale = 16;    // dt PNG value = min(65535, round(dt_scale · distance in pixels))
  std::string body_texture;  // an image for the body's OBJ texture coordinates (ddc.png); empty: flat skin colour
};

struct SynthConfig {
  std::string file;        // the YAML it came from (messages)
  std::string name;
  uint64_t seed = 1;
  std::string character;   // a default-character config (configs/characters/*.yaml)
  // The clips in dataset order: one from `motion:`, or the `motions:` list. Clip k covers
  // the dataset frames after those of clips 0..k−1; all clips share one fps.
  std::vector<SynthMotionConfig> motions{SynthMotionConfig{}};
  bool motion_list = false;  // the clips came from `motions:` (messages name motions[k])
  SynthSimulationConfig simulation;
  SynthCameraConfig cameras;
  SynthRenderConfig render;
  KeypointNoiseConfig keypoints;
  double val_fraction = 0.1, test_fraction = 0.1;  // one held-out stretch per clip: val, then test
  double split_place = 1;  // where that stretch sits in each clip: 0 its start, 0.5 the middle, 1 the end

  double fps() const { return motions.front().fps; }  // the dataset's frame rate
  int frames() const;                                 // all clips' frames
  // The clip's config key in messages: "motion", or "motions[k]".
  std::string motion_key(size_t clip) const;
};

// Strict YAML: unknown keys, wrong types, missing files and out-of-range values are
// errors naming the file, line and key. Paths are relative to the config.
SynthConfig load_synth_config(const std::string& path);
SynthConfig parse_synth_config(const std::string& yaml_text, const std::string& name);
// A `keypoints:` section (the detector error model, synthetic_keypoints.h) into k: `model`
// first (gaussian or openpose, which sets the other keys' defaults), then the numbers.
// `key` names the section in messages ("keypoints", "virtual_poses.keypoints"); a key of
// the other model, or out of range, is an error naming the file, line and key.
void parse_keypoint_noise(const StrictYaml& y, const YAML::Node& section, KeypointNoiseConfig& k,
                          const std::string& key = "keypoints");

struct SynthFrameReport {
  int frame = 0;
  std::string status = "skinned";  // simulator status, or "skinned" without simulation
  bool failed = false;             // left out of every split
  int newton_iterations = 0;
  double penetration_max = 0;      // m
  double oob_force_max_rel = 0;    // ÷ m g
};

struct SynthSummary {
  int frames = 0, views = 0;
  std::vector<int> segments;        // first frame of each clip (one clip: {0})
  int failed_frames = 0;
  int images = 0;                   // rendered views
  int cloth_vertices = 0, body_vertices = 0;
  std::vector<int> train, val, test;
  std::vector<SynthFrameReport> reports;
  double seconds_character = 0, seconds_motion = 0, seconds_simulation = 0;
  double seconds_rendering = 0;     // render + distance transform + keypoints (wall)
  double seconds_writing = 0;       // PNG/JSON/PLY encoding and writes (wall)
  double seconds_total = 0;
  double views_per_second() const { return seconds_rendering > 0 ? images / seconds_rendering : 0; }
};

struct SynthProgress {
  std::string stage;  // "motion" ("motion k/n" per clip with several), "simulation", "rendering"
  int done = 0, total = 0;
};

// Writes the dataset into out_dir (created if missing; existing dataset files are
// replaced). `progress` is called as stages advance, from one thread at a time (the
// rendering's parallel loop calls it under a lock), with `done` rising within a stage. With several clips, dataset.yaml
// lists their first frames (`segments`) and every split takes its fraction from the end of
// each clip; one clip gives the files a single-clip config always gave.
SynthSummary synthesize_dataset(const SynthConfig& config, const std::string& out_dir,
                                const std::function<void(const SynthProgress&)>& progress = {});

// The splits of one clip's frames [first, end): floor(val_fraction · n) val frames then
// floor(test_fraction · n) test frames in one held-out stretch that starts at
// first + round(place · (n − held-out frames)), the rest train; each list ascending.
struct ClipSplit {
  std::vector<int> train, val, test;
};
ClipSplit split_clip(int first, int end, double val_fraction, double test_fraction, double place);

}  // namespace weft::capture
