#pragma once
// The detector's keypoint codec (the one place that maps keypoints to heatmaps and back;
// the network and its losses never decode): BODY_25 keypoints in crop pixels ↔ one
// heatmap per keypoint on a grid of `stride`-pixel cells over the input_size² crop.
//
// Geometry (the crop's pixel convention, capture/dataset/synthetic_dataset.h: pixel x has
// its centre at x): cell (row i, column j) covers crop pixels [stride·j, stride·j + stride)
// and its centre lies at
//     u = stride · (j + ½) − ½,   v = stride · (i + ½) − ½,
// the geometry cv::resize gives a grid scaled by `stride` (so cell centres and pixel
// centres line up as when the heatmap is resized to the crop).
// Target: a Gaussian of σ = sigma_px crop pixels around the keypoint, peak 1, one plane
// per keypoint; a keypoint with confidence 0 has an all-zero plane and weight 0.
// Decoding: the arg-max cell, refined to sub-cell precision by the parabola through the
// logarithms of the peak and its two neighbours along each axis (exact for a Gaussian);
// the confidence is the peak value clamped to [0, 1]; below min_confidence the keypoint
// is undetected, (0, 0, 0), as OpenPose writes it.
#include <opencv2/core.hpp>

#include <vector>

#include "capture/io/openpose.h"
#include "graph/tensor.h"

namespace weft::capture {

struct HeatmapCodec {
  int input_size = 128;   // crop side (pixels)
  int stride = 4;         // crop pixels per heatmap cell
  double sigma_px = 3.0;  // the target Gaussian's σ (crop pixels)
  double min_confidence = 0.1;  // decoded peaks below this are undetected
  int cells() const { return input_size / stride; }  // heatmap side
  // The crop position of cell (i, j)'s centre (pixels).
  double cell_u(double j) const { return stride * (j + 0.5) - 0.5; }
  double cell_v(double i) const { return stride * (i + 0.5) - 0.5; }
};

// Targets for keypoints [B, 25, 3] (crop pixels, confidence), float32:
// heatmaps [B, 25, H, H] (H = cells()) and weights [B, 25] (the confidences).
struct HeatmapTargets {
  Tensor heatmaps, weights;
};
HeatmapTargets encode_heatmaps(const Tensor& keypoints, const HeatmapCodec& codec);

// Sample b of heatmaps [B, 25, H, H] as keypoints in crop pixels.
Body25 decode_heatmaps(const Tensor& heatmaps, int64_t b, const HeatmapCodec& codec);

// Sample b of mask logits [B, 1, h, h] (a grid of input_size / h pixels per cell, the
// same geometry as the heatmaps) as the crop's mask (CV_32FC1 logits, input_size²,
// bilinear). A pixel is the person where the logit is above logit(threshold).
cv::Mat mask_logits_in_crop(const Tensor& mask_logits, int64_t b, int input_size);
cv::Mat threshold_mask(const cv::Mat& logits, double threshold = 0.5);  // CV_8UC1 0/255

}  // namespace weft::capture
