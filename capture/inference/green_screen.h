#pragma once
// Foreground masks by chroma keying for a person filmed in front of a green screen (the
// studio setting of the method's test sequences when no masks are given).
#include <opencv2/core.hpp>

#include "capture/inference/capture_config.h"

namespace weft::capture {

// CV_8UC1, 255 person / 0 background, of `bgr`'s size (CV_8UC3).
cv::Mat key_green_screen(const cv::Mat& bgr, const KeyingConfig& config);

}  // namespace weft::capture
