#include "capture/render/photos.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

std::vector<std::string> list_photos(const std::string& path, const std::string& key) {
  std::vector<std::string> out;
  auto is_image = [](const fs::path& p) {
    std::string ext = p.extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char ch) { return std::tolower(ch); });
    return ext == ".jpg" || ext == ".jpeg" || ext == ".png";
  };
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    for (const auto& e : fs::directory_iterator(path, ec))
      if (e.is_regular_file() && is_image(e.path())) out.push_back(e.path().string());
    std::sort(out.begin(), out.end());
  } else if (fs::is_regular_file(path, ec) && is_image(path)) {
    out.push_back(path);
  }
  if (out.empty())
    fail(key, ": no .jpg, .jpeg or .png photo at ", path,
         " (the nature photos come with Debian's mate-backgrounds: scripts/setup.sh installs it)");
  return out;
}

cv::Mat photo_crop(const cv::Mat& photo, int width, int height, double fill, double x, double y) {
  WEFT_CHECK(photo.type() == CV_8UC3 && !photo.empty(), "photo_crop: expected a BGR photo");
  WEFT_CHECK(width > 0 && height > 0 && fill > 0 && fill <= 1 && x >= 0 && x <= 1 && y >= 0 && y <= 1,
             "photo_crop: bad frame ", width, "x", height, " or window (fill ", fill, ", at ", x, ", ", y, ")");
  const double fit = std::min(photo.cols / double(width), photo.rows / double(height)) * fill;
  const int w = std::clamp(static_cast<int>(std::lround(width * fit)), 1, photo.cols);
  const int h = std::clamp(static_cast<int>(std::lround(height * fit)), 1, photo.rows);
  const int left = static_cast<int>(x * (photo.cols - w)), top = static_cast<int>(y * (photo.rows - h));
  cv::Mat out;
  cv::resize(photo(cv::Rect(left, top, w, h)), out, cv::Size(width, height), 0, 0, cv::INTER_AREA);
  return out;
}

}  // namespace weft::capture
