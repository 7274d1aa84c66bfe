#pragma once
// Training-time augmentation of dataset samples (docs/TRAINING.md, "Augmentation"): the
// person's crop moved and scaled, the colours jittered, and the studio's background
// replaced by a photograph behind the person's mask. Every draw is a function of one
// 64-bit seed (the prefetcher gives each sample of each epoch its own), so a resumed run
// sees exactly the images an uninterrupted one saw. The crop's jitter moves the crop
// camera with it: masks, distance transforms, keypoints and every projection stay
// consistent with the image.
#include <opencv2/core.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace YAML {
class Node;
}

namespace weft {
struct StrictYaml;  // files/strict_yaml.h
}  // namespace weft

namespace weft::capture {

struct AugmentationOptions {
  double shift = 0;       // the crop's centre moves by up to ± shift · crop side on each axis
  double scale = 0;       // the crop's side × e^u, u uniform in ±ln(1 + scale)
  double brightness = 0;  // RGB × (1 + u), u uniform in ±brightness
  double contrast = 0;    // (x − image mean)(1 + u) + image mean, u uniform in ±contrast
  double saturation = 0;  // (x − pixel grey)(1 + u) + pixel grey, u uniform in ±saturation
  std::string backgrounds;            // a folder (or file) of photos; "" none
  // The training share of those photos: file names in `backgrounds` (empty: all of them).
  // The rest are the test share, kept for test sequences (docs/TRAINING.md).
  std::vector<std::string> background_photos;
  double background_probability = 0;  // per sample: the photo replaces what is outside the mask
  bool enabled() const {
    return shift > 0 || scale > 0 || brightness > 0 || contrast > 0 || saturation > 0 ||
           (!backgrounds.empty() && background_probability > 0);
  }
};

// Reads an `augmentation:` section; `key` prefixes messages. Unknown keys, values out of
// range and a background folder without photos are errors naming the file, line and key.
AugmentationOptions parse_augmentation(const StrictYaml& yaml, const YAML::Node& section, const std::string& key);

// One sample's draws.
struct AugmentationDraw {
  double shift_x = 0, shift_y = 0;  // fractions of the crop side
  double scale = 1;                 // crop side factor
  double brightness = 1, contrast = 1, saturation = 1;  // factors
  int background = -1;              // index into the photos, -1: keep the studio's
  double photo_x = 0, photo_y = 0, photo_fill = 1;      // where the photo's crop sits (0..1) and its size
};
AugmentationDraw draw_augmentation(const AugmentationOptions& options, int photos, uint64_t seed);

// The photos of `backgrounds` (only those named in `names` when it is not empty), each
// scaled so its longer side is at most max_side pixels (CV_8UC3 BGR). Errors name the folder.
std::vector<cv::Mat> load_background_photos(const std::string& backgrounds, const std::vector<std::string>& names = {},
                                            int max_side = 1024);
// The paths of `backgrounds`'s photos named in `names` (all of them when empty); a name that
// is not one of them is an error naming `key`.
std::vector<std::string> select_photos(const std::string& backgrounds, const std::vector<std::string>& names,
                                       const std::string& key);

// `bgr` (CV_8UC3) with the pixels outside `mask` (CV_8UC1, nonzero = person) replaced by a
// crop of `photo` resized to the image, as `draw` places it.
cv::Mat replace_background(const cv::Mat& bgr, const cv::Mat& mask, const cv::Mat& photo, const AugmentationDraw& draw);

// Brightness, contrast and saturation of an RGB image in [0, 1] (CV_32FC3), in that
// order, clamped to [0, 1].
void jitter_colours(cv::Mat& rgb, const AugmentationDraw& draw);

}  // namespace weft::capture
