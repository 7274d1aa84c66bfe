#include "capture/dataset/augmentation.h"


#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "capture/io/portable_random.h"
#include "files/strict_yaml.h"
#include "capture/render/photos.h"
#include "graph/error.h"

namespace weft::capture {

AugmentationOptions parse_augmentation(const StrictYaml& y, const YAML::Node& n, const std::string& key) {
  AugmentationOptions a;
  if (!n.IsMap()) y.fail_at(n, key, "expected a map of augmentation keys");
  y.numbers(n, key + ".",
            {{"shift", &a.shift, 0, 0.5},
             {"scale", &a.scale, 0, 1},
             {"brightness", &a.brightness, 0, 0.9},
             {"contrast", &a.contrast, 0, 0.9},
             {"saturation", &a.saturation, 0, 1},
             {"background_probability", &a.background_probability, 0, 1}},
            {}, {"backgrounds", "background_photos"});
  if (n["backgrounds"]) {
    const std::string where = y.get<std::string>(n["backgrounds"], key + ".backgrounds", "a folder of photos");
    a.backgrounds = (y.dir / where).lexically_normal().string();
    try {
      list_photos(a.backgrounds, key + ".backgrounds");
    } catch (const Error&) {
      y.fail_at(n["backgrounds"], key + ".backgrounds",
                "no .jpg, .jpeg or .png photo at " + a.backgrounds +
                    " (Debian's mate-backgrounds has /usr/share/backgrounds/mate/nature: scripts/setup.sh installs it)");
    }
  }
  if (const YAML::Node names = n["background_photos"]) {
    if (a.backgrounds.empty()) y.fail_at(names, key + ".background_photos", "needs " + key + ".backgrounds");
    a.background_photos = y.strings(names, key + ".background_photos");
    if (a.background_photos.empty())
      y.fail_at(names, key + ".background_photos", "expected a list of photo file names (the training share)");
    try {
      select_photos(a.backgrounds, a.background_photos, key + ".background_photos");
    } catch (const Error& e) {
      y.fail_at(names, key + ".background_photos", e.what());
    }
  }
  if (a.background_probability > 0 && a.backgrounds.empty())
    y.fail_at(n["background_probability"], key + ".background_probability", "needs " + key + ".backgrounds");
  return a;
}

AugmentationDraw draw_augmentation(const AugmentationOptions& o, int photos, uint64_t seed) {
  PortableRandom rng(seed);
  AugmentationDraw d;
  // A fixed number of draws whatever the options, so one option does not move the others.
  const double u[9] = {rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1),
                       rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(),      rng.uniform(),
                       rng.uniform()};
  const double pick = rng.uniform(), fill = rng.uniform();
  d.shift_x = o.shift * u[0];
  d.shift_y = o.shift * u[1];
  d.scale = std::exp(std::log1p(o.scale) * u[2]);
  d.brightness = 1 + o.brightness * u[3];
  d.contrast = 1 + o.contrast * u[4];
  d.saturation = 1 + o.saturation * u[5];
  if (photos > 0 && u[6] < o.background_probability)
    d.background = std::min(photos - 1, static_cast<int>(pick * photos));
  d.photo_x = u[7];
  d.photo_y = u[8];
  d.photo_fill = 0.4 + 0.6 * fill;
  return d;
}

std::vector<std::string> select_photos(const std::string& backgrounds, const std::vector<std::string>& names,
                                       const std::string& key) {
  const std::vector<std::string> all = list_photos(backgrounds, key);
  if (names.empty()) return all;
  std::vector<std::string> out;
  for (const std::string& name : names) {
    const auto it = std::find_if(all.begin(), all.end(), [&](const std::string& p) {
      return std::filesystem::path(p).filename().string() == name;
    });
    if (it == all.end()) fail(key, ": no photo '", name, "' in ", backgrounds);
    if (std::find(out.begin(), out.end(), *it) != out.end()) fail(key, ": photo '", name, "' listed twice");
    out.push_back(*it);
  }
  return out;
}

std::vector<cv::Mat> load_background_photos(const std::string& backgrounds, const std::vector<std::string>& names,
                                            int max_side) {
  std::vector<cv::Mat> out;
  for (const std::string& path : select_photos(backgrounds, names, "augmentation.backgrounds")) {
    cv::Mat photo = cv::imread(path, cv::IMREAD_COLOR);
    WEFT_CHECK(!photo.empty(), path, ": cannot read this photo as an image");
    const double s = double(max_side) / std::max(photo.cols, photo.rows);
    if (s < 1) cv::resize(photo, photo, cv::Size(), s, s, cv::INTER_AREA);
    out.push_back(photo);
  }
  return out;
}

cv::Mat replace_background(const cv::Mat& bgr, const cv::Mat& mask, const cv::Mat& photo, const AugmentationDraw& d) {
  WEFT_CHECK(bgr.type() == CV_8UC3 && mask.type() == CV_8UC1 && bgr.size() == mask.size() && photo.type() == CV_8UC3,
             "replace_background: expected a BGR image, its 8-bit mask and a BGR photo");
  cv::Mat back = photo_crop(photo, bgr.cols, bgr.rows, d.photo_fill, d.photo_x, d.photo_y);
  bgr.copyTo(back, mask);
  return back;
}

void jitter_colours(cv::Mat& rgb, const AugmentationDraw& d) {
  WEFT_CHECK(rgb.type() == CV_32FC3, "jitter_colours: expected CV_32FC3");
  if (d.brightness != 1) rgb *= d.brightness;
  if (d.contrast != 1) {
    const cv::Scalar m = cv::mean(rgb);
    const float grey = float((m[0] + m[1] + m[2]) / 3);
    rgb = (rgb - cv::Scalar::all(grey)) * d.contrast + cv::Scalar::all(grey);
  }
  if (d.saturation != 1) {
    const float s = float(d.saturation);
    for (int r = 0; r < rgb.rows; ++r) {
      float* p = rgb.ptr<float>(r);
      for (int c = 0; c < rgb.cols; ++c, p += 3) {
        const float g = 0.299f * p[0] + 0.587f * p[1] + 0.114f * p[2];
        for (int k = 0; k < 3; ++k) p[k] = g + (p[k] - g) * s;
      }
    }
  }
  cv::min(cv::max(rgb, 0.0), 1.0, rgb);
}

}  // namespace weft::capture
