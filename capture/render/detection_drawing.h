#pragma once
// A person detection drawn over its frame: the mask's outline (orange) and the detected
// BODY_25 keypoints (green dots, labelled by index). What `weft detect --overlays` writes
// per frame and what `weft eval`'s report shows beside the capture when the capture read
// the model's own detections.
#include <opencv2/core.hpp>

#include "capture/io/openpose.h"

namespace weft::capture {

// `frame` CV_8UC3 BGR, `mask` CV_8UC1 of the same size (nonzero: person); keypoints in
// the frame's pixels, a confidence of 0 meaning not detected. Returns a drawn copy.
cv::Mat draw_detection(const cv::Mat& frame, const Body25& keypoints, const cv::Mat& mask);

}  // namespace weft::capture
