#include "capture/inference/frame_source.h"
#include "capture/dataset/synthetic_dataset.h"

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c); });
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

}  // namespace

FrameSource::FrameSource(const std::string& path) : path_(path) {
  WEFT_CHECK(fs::exists(path), path, ": input not found (expected a video file or a folder of images)");
  if (fs::is_directory(path)) {
    for (const auto& e : fs::directory_iterator(path)) {
      const std::string ext = lower(e.path().extension().string());
      if (e.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp"))
        files_.push_back(e.path().string());
    }
    std::sort(files_.begin(), files_.end());
    WEFT_CHECK(!files_.empty(), path, ": no images (.png, .jpg, .jpeg, .bmp) in the folder");
    bool numbered = true;
    for (const std::string& f : files_) numbered = numbered && all_digits(fs::path(f).stem().string());
    for (size_t i = 0; i < files_.size(); ++i)
      ids_.push_back(numbered ? std::stoi(fs::path(files_[i]).stem().string()) : int(i));
    size_ = int(files_.size());
    return;
  }
  video_ = true;
  // FFmpeg first (it reads every common container); then whatever backend OpenCV has.
  if (!capture_.open(path, cv::CAP_FFMPEG)) capture_.open(path, cv::CAP_ANY);
  WEFT_CHECK(capture_.isOpened(), path, ": cannot be opened as a video (OpenCV's video backends do not read it)");
  size_ = std::max(0, int(capture_.get(cv::CAP_PROP_FRAME_COUNT)));
  fps_ = capture_.get(cv::CAP_PROP_FPS);
  if (!(fps_ > 0 && fps_ < 1000)) fps_ = 0;
}

bool FrameSource::next(InputFrame& frame) {
  if (video_) {
    cv::Mat bgr;
    if (!capture_.read(bgr) || bgr.empty()) return false;
    if (bgr.type() != CV_8UC3) fail(path_, ": frame ", next_, " is not an 8-bit colour image");
    frame.id = next_++;
    frame.name = dataset_frame_name(frame.id);
    frame.bgr = bgr;
    size_ = std::max(size_, next_);
    return true;
  }
  if (next_ >= int(files_.size())) return false;
  const std::string& file = files_[size_t(next_)];
  frame.bgr = cv::imread(file, cv::IMREAD_COLOR);
  WEFT_CHECK(!frame.bgr.empty(), file, ": cannot be read as an image");
  frame.id = ids_[size_t(next_)];
  frame.name = fs::path(file).stem().string();
  ++next_;
  return true;
}

void FrameSource::rewind() {
  next_ = 0;
  if (video_) {
    capture_.release();
    if (!capture_.open(path_, cv::CAP_FFMPEG)) capture_.open(path_, cv::CAP_ANY);
    WEFT_CHECK(capture_.isOpened(), path_, ": cannot be opened again as a video");
  }
}

FrameFiles::FrameFiles(const std::string& dir, const std::string& suffix) : dir_(dir) {
  WEFT_CHECK(fs::is_directory(dir), dir, ": folder not found");
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    if (!e.is_regular_file() || n.size() <= suffix.size() || n.compare(n.size() - suffix.size(), suffix.size(), suffix))
      continue;
    const std::string key = n.substr(0, n.size() - suffix.size());
    by_name_[key] = e.path().string();
    size_t digits = key.size();
    while (digits > 0 && std::isdigit(static_cast<unsigned char>(key[digits - 1]))) --digits;
    if (digits < key.size() && key.size() - digits <= 15) {  // OpenPose pads video frame numbers to 12 digits
      const long long number = std::stoll(key.substr(digits));
      if (number <= 2147483647LL) by_number_[int(number)] = e.path().string();
    }
  }
  WEFT_CHECK(!by_name_.empty(), dir, ": no files ending in ", suffix);
}

std::string FrameFiles::find(const InputFrame& frame) const {
  if (auto it = by_name_.find(frame.name); it != by_name_.end()) return it->second;
  if (auto it = by_number_.find(frame.id); it != by_number_.end()) return it->second;
  return "";
}

}  // namespace weft::capture
