#include "capture/inference/sequence_input.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <spdlog/fmt/fmt.h>

#include <chrono>
#include <regex>

#include "capture/dataset/synthetic_dataset.h"
#include "capture/inference/green_screen.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

cv::Mat read_mask(const std::string& path, const cv::Size& size) {
  const cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
  WEFT_CHECK(!m.empty(), path, ": cannot be read as a mask image");
  WEFT_CHECK(m.size() == size, path, ": mask of ", m.cols, "x", m.rows, ", expected the frame's ", size.width, "x",
             size.height);
  cv::Mat out;
  cv::threshold(m, out, 127, 255, cv::THRESH_BINARY);
  return out;
}

}  // namespace

CaptureCameras::CaptureCameras(const std::string& file, const std::string& wanted) : file_(file) {
  for (const Camera& c : read_cameras_yaml(file)) by_name_[c.name] = c;
  WEFT_CHECK(!by_name_.empty(), file, ": no cameras");
  const std::regex per_frame("(.+)_([0-9]{4,})");
  std::map<std::string, int> families;
  for (const auto& [n, c] : by_name_) {
    std::smatch m;
    if (std::regex_match(n, m, per_frame)) ++families[m[1].str()];
  }
  if (!wanted.empty()) {
    name_ = wanted;
    per_frame_ = !by_name_.count(wanted) && families.count(wanted);
    WEFT_CHECK(by_name_.count(wanted) || per_frame_, file, ": no camera '", wanted, "' (nor per-frame cameras ",
               wanted, "_0000, …); the file has ", listing());
  } else if (by_name_.size() == 1) {
    name_ = by_name_.begin()->first;
  } else if (families.size() == 1 && families.begin()->second == int(by_name_.size())) {
    name_ = families.begin()->first;
    per_frame_ = true;
  } else {
    fail(file, ": several cameras (", listing(), "); choose one with --camera-name");
  }
}

const Camera& CaptureCameras::at(int id) const {
  const std::string n = per_frame_ ? name_ + "_" + dataset_frame_name(id) : name_;
  const auto it = by_name_.find(n);
  WEFT_CHECK(it != by_name_.end(), file_, ": no camera '", n, "' for frame ", id);
  return it->second;
}

std::string CaptureCameras::listing() const {
  std::string s;
  int k = 0;
  for (const auto& [n, c] : by_name_) {
    if (k++ == 6) return s + ", …";
    s += (s.empty() ? "" : ", ") + n;
  }
  return s;
}

SequenceInput::SequenceInput(SequenceInputOptions o)
    : options_(std::move(o)), cameras_(options_.camera, options_.camera_name), source_(options_.input) {
  if (!options_.masks.empty()) masks_ = FrameFiles(options_.masks, ".png");
  if (!options_.keypoints.empty()) keypoints_ = FrameFiles(options_.keypoints, "_keypoints.json");
}

const char* input_source_name(InputSource s) {
  switch (s) {
    case InputSource::folder: return "folder";
    case InputSource::detector: return "detector";
    case InputSource::keying: return "keying";
    case InputSource::none: return "none";
  }
  return "?";
}

InputSource SequenceInput::masks_from() const {
  return !options_.masks.empty() ? InputSource::folder : options_.detector ? InputSource::detector : InputSource::keying;
}

InputSource SequenceInput::keypoints_from() const {
  return !options_.keypoints.empty() ? InputSource::folder : options_.detector ? InputSource::detector : InputSource::none;
}

std::string SequenceInput::describe() const {
  auto what = [](InputSource s, const std::string& folder, const char* otherwise) {
    return s == InputSource::folder     ? folder
           : s == InputSource::detector ? std::string("the model's person detector")
                                        : std::string(otherwise);
  };
  return fmt::format("input {} ({} frames{}); camera {}{}; masks: {}; keypoints: {}", options_.input, source_.size(),
                     source_.is_video() ? fmt::format(", {:.3g} fps", source_.fps()) : std::string(), cameras_.name(),
                     cameras_.per_frame() ? " (one per frame)" : "",
                     what(masks_from(), options_.masks, "green-screen keying"),
                     what(keypoints_from(), options_.keypoints, "none"));
}

bool SequenceInput::next(SequenceFrame& f, std::map<std::string, double>* parts) {
  using Clock = std::chrono::steady_clock;
  auto t = Clock::now();
  auto lap = [&](const char* part) {
    const auto now = Clock::now();
    if (parts) (*parts)[part] += std::chrono::duration<double>(now - t).count();
    t = now;
  };
  const bool detecting = masks_from() == InputSource::detector || keypoints_from() == InputSource::detector;
  PersonDetection detected;
  if (!detecting) {
    if (!source_.next(f.frame)) return false;
  } else {
    if (ahead_.empty()) {
      std::vector<InputFrame> frames;
      for (InputFrame g; int(frames.size()) < kDetectBatch && source_.next(g); g = InputFrame()) frames.push_back(g);
      if (frames.empty()) return false;
      lap("read");
      std::vector<cv::Mat> images;
      for (const InputFrame& g : frames) images.push_back(g.bgr);
      std::vector<PersonDetection> found = detect_people(*options_.detector, images);
      for (size_t i = 0; i < frames.size(); ++i) ahead_.emplace_back(std::move(frames[i]), std::move(found[i]));
      lap("detect");
    }
    f.frame = std::move(ahead_.front().first);
    detected = std::move(ahead_.front().second);
    ahead_.pop_front();
  }
  f.camera = cameras_.at(f.frame.id);
  WEFT_CHECK(f.frame.bgr.cols == f.camera.width && f.frame.bgr.rows == f.camera.height, options_.camera,
             ": camera '", f.camera.name, "' is for ", f.camera.width, "x", f.camera.height, " images, but frame ",
             f.frame.name, " of ", options_.input, " is ", f.frame.bgr.cols, "x", f.frame.bgr.rows);
  f.detections = Body25::Zero();
  f.has_detections = false;
  if (!keypoints_.empty()) {
    const std::string path = keypoints_.find(f.frame);
    if (!path.empty()) f.detections = read_dataset_keypoints(path), f.has_detections = true;
  }
  lap("read");
  if (keypoints_from() == InputSource::detector) f.detections = detected.keypoints, f.has_detections = detected.found;
  if (masks_from() == InputSource::detector) {
    f.mask = detected.mask;
  } else if (!masks_.empty()) {
    const std::string path = masks_.find(f.frame);
    WEFT_CHECK(!path.empty(), options_.masks, ": no mask for frame ", f.frame.name, " (expected ", f.frame.name,
               ".png)");
    f.mask = read_mask(path, f.frame.bgr.size());
  } else {
    f.mask = key_green_screen(f.frame.bgr, options_.keying);
  }
  lap("segment");
  return true;
}

}  // namespace weft::capture
