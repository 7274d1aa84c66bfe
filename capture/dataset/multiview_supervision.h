#pragma once
// What supervises one frame in every view of a recording: the calibrated cameras, the
// 2D keypoint detections (full-image pixels) and the foreground masks as distance
// transforms at a reduced size. The networks read one view; the losses look at all of
// them (the method's multi-view training), so a sample's (frame, view) from the dataset
// reader is paired with this frame's supervision here.
//
// The distance transforms are of the mask padded to a square (side = max(width, height),
// extra rows or columns background) and resized to size² pixels (INTER_AREA, then
// thresholded at half coverage), so silhouette_camera() is the full camera mapped into
// that square exactly as the dataset reader's crops are (crop_camera). Masks and distance
// transforms are computed once per (frame, view) and kept (5 size² bytes); thread-safe.
#include <opencv2/core.hpp>

#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "capture/dataset/synthetic_dataset.h"

namespace weft::capture {

class MultiviewSupervision {
 public:
  // Reads cameras.yaml and every keypoint file of `frames` up front (errors name the
  // file); masks are read when first asked for.
  MultiviewSupervision(const DatasetInfo& info, const std::vector<int>& frames, int silhouette_size);

  const DatasetInfo& info() const { return info_; }
  int views() const { return static_cast<int>(info_.views.size()); }
  int silhouette_size() const { return size_; }

  // The full image's camera and keypoints of `frame` in view v (index into info().views).
  const Camera& camera(int frame, int v) const;
  const Body25& detections(int frame, int v) const;
  // The camera into the distance transform's size² pixels, and the transform itself
  // (CV_32FC1, distance in those pixels to the nearest foreground pixel).
  const Camera& silhouette_camera(int frame, int v) const;
  cv::Mat distance_transform(int frame, int v) const;
  cv::Mat mask(int frame, int v) const;  // CV_8UC1 0/255 at size²

 private:
  struct FrameData {
    std::vector<Camera> cameras, silhouette_cameras;
    std::vector<Body25> detections;
  };
  const FrameData& at(int frame) const;

  DatasetInfo info_;
  int size_;
  std::map<int, FrameData> frames_;
  mutable std::mutex mutex_;
  mutable std::map<std::pair<int, int>, cv::Mat> masks_, dt_;
};

}  // namespace weft::capture
