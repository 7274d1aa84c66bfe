#include "capture/render/detection_drawing.h"

#include <opencv2/imgproc.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "graph/error.h"

namespace weft::capture {

cv::Mat draw_detection(const cv::Mat& frame, const Body25& keypoints, const cv::Mat& mask) {
  WEFT_CHECK(frame.type() == CV_8UC3 && mask.type() == CV_8UC1 && frame.size() == mask.size(),
             "draw_detection: expected a BGR frame and its 8-bit mask of the same size");
  cv::Mat out = frame.clone();
  std::vector<std::vector<cv::Point>> outline;
  cv::findContours(mask.clone(), outline, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  cv::drawContours(out, outline, -1, cv::Scalar(0, 140, 255), 1, cv::LINE_AA);
  for (int m = 0; m < kBody25Count; ++m) {
    if (!(keypoints(m, 2) > 0)) continue;
    const cv::Point p(int(std::lround(keypoints(m, 0))), int(std::lround(keypoints(m, 1))));
    cv::circle(out, p, 2, cv::Scalar(40, 220, 40), cv::FILLED, cv::LINE_AA);
    cv::putText(out, std::to_string(m), p + cv::Point(3, -2), cv::FONT_HERSHEY_PLAIN, 0.6, cv::Scalar(255, 255, 255), 1);
  }
  return out;
}

}  // namespace weft::capture
