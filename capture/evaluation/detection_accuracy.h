#pragma once
// How well predicted keypoints and masks (`weft detect`'s folder: keypoints/<name>_keypoints.json,
// masks/<name>.png) match one view of a dataset: the mask IoU against the rendered masks,
// and each BODY_25 keypoint's pixel error against the true keypoint (the character posed
// by gt/pose.motion, projected by the frame's camera) and against the dataset's own
// detections (the labels the detector was trained on). PCK counts a keypoint correct
// within 5 % of the person's height (the true mask's box height in that frame).
// A keypoint the prediction leaves undetected while the truth has it counts as wrong at
// any threshold and as an infinite error (medians include it). Every true keypoint in the
// image counts, those hidden behind the body too; the figures over the visible ones alone
// (the studio's occlusion rule, capture/render/keypoint_visibility.h, on a depth render of
// the true body and garment) are given beside them.
#include <array>
#include <map>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "capture/character/character.h"
#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/io/camera.h"
#include "capture/io/openpose.h"

namespace weft::capture {

// The IoU of two masks (nonzero = person; one size); 1 when both are empty.
double mask_iou(const cv::Mat& a, const cv::Mat& b);
// The median of `values` (+inf counts; NaN for none).
double median_of(std::vector<double> values);
// The fraction of errors[i] ≤ thresholds[i] (NaN for none).
double fraction_within(const std::vector<double>& errors, const std::vector<double>& thresholds);

struct DetectionAccuracy {
  std::string data, view, detections;
  std::vector<std::string> frames;  // names
  std::vector<double> iou;          // per frame
  // Per keypoint (BODY_25 order), one entry per frame where the reference has it: the
  // error in frame pixels and 5 % of the person's height there.
  std::array<std::vector<double>, kBody25Count> truth_error_px, truth_threshold_px;
  std::array<std::vector<char>, kBody25Count> truth_visible;  // beside truth_error_px: not occluded
  std::array<std::vector<double>, kBody25Count> label_error_px, label_threshold_px;
  double pck_fraction = 0.05;
};

// Reads the predictions of `detections` for every frame of `view` in the dataset `data`
// (all splits), or only for the frame ids `frames` when given (e.g. the frames a capture
// has); errors name the missing file or a frame the dataset lacks.
DetectionAccuracy measure_detections(const std::string& detections, const std::string& data, const std::string& view,
                                     const std::vector<int>& frames = {});

// The dataset's truth that measure needs, for a caller that has read it already (weft eval):
// the posed character's keypoints from `motion`, the cameras by name (the files' paths for errors).
struct DetectionTruth {
  const DatasetInfo& info;
  const Character& character;
  const Motion& motion;
  const std::string& motion_path;
  const std::map<std::string, Camera>& cameras;
  const std::string& cameras_path;
};
DetectionAccuracy measure_detections(const std::string& detections, const DetectionTruth& truth,
                                     const std::string& view, const std::vector<int>& frames);

// The headline figures, over all frames and keypoints (NaN where nothing was measured).
struct DetectionFigures {
  double mask_iou_median = 0, mask_iou_min = 0;
  double truth_median_px = 0, truth_pck = 0;  // against the true keypoints
  double label_median_px = 0, label_pck = 0;  // against the dataset's detections
  size_t truth_keypoints = 0;
  double visible_median_px = 0, visible_pck = 0;  // against the true keypoints the camera sees
  size_t visible_keypoints = 0;
};
DetectionFigures detection_figures(const DetectionAccuracy& a);

// detection_accuracy.json: medians, PCK and counts over all keypoints and per keypoint.
std::string detection_accuracy_json(const DetectionAccuracy& a);
// Lines for the log: the overall figures (mask IoU; keypoint medians and PCK)...
std::vector<std::string> detection_summary_lines(const DetectionAccuracy& a);
// ...and those followed by a table per keypoint.
std::vector<std::string> detection_accuracy_lines(const DetectionAccuracy& a);

}  // namespace weft::capture
