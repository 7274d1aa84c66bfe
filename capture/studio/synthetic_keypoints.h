#pragma once
// Synthetic 2D keypoints: BODY_25 joints of a posed character projected into a camera,
// then made to look like a detector's output (OpenPose). Two error models:
// - gaussian (the default, and every dataset made before the openpose model): a fixed pixel
//   noise, lower confidence where the joint is hidden by the body, random dropouts.
// - openpose: what a bottom-up detector gets wrong (docs/DATASET.md, "Detector error
//   model"): a position error proportional to the person's size in the image, per
//   keypoint as in COCO's annotator spread; left/right swaps, more often in side views;
//   more dropouts under occlusion; a confidence that falls with the drawn error.
//
// Occlusion: the rule of capture/render/keypoint_visibility.h with the config's
// depth_tolerance_m (0.15 m). On the default character in its rest pose, seen by the
// 8-view rig, joints facing a camera are at most 0.13 m under the surface, the far
// shoulder, hip and knee of a side view 0.26–0.71 m, the nose from behind 0.18 m; the
// pelvis centre seen from the side (0.16 m) counts as hidden.
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <string>
#include <utility>

#include "capture/io/camera.h"
#include "geometry/mesh.h"
#include "capture/io/openpose.h"
#include "capture/io/portable_random.h"  // mix_seed(dataset seed, view, frame)
#include "capture/render/keypoint_visibility.h"

namespace weft::capture {

enum class KeypointErrorModel { gaussian, openpose };

struct KeypointNoiseConfig {
  KeypointErrorModel model = KeypointErrorModel::gaussian;
  double noise_px = 2.0;               // gaussian: std dev of the pixel noise, per axis
  double dropout = 0.05;               // probability a visible keypoint is reported undetected
  double occluded_dropout = 0.05;      // the same for an occluded keypoint
  double visible_confidence = 0.9;     // reported confidence of a visible keypoint (openpose: at zero error)
  double occluded_confidence = 0.3;    // … of an occluded one
  double confidence_jitter = 0.05;     // confidences vary uniformly by ± this (kept in (0, 1])
  double depth_tolerance_m = kOcclusionDepthToleranceM;  // occlusion rule (see above), metres
  double metres_per_unit = 1.0;        // character units: 1 (metres), 0.001 (millimetres)

  // openpose only. Keypoint k's error is Gaussian with an rms length (Euclidean, pixels) of
  // scale_error_multiple × σ_k × s: σ_k is COCO's per-keypoint annotator spread relative to
  // the person's scale (kBody25CocoSigma), s = person_scale_px(). 1 would be a human
  // annotator; 1.5 is an assumption for OpenPose (docs/DATASET.md gives the reasoning).
  double scale_error_multiple = 1.5;
  double swap_probability = 0.03;      // per left/right pair seen face on: the two trade places
  double swap_probability_side = 0.10; // … seen edge on (the pair foreshortened to a point)
  double swap_confidence_scale = 0.5;  // a swapped pair's confidences are multiplied by this
  double confidence_falloff = 2.0;     // confidence × exp(−½ (e / falloff)²), e = error / per-axis σ

  // The openpose model's defaults: the fields above, plus occluded_dropout 0.3.
  static KeypointNoiseConfig openpose();
};

// COCO's per-keypoint σ_i (cocodataset.org keypoint evaluation, "Tuning OKS": σ_i² =
// E[d_i² / s²] over 5,000 twice-annotated val images, d the Euclidean distance between two
// annotators, s = √(segment area); nose .026, eyes .025, ears .035, shoulders .079, elbows
// .072, wrists .062, hips .107, knees .087, ankles .089), mapped onto BODY_25: Neck takes
// the shoulders' value, MidHip the hips', the toes and heels the ankles'.
extern const std::array<double, kBody25Count> kBody25CocoSigma;

// BODY_25's left/right pairs (right, left): shoulder, elbow, wrist, hip, knee, ankle, eye,
// ear, big toe, small toe, heel.
extern const std::array<std::pair<int, int>, 11> kBody25LeftRightPairs;

// The person's scale in the image, pixels, as COCO's s = √(segment area): the square root
// of the number of foreground pixels of `depth` (render()'s depth, the person's mask); with
// an empty depth image, the square root of the area of the box around the keypoints that
// project into the image (0 with fewer than two).
double person_scale_px(const Camera& camera, const Vertices& body25_world, const cv::Mat& depth);

// Noise-free projection: pixel coordinates and confidence 1 for mapped keypoints in front
// of the camera whose pixel lies in the image ([−½, width − ½) × [−½, height − ½), the
// renderer's pixel convention); 0, 0, 0 otherwise. `body25_world` is 25×3 (world units),
// NaN rows for unmapped keypoints.
Body25 project_keypoints(const Camera& camera, const Vertices& body25_world);

// Classifies each keypoint by keypoint_visibility() with the config's depth_tolerance_m.
// `depth` is render()'s depth for this camera (CV_32FC1, camera z in world units, 0 =
// background, the camera's size); an empty Mat skips the occlusion test (every keypoint in
// the image is visible).
std::array<KeypointVisibility, kBody25Count> keypoint_visibility(const Camera& camera, const Vertices& body25_world,
                                                                 const cv::Mat& depth,
                                                                 const KeypointNoiseConfig& config);

// A detector-like Body25: visible and occluded keypoints get the projection plus Gaussian
// noise and a confidence; dropouts, unmapped keypoints, keypoints outside the image and
// noisy positions that leave the image are 0, 0, 0.
// - gaussian: noise_px per axis, confidence visible_/occluded_confidence ± jitter.
// - openpose: per-axis σ = scale_error_multiple × kBody25CocoSigma[k] × s / √2 (so the rms
//   Euclidean error is multiple × σ_k × s), confidence = base × exp(−½ (e / falloff)²) ±
//   jitter with e = |error| / σ; then each left/right pair trades rows (positions and
//   confidences, a lone detection moving to the other side's slot) with a probability
//   from swap_probability (face on) to swap_probability_side (edge on, by how much the
//   pair is foreshortened in the image), its confidences × swap_confidence_scale.
// Deterministic per seed on every platform; keypoint k draws from its own stream
// mix_seed(seed, k, 0) (left/right pair p from mix_seed(seed, 25 + p, 0)), so one
// keypoint's fate does not shift another's noise. Throws weft::Error naming the field for
// an invalid config, or for a depth image of the wrong type or size.
Body25 synthesize_keypoints(const Camera& camera, const Vertices& body25_world, const cv::Mat& depth,
                            const KeypointNoiseConfig& config, uint64_t seed);

// Throws weft::Error naming the field unless probabilities, confidences and the swap's
// confidence scale are in [0, 1], noise, tolerance and the error multiple are ≥ 0,
// confidence_falloff and metres_per_unit > 0.
void validate_keypoint_noise(const KeypointNoiseConfig& config, const std::string& what);

}  // namespace weft::capture
