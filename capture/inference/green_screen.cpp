#include "capture/inference/green_screen.h"

#include <opencv2/imgproc.hpp>

#include "graph/error.h"

namespace weft::capture {

namespace {

cv::Mat morphology(const cv::Mat& mask, int op, int radius) {
  if (radius <= 0) return mask;
  const cv::Mat element = cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1));
  cv::Mat out;
  cv::morphologyEx(mask, out, op, element);
  return out;
}

}  // namespace

cv::Mat key_green_screen(const cv::Mat& bgr, const KeyingConfig& c) {
  WEFT_CHECK(bgr.type() == CV_8UC3 && !bgr.empty(), "key_green_screen: expected an 8-bit BGR image");
  cv::Mat hsv, background, mask;
  cv::cvtColor(bgr, hsv, cv::COLOR_BGR2HSV);
  cv::inRange(hsv, cv::Scalar(c.hue_min, c.min_saturation, c.min_value), cv::Scalar(c.hue_max, 255, 255), background);
  cv::bitwise_not(background, mask);
  mask = morphology(morphology(mask, cv::MORPH_OPEN, c.open_px), cv::MORPH_CLOSE, c.close_px);
  if (!c.largest_component) return mask;
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  if (n <= 2) return mask;  // nothing, or one region
  int best = 1;
  for (int i = 2; i < n; ++i)
    if (stats.at<int>(i, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA)) best = i;
  cv::compare(labels, best, mask, cv::CMP_EQ);
  return mask;
}

}  // namespace weft::capture
