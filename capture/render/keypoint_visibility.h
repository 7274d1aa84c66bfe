#pragma once
// Which BODY_25 keypoints a camera sees: the occlusion rule the synthetic studio's detections
// are made with (capture/studio/synthetic_keypoints.h) and that `weft detect --truth` and
// `weft eval` measure detections by (capture/evaluation/detection_accuracy.h).
//
// Keypoints are joint centres and sit inside the body, so the rendered surface at a
// keypoint's pixel is always somewhat in front of it. A keypoint counts as occluded when
// that surface is more than a depth tolerance (about the half-thickness of the torso,
// 0.15 m) in front of it: a joint facing the camera has only its own flesh in front and
// stays visible, a joint behind the torso, the head or the other leg has a whole body part
// in front and is occluded. Where nothing is rendered at the pixel (depth 0, e.g. just
// outside a thin limb's silhouette) the keypoint is visible.
#include <array>

#include <opencv2/core.hpp>

#include "capture/io/camera.h"
#include "capture/io/openpose.h"
#include "geometry/mesh.h"

namespace weft::capture {

// The synthetic studio's depth tolerance, metres: about the torso's half-thickness.
constexpr double kOcclusionDepthToleranceM = 0.15;

enum class KeypointVisibility {
  unmapped,  // the character has no such keypoint (a NaN row)
  outside,   // behind the camera or projects outside the image
  occluded,  // in the image, hidden behind the body
  visible,
};

// True when pixel coordinates `uv` lie in the camera's image ([−½, width − ½) ×
// [−½, height − ½), the renderer's pixel convention).
bool in_camera_image(const Camera& camera, const Eigen::Vector2d& uv);

// Classifies each keypoint of `body25_world` (25×3, world units, NaN rows for unmapped
// keypoints). `depth` is render()'s depth for this camera (CV_32FC1, camera z in world
// units, 0 = background, the camera's size); an empty Mat skips the occlusion test (every
// keypoint in the image is visible). `depth_tolerance` is in world units. Throws
// weft::Error for a wrong keypoint array, depth image or a negative tolerance.
std::array<KeypointVisibility, kBody25Count> keypoint_visibility(const Camera& camera, const Vertices& body25_world,
                                                                 const cv::Mat& depth, double depth_tolerance);

}  // namespace weft::capture
