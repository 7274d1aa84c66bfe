#pragma once
// The global translation of a capture without keypoints, from the person's silhouette
// alone: the depth at which the predicted body's projected height matches the mask's
// bounding box, and the position that centres its projection on the box. The projection
// scales about the principal point as the body moves along the viewing direction, so a
// few fixed-point rounds converge; they also absorb perspective and lens distortion.
// Accurate to the extent the predicted pose explains the silhouette's extent.
#include <opencv2/core.hpp>

#include <Eigen/Core>

#include "capture/io/camera.h"
#include "geometry/mesh.h"

namespace weft::capture {

// relative: the body placed with translation 0 (world orientation, character units);
// box: the mask's bounding box (pixels). Returns t such that relative + t projects onto it.
Eigen::Vector3d translation_from_silhouette(const Camera& camera, const Vertices& relative, const cv::Rect& box);

}  // namespace weft::capture
