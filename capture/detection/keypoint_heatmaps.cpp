#include "capture/detection/keypoint_heatmaps.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "graph/error.h"

namespace weft::capture {

namespace {

void check_codec(const HeatmapCodec& c) {
  WEFT_CHECK(c.stride >= 1 && c.input_size >= c.stride && c.input_size % c.stride == 0 && c.sigma_px > 0,
             "HeatmapCodec: input_size ", c.input_size, " must be a positive multiple of stride ", c.stride,
             ", sigma_px ", c.sigma_px, " positive");
}

// The offset (in cells, within ±½) of a peak from its centre cell, from the values on
// either side: the vertex of the parabola through their logarithms (a Gaussian's is one).
double sub_cell(double before, double peak, double after) {
  constexpr double kFloor = 1e-6;
  if (!(before > kFloor && peak > kFloor && after > kFloor)) return 0;
  const double a = std::log(before), c = std::log(peak), b = std::log(after);
  const double curvature = a - 2 * c + b;
  if (!(curvature < 0)) return 0;
  return std::clamp(0.5 * (a - b) / curvature, -0.5, 0.5);
}

}  // namespace

HeatmapTargets encode_heatmaps(const Tensor& keypoints, const HeatmapCodec& codec) {
  check_codec(codec);
  WEFT_CHECK(keypoints.dim() == 3 && keypoints.size(1) == kBody25Count && keypoints.size(2) == 3 &&
                 keypoints.dtype() == DType::F32,
             "encode_heatmaps: expected float32 keypoints [B, 25, 3], got ", shape_str(keypoints.shape()));
  const int64_t B = keypoints.size(0), H = codec.cells();
  HeatmapTargets t;
  t.heatmaps = Tensor::zeros({B, kBody25Count, H, H});
  t.weights = Tensor::zeros({B, kBody25Count});
  const Tensor& k = keypoints;
  const float* kp = k.data<float>();
  float* maps = t.heatmaps.data<float>();
  float* weights = t.weights.data<float>();
  const double inv = 1.0 / (2 * codec.sigma_px * codec.sigma_px);
  for (int64_t b = 0; b < B; ++b)
    for (int64_t m = 0; m < kBody25Count; ++m) {
      const float* row = kp + (b * kBody25Count + m) * 3;
      if (!(row[2] > 0)) continue;
      weights[b * kBody25Count + m] = std::min(1.0f, row[2]);
      float* plane = maps + (b * kBody25Count + m) * H * H;
      for (int64_t i = 0; i < H; ++i) {
        const double dv = codec.cell_v(double(i)) - row[1];
        for (int64_t j = 0; j < H; ++j) {
          const double du = codec.cell_u(double(j)) - row[0];
          plane[i * H + j] = float(std::exp(-(du * du + dv * dv) * inv));
        }
      }
    }
  return t;
}

Body25 decode_heatmaps(const Tensor& heatmaps, int64_t b, const HeatmapCodec& codec) {
  check_codec(codec);
  const int64_t H = codec.cells();
  WEFT_CHECK(heatmaps.dim() == 4 && heatmaps.size(1) == kBody25Count && heatmaps.size(2) == H &&
                 heatmaps.size(3) == H && heatmaps.dtype() == DType::F32 && b >= 0 && b < heatmaps.size(0),
             "decode_heatmaps: expected float32 heatmaps [B, 25, ", H, ", ", H, "] and b < B, got ",
             shape_str(heatmaps.shape()), " and ", b);
  const Tensor& hm = heatmaps;
  Body25 out = Body25::Zero();
  for (int m = 0; m < kBody25Count; ++m) {
    const float* p = hm.data<float>() + (b * kBody25Count + m) * H * H;
    const int64_t best = std::max_element(p, p + H * H) - p;
    const int64_t i = best / H, j = best % H;
    const double peak = p[best];
    if (!(peak >= codec.min_confidence)) continue;  // undetected: 0, 0, 0
    const double dj = j > 0 && j + 1 < H ? sub_cell(p[best - 1], peak, p[best + 1]) : 0;
    const double di = i > 0 && i + 1 < H ? sub_cell(p[best - H], peak, p[best + H]) : 0;
    out.row(m) << codec.cell_u(double(j) + dj), codec.cell_v(double(i) + di), std::min(1.0, peak);
  }
  return out;
}

cv::Mat mask_logits_in_crop(const Tensor& mask_logits, int64_t b, int input_size) {
  WEFT_CHECK(mask_logits.dim() == 4 && mask_logits.size(1) == 1 && mask_logits.size(2) == mask_logits.size(3) &&
                 mask_logits.dtype() == DType::F32 && b >= 0 && b < mask_logits.size(0) &&
                 input_size % mask_logits.size(2) == 0,
             "mask_logits_in_crop: expected float32 logits [B, 1, h, h] with h dividing ", input_size, " and b < B, got ",
             shape_str(mask_logits.shape()), " and ", b);
  const int h = int(mask_logits.size(2));
  const Tensor& m = mask_logits;
  const cv::Mat grid(h, h, CV_32FC1, const_cast<float*>(m.data<float>() + b * h * h));
  cv::Mat out;
  if (h == input_size) return grid.clone();
  cv::resize(grid, out, cv::Size(input_size, input_size), 0, 0, cv::INTER_LINEAR);
  return out;
}

cv::Mat threshold_mask(const cv::Mat& logits, double threshold) {
  WEFT_CHECK(logits.type() == CV_32FC1 && threshold > 0 && threshold < 1,
             "threshold_mask: expected CV_32FC1 logits and a threshold in (0, 1), got ", threshold);
  cv::Mat out;
  cv::threshold(logits, out, std::log(threshold / (1 - threshold)), 255, cv::THRESH_BINARY);
  out.convertTo(out, CV_8UC1);
  return out;
}

}  // namespace weft::capture
