#include "capture/studio/scene_dressing.h"


#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <numbers>

#include "capture/io/portable_random.h"
#include "capture/render/photos.h"
#include "files/strict_yaml.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

constexpr uint64_t kLightStream = 0x4c49474854534554ull;  // "LIGHTSET"
constexpr uint64_t kPhotoStream = 0x50484f544f424b47ull;  // "PHOTOBKG"

// A [min, max] pair within [lo, hi].
void range(const StrictYaml& y, const YAML::Node& n, const std::string& key, double lo, double hi, double& min,
           double& max) {
  if (!n.IsSequence() || n.size() != 2) y.fail_at(n, key, "expected [min, max]");
  min = y.number(n[0], key, lo, hi);
  max = y.number(n[1], key, lo, hi);
  if (min > max) y.fail_at(n, key, "min must not exceed max");
}

}  // namespace

StudioLightingConfig parse_studio_lighting(const StrictYaml& y, const YAML::Node& n, const std::string& key) {
  StudioLightingConfig c;
  if (!n.IsMap()) y.fail_at(n, key, "expected a map of lighting keys");
  y.numbers(n, key + ".", {{"ambient", &c.ambient, 0, 4}, {"headlight", &c.headlight, 0, 4}},
            {{"lights", &c.lights, 0, 8}}, {"intensity", "elevation_deg"});
  if (n["intensity"]) range(y, n["intensity"], key + ".intensity", 0, 4, c.intensity_min, c.intensity_max);
  if (n["elevation_deg"])
    range(y, n["elevation_deg"], key + ".elevation_deg", -90, 90, c.elevation_min_deg, c.elevation_max_deg);
  if (c.ambient + c.headlight + c.lights * c.intensity_max <= 0)
    y.fail_at(n, key, "no light at all: ambient, headlight and lights are all zero");
  return c;
}

Lighting draw_lighting(const StudioLightingConfig& c, uint64_t seed, int clip) {
  Lighting l;
  l.ambient = c.ambient;
  l.headlight = c.headlight;
  PortableRandom rng(mix_seed(seed, kLightStream, static_cast<uint64_t>(clip)));
  const double deg = std::numbers::pi / 180;
  for (int i = 0; i < c.lights; ++i) {
    const double azimuth = rng.uniform(0, 2 * std::numbers::pi);
    const double elevation = rng.uniform(c.elevation_min_deg, c.elevation_max_deg) * deg;
    const double intensity = rng.uniform(c.intensity_min, c.intensity_max);
    // Where the light comes from (y up); it travels the other way.
    const Eigen::Vector3d from(std::cos(elevation) * std::sin(azimuth), std::sin(elevation),
                               std::cos(elevation) * std::cos(azimuth));
    l.lights.push_back({-from, intensity});
  }
  return l;
}

size_t photo_background_index(size_t count, uint64_t seed, int clip, int view) {
  WEFT_CHECK(count > 0, "photo background: no photos to draw from");
  PortableRandom rng(mix_seed(mix_seed(seed, kPhotoStream, static_cast<uint64_t>(clip)), static_cast<uint64_t>(view), 0));
  return std::min(count - 1, static_cast<size_t>(rng.uniform() * count));
}

cv::Mat draw_photo_background(const std::vector<std::string>& photos, int width, int height, uint64_t seed, int clip,
                              int view) {
  WEFT_CHECK(!photos.empty(), "photo background: no photos to draw from");
  WEFT_CHECK(width > 0 && height > 0, "photo background: bad frame size ", width, "x", height);
  PortableRandom rng(mix_seed(mix_seed(seed, kPhotoStream, static_cast<uint64_t>(clip)), static_cast<uint64_t>(view), 0));
  rng.uniform();  // the pick's draw, made by photo_background_index from the same stream
  const size_t pick = photo_background_index(photos.size(), seed, clip, view);
  const cv::Mat photo = cv::imread(photos[pick], cv::IMREAD_COLOR);
  WEFT_CHECK(!photo.empty(), photos[pick], ": cannot read this photo as an image");
  // The frame spans 50–100 % of the photo along its tighter axis.
  const double fill = rng.uniform(0.5, 1.0), x = rng.uniform(), y = rng.uniform();
  return photo_crop(photo, width, height, fill, x, y);
}

}  // namespace weft::capture
