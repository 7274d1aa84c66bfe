#include "capture/detection/person_detection.h"

#include <opencv2/imgproc.hpp>

#include "graph/autograd.h"
#include "graph/error.h"

namespace weft::capture {

HeatmapCodec detector_codec(const DetectorConfig& config) {
  HeatmapCodec c;
  c.input_size = config.input_size;
  c.stride = DetectorConfig::kHeatmapStride;
  c.sigma_px = config.sigma_px;
  return c;
}

cv::Mat crop_mask_in_frame(const cv::Mat& crop_logits, const CropWindow& crop, int width, int height,
                           double threshold) {
  WEFT_CHECK(crop_logits.type() == CV_32FC1 && width > 0 && height > 0 && crop.scale > 0,
             "crop_mask_in_frame: expected CV_32FC1 logits, a crop and a frame size");
  // Crop pixel u' = scale (u − x0), so frame pixel u = u' / scale + x0.
  const cv::Matx23d crop_to_frame(1 / crop.scale, 0, crop.x0, 0, 1 / crop.scale, crop.y0);
  cv::Mat logits;
  cv::warpAffine(crop_logits, logits, crop_to_frame, cv::Size(width, height), cv::INTER_LINEAR, cv::BORDER_CONSTANT,
                 cv::Scalar(-100.0));
  return threshold_mask(logits, threshold);
}

cv::Mat largest_region(const cv::Mat& mask) {
  WEFT_CHECK(mask.type() == CV_8UC1, "largest_region: expected an 8-bit mask");
  cv::Mat labels, stats, centroids;
  const int n = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  if (n <= 2) return mask.clone();  // background and at most one region
  int best = 1;
  for (int i = 2; i < n; ++i)
    if (stats.at<int>(i, cv::CC_STAT_AREA) > stats.at<int>(best, cv::CC_STAT_AREA)) best = i;
  cv::Mat out = labels == best;  // 0/255
  return out;
}

namespace {

// The detector on the frames, each cut as prepare_sample cuts it around `masks` (an empty
// mask: the whole frame), in one batch.
struct Pass {
  std::vector<Sample> samples;
  DetectorOutput out;
};
Pass run_pass(PersonDetector& detector, const std::vector<cv::Mat>& frames, const std::vector<cv::Mat>& masks) {
  const DetectorConfig& c = detector.config();
  DatasetOptions o;
  o.input_size = c.input_size;
  o.margin = c.margin;
  Pass p;
  for (size_t i = 0; i < frames.size(); ++i) {
    Camera camera;  // the crop's geometry is all the pass needs of it
    camera.width = frames[i].cols;
    camera.height = frames[i].rows;
    p.samples.push_back(prepare_sample(frames[i], masks[i], Body25::Zero(), camera, o));
  }
  const Batch batch = make_batch(p.samples);
  p.out = detector.run(batch.images);
  return p;
}

}  // namespace

std::vector<PersonDetection> detect_people(PersonDetector& detector, const std::vector<cv::Mat>& frames) {
  std::vector<PersonDetection> result(frames.size());
  if (frames.empty()) return result;
  for (const cv::Mat& f : frames)
    WEFT_CHECK(f.type() == CV_8UC3 && !f.empty(), "detect_people: expected 8-bit BGR frames");
  const bool was_training = detector.is_training();
  detector.eval();
  NoGradGuard no_grad;
  const DetectorConfig& c = detector.config();
  const HeatmapCodec codec = detector_codec(c);

  std::vector<cv::Mat> empty, coarse_masks;
  for (const cv::Mat& f : frames) empty.push_back(cv::Mat::zeros(f.size(), CV_8UC1));
  const Pass coarse = run_pass(detector, frames, empty);
  for (size_t i = 0; i < frames.size(); ++i) {
    const cv::Mat logits = mask_logits_in_crop(coarse.out.mask_logits, int64_t(i), c.input_size);
    coarse_masks.push_back(largest_region(crop_mask_in_frame(logits, coarse.samples[i].crop, frames[i].cols,
                                                             frames[i].rows)));
    result[i].coarse = coarse.samples[i].crop;
    result[i].found = cv::countNonZero(coarse_masks.back()) > 0;
  }
  const Pass fine = run_pass(detector, frames, coarse_masks);
  for (size_t i = 0; i < frames.size(); ++i) {
    PersonDetection& d = result[i];
    d.crop = fine.samples[i].crop;
    const cv::Mat logits = mask_logits_in_crop(fine.out.mask_logits, int64_t(i), c.input_size);
    d.mask = largest_region(crop_mask_in_frame(logits, d.crop, frames[i].cols, frames[i].rows));
    const Body25 k = decode_heatmaps(fine.out.heatmaps, int64_t(i), codec);
    for (int m = 0; m < kBody25Count; ++m)
      if (k(m, 2) > 0) d.keypoints.row(m) << k(m, 0) / d.crop.scale + d.crop.x0, k(m, 1) / d.crop.scale + d.crop.y0, k(m, 2);
  }
  detector.train(was_training);
  return result;
}

}  // namespace weft::capture
