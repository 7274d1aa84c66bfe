#pragma once
// Finding the person in a whole frame with the detector (person_detector.h), the way
// `weft detect`, `weft infer` and `weft adapt` use it without given keypoints or masks:
//   1. a coarse pass on the square around the whole frame (the frame padded with black,
//      resized to the detector's input size), which gives a rough mask;
//   2. the crop the dataset reader would cut around that mask (choose_crop with the
//      detector's margin), and the fine pass on it: the keypoints and the mask.
// Both masks keep only their largest connected region. Pixels of the frame outside the
// fine crop are background.
#include <opencv2/core.hpp>

#include <vector>

#include "capture/dataset/synthetic_dataset.h"
#include "capture/detection/keypoint_heatmaps.h"
#include "capture/detection/person_detector.h"

namespace weft::capture {

struct PersonDetection {
  Body25 keypoints = Body25::Zero();  // full-frame pixels, confidence; (0, 0, 0) undetected
  cv::Mat mask;                       // CV_8UC1 0/255, the frame's size
  CropWindow coarse, crop;            // the two passes' squares
  bool found = false;                 // the coarse pass saw a person (else the fine pass ran on the whole frame)
};

// The codec the detector's heatmaps decode with.
HeatmapCodec detector_codec(const DetectorConfig& config);

// Detects the person in each frame (CV_8UC3 BGR, any size; the frames of one call may
// differ in size), in evaluation mode and without a graph; frames run as one batch per
// pass, so callers bound the batch.
std::vector<PersonDetection> detect_people(PersonDetector& detector, const std::vector<cv::Mat>& frames);

// A crop's mask logits (CV_32FC1, input_size², mask_logits_in_crop) placed in a frame of
// width × height: 0/255 where the logit is above logit(threshold), 0 outside the crop.
cv::Mat crop_mask_in_frame(const cv::Mat& crop_logits, const CropWindow& crop, int width, int height,
                           double threshold = 0.5);
// Only the largest 8-connected region of a 0/255 mask (all zero stays all zero).
cv::Mat largest_region(const cv::Mat& mask);

}  // namespace weft::capture
