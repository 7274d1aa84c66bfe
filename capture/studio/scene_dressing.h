#pragma once
// What surrounds the subject of a synthetic take, drawn per clip from the dataset's seed:
// the lights (an ambient term, the optional headlight along each camera's axis and
// directional lights from random directions above the horizon) and the photographs behind
// the subject (a random crop of one photo per clip and view). A clip is one take: its lights
// and backgrounds stay fixed through it, as they would in a studio or on location.
//
// Photos are read from where Debian installs them (scripts/setup.sh installs
// mate-backgrounds: /usr/share/backgrounds/mate/nature, GPL-2+); never copied into datasets'
// configs or the repository; a dataset's images contain crops of them.
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "capture/render/photos.h"
#include "capture/render/renderer.h"

namespace YAML {
class Node;
}

namespace weft {
struct StrictYaml;  // files/strict_yaml.h
}  // namespace weft

namespace weft::capture {

struct StudioLightingConfig {
  double ambient = 0.35;
  double headlight = 0.65;  // along each camera's optical axis; 0 switches it off
  int lights = 0;           // directional lights, directions drawn per clip
  double intensity_min = 0.3, intensity_max = 0.6;          // drawn per light
  double elevation_min_deg = 15, elevation_max_deg = 60;    // above the horizon; azimuth: the whole circle
};

// Reads a `lighting:` section; `key` prefixes messages (e.g. "render.lighting"). Unknown
// keys, out-of-range values and a min above its max are errors naming the file, line and key.
StudioLightingConfig parse_studio_lighting(const StrictYaml& yaml, const YAML::Node& section, const std::string& key);

// The lighting of clip `clip` (y up, metres or any unit: only directions matter).
Lighting draw_lighting(const StudioLightingConfig& config, uint64_t seed, int clip);

// A width×height crop of one of `photos` (CV_8UC3), drawn for (seed, clip, view): the
// photo is scaled so the frame covers 50–100 % of its shorter side, and the crop's place is
// uniform within it. Throws weft::Error naming the file when it cannot be read.
cv::Mat draw_photo_background(const std::vector<std::string>& photos, int width, int height, uint64_t seed,
                              int clip, int view);
// Which of `count` photos draw_photo_background takes for (seed, clip, view): the test
// sequences' backgrounds, which a detector's training share of the photos must leave out.
size_t photo_background_index(size_t count, uint64_t seed, int clip, int view);

}  // namespace weft::capture
