#include "capture/dataset/multiview_supervision.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <filesystem>

#include "capture/render/renderer.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

// The square [0, side)² of the full image (padded), resized to `size`.
CropWindow whole_image_window(const DatasetInfo& info, int size) {
  CropWindow w;
  w.left = w.top = 0;
  w.side = std::max(info.image_width, info.image_height);
  w.scale = double(size) / w.side;
  w.x0 = w.left - 0.5 + 0.5 / w.scale;
  w.y0 = w.top - 0.5 + 0.5 / w.scale;
  w.source = CropSource::whole_image;
  return w;
}

}  // namespace

MultiviewSupervision::MultiviewSupervision(const DatasetInfo& info, const std::vector<int>& frames,
                                           int silhouette_size)
    : info_(info), size_(silhouette_size) {
  WEFT_CHECK(size_ >= 8, "MultiviewSupervision: silhouette size must be ≥ 8, got ", size_);
  const std::string cameras_path = (fs::path(info.dir) / "cameras.yaml").string();
  std::map<std::string, Camera> cameras;
  for (Camera& c : read_cameras_yaml(cameras_path)) cameras[c.name] = c;
  const CropWindow window = whole_image_window(info, size_);
  for (int f : frames) {
    FrameData d;
    for (const std::string& view : info.views) {
      const std::string name = dataset_camera_name(info, f, view);
      const auto it = cameras.find(name);
      WEFT_CHECK(it != cameras.end(), cameras_path, ": no camera '", name, "' (frame ", f, ", view ", view, ")");
      d.cameras.push_back(it->second);
      d.silhouette_cameras.push_back(crop_camera(it->second, window, size_));
      d.detections.push_back(read_dataset_keypoints(dataset_keypoints_path(info, f, view)));
    }
    frames_.emplace(f, std::move(d));
  }
}

const MultiviewSupervision::FrameData& MultiviewSupervision::at(int frame) const {
  const auto it = frames_.find(frame);
  WEFT_CHECK(it != frames_.end(), info_.dir, ": frame ", frame, " was not loaded for multi-view supervision");
  return it->second;
}

const Camera& MultiviewSupervision::camera(int frame, int v) const { return at(frame).cameras.at(v); }
const Body25& MultiviewSupervision::detections(int frame, int v) const { return at(frame).detections.at(v); }
const Camera& MultiviewSupervision::silhouette_camera(int frame, int v) const {
  return at(frame).silhouette_cameras.at(v);
}

cv::Mat MultiviewSupervision::mask(int frame, int v) const {
  at(frame);
  const std::pair<int, int> key{frame, v};
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = masks_.find(key);
    if (it != masks_.end()) return it->second;
  }
  const cv::Mat full = read_dataset_mask(info_, frame, info_.views.at(v));  // 0/255
  const int side = std::max(full.cols, full.rows);
  cv::Mat square(side, side, CV_32FC1, cv::Scalar(0));
  full.convertTo(square(cv::Rect(0, 0, full.cols, full.rows)), CV_32FC1, 1.0 / 255.0);
  cv::Mat small;
  cv::resize(square, small, cv::Size(size_, size_), 0, 0, size_ < side ? cv::INTER_AREA : cv::INTER_LINEAR);
  const cv::Mat m = small >= 0.5f;  // CV_8UC1 0/255
  std::lock_guard<std::mutex> lock(mutex_);
  return masks_.emplace(key, m).first->second;
}

cv::Mat MultiviewSupervision::distance_transform(int frame, int v) const {
  const std::pair<int, int> key{frame, v};
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto it = dt_.find(key);
    if (it != dt_.end()) return it->second;
  }
  const cv::Mat dt = capture::distance_transform(mask(frame, v));
  std::lock_guard<std::mutex> lock(mutex_);
  return dt_.emplace(key, dt).first->second;
}

}  // namespace weft::capture
