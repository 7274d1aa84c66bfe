#pragma once
// Synthetic 2D keypoints: BODY_25 joints of a posed character projected into a camera,
// then made to look like a detector's output (OpenPose): Gaussian pixel noise, lower
// confidence where the joint is hidden by the body, and random dropouts.
//
// Occlusion. Keypoints are joint centres and sit inside the body, so the rendered
// surface at a keypoint's pixel is always somewhat in front of it. A keypoint counts as
// occluded when that surface is more than `depth_tolerance_m` (about the half-thickness of
// the torso, 0.15 m) in front of it: a joint facing the camera has only its own flesh in
// front and stays visible, a joint behind the torso, the head or the other leg has a whole
// body part in front and is occluded. On the default character in its rest pose, seen by
// the 8-view rig, joints facing a camera are at most 0.13 m under the surface, the far
// shoulder, hip and knee of a side view 0.26–0.71 m, the nose from behind 0.18 m; the
// pelvis centre seen from the side (0.16 m) counts as hidden. Where nothing is rendered
// at the pixel (depth 0, e.g. just outside a thin limb's silhouette) the keypoint is
// visible.
#include <opencv2/core.hpp>

#include <array>
#include <cstdint>
#include <string>

#include "capture/io/camera.h"
#include "geometry/mesh.h"
#include "capture/io/openpose.h"
#include "capture/io/portable_random.h"  // mix_seed(dataset seed, view, frame)

namespace weft::capture {

struct KeypointNoiseConfig {
  double noise_px = 2.0;               // std dev of the Gaussian pixel noise, per axis
  double dropout = 0.05;               // probability a visible keypoint is reported undetected
  double occluded_dropout = 0.05;      // the same for an occluded keypoint
  double visible_confidence = 0.9;     // reported confidence of a visible keypoint
  double occluded_confidence = 0.3;    // … of an occluded one
  double confidence_jitter = 0.05;     // confidences vary uniformly by ± this (kept in (0, 1])
  double depth_tolerance_m = 0.15;     // occlusion rule (see above), metres
  double metres_per_unit = 1.0;        // character units: 1 (metres), 0.001 (millimetres)
};

enum class KeypointVisibility {
  unmapped,  // the character has no such keypoint (a NaN row)
  outside,   // behind the camera or projects outside the image
  occluded,  // in the image, hidden behind the body
  visible,
};

// Noise-free projection: pixel coordinates and confidence 1 for mapped keypoints in front
// of the camera whose pixel lies in the image ([−½, width − ½) × [−½, height − ½), the
// renderer's pixel convention); 0, 0, 0 otherwise. `body25_world` is 25×3 (world units),
// NaN rows for unmapped keypoints.
Body25 project_keypoints(const Camera& camera, const Vertices& body25_world);

// Classifies each keypoint. `depth` is render()'s depth for this camera (CV_32FC1, camera
// z in world units, 0 = background, the camera's size); an empty Mat skips the occlusion
// test (every keypoint in the image is visible).
std::array<KeypointVisibility, kBody25Count> keypoint_visibility(const Camera& camera, const Vertices& body25_world,
                                                                 const cv::Mat& depth,
                                                                 const KeypointNoiseConfig& config);

// A detector-like Body25: visible and occluded keypoints get the projection plus Gaussian
// noise (noise_px per axis) and their confidence ± jitter; dropouts, unmapped keypoints,
// keypoints outside the image and noisy positions that leave the image are 0, 0, 0.
// Deterministic per seed on every platform; keypoint k draws from its own stream
// mix_seed(seed, k, 0), so one keypoint's fate does not shift another's noise. Throws
// weft::Error naming the field for an invalid config, or for a depth image of the wrong
// type or size.
Body25 synthesize_keypoints(const Camera& camera, const Vertices& body25_world, const cv::Mat& depth,
                            const KeypointNoiseConfig& config, uint64_t seed);

// Throws weft::Error naming the field unless probabilities and confidences are in [0, 1],
// noise and tolerance are ≥ 0 and metres_per_unit > 0.
void validate_keypoint_noise(const KeypointNoiseConfig& config, const std::string& what);

}  // namespace weft::capture
