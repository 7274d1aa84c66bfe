#include "capture/render/keypoint_visibility.h"

#include <algorithm>
#include <cmath>

#include "graph/error.h"

namespace weft::capture {

bool in_camera_image(const Camera& camera, const Eigen::Vector2d& uv) {
  return uv.x() >= -0.5 && uv.x() < camera.width - 0.5 && uv.y() >= -0.5 && uv.y() < camera.height - 0.5;
}

std::array<KeypointVisibility, kBody25Count> keypoint_visibility(const Camera& camera, const Vertices& body25_world,
                                                                 const cv::Mat& depth, double depth_tolerance) {
  if (body25_world.rows() != kBody25Count || body25_world.cols() != 3)
    fail("keypoint_visibility: expected 25×3 BODY_25 world positions, got ", body25_world.rows(), "×",
         body25_world.cols());
  if (!(depth_tolerance >= 0)) fail("keypoint_visibility: the depth tolerance must be ≥ 0, got ", depth_tolerance);
  if (!depth.empty() && (depth.type() != CV_32FC1 || depth.cols != camera.width || depth.rows != camera.height))
    fail("keypoint_visibility: camera '", camera.name, "': expected a CV_32FC1 depth image of ", camera.width, "x",
         camera.height, " (render()'s depth), got type ", depth.type(), " of ", depth.cols, "x", depth.rows);
  std::array<KeypointVisibility, kBody25Count> out;
  for (int k = 0; k < kBody25Count; ++k) {
    if (!body25_world.row(k).allFinite()) {
      out[k] = KeypointVisibility::unmapped;
      continue;
    }
    const Eigen::Vector3d X = body25_world.row(k).transpose();
    const double z = camera.depth(X);
    const Eigen::Vector2d uv = camera.project(X);
    if (!(z > 0) || !in_camera_image(camera, uv)) {
      out[k] = KeypointVisibility::outside;
      continue;
    }
    out[k] = KeypointVisibility::visible;
    if (depth.empty()) continue;
    // The pixel whose centre is nearest: pixel (x, y) covers [x − ½, x + ½).
    const int x = std::clamp(static_cast<int>(std::floor(uv.x() + 0.5)), 0, camera.width - 1);
    const int y = std::clamp(static_cast<int>(std::floor(uv.y() + 0.5)), 0, camera.height - 1);
    const double surface = depth.at<float>(y, x);
    if (surface > 0 && z - surface > depth_tolerance) out[k] = KeypointVisibility::occluded;
  }
  return out;
}

}  // namespace weft::capture
