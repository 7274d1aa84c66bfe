#include "capture/training/silhouette_rays.h"

#include <opencv2/calib3d.hpp>

#include <limits>

#include "capture/deformation/losses.h"
#include "graph/error.h"

namespace weft::capture {

std::vector<Eigen::Vector2d> mask_contour(const cv::Mat& mask) {
  WEFT_CHECK(mask.type() == CV_8UC1, "mask_contour: expected an 8-bit single-channel mask");
  std::vector<Eigen::Vector2d> contour;
  const int h = mask.rows, w = mask.cols;
  auto background = [&](int y, int x) { return y < 0 || y >= h || x < 0 || x >= w || mask.at<uint8_t>(y, x) == 0; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (!background(y, x) &&
          (background(y - 1, x) || background(y + 1, x) || background(y, x - 1) || background(y, x + 1)))
        contour.emplace_back(x, y);
  return contour;
}

namespace {

// The unit direction (world) of the camera ray through pixel p, distortion undone.
Eigen::Vector3d ray_direction(const Camera& camera, const Eigen::Vector2d& p) {
  Eigen::Vector3d normalised;
  if (camera.dist.isZero()) {
    normalised = camera.K.inverse() * Eigen::Vector3d(p.x(), p.y(), 1.0);
  } else {
    cv::Mat K(3, 3, CV_64F), dist(1, 5, CV_64F);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) K.at<double>(r, c) = camera.K(r, c);
    for (int i = 0; i < 5; ++i) dist.at<double>(0, i) = camera.dist(i);
    std::vector<cv::Point2d> in{{p.x(), p.y()}}, out;
    cv::undistortPoints(in, out, K, dist);
    normalised = Eigen::Vector3d(out[0].x, out[0].y, 1.0);
  }
  return (camera.R.transpose() * normalised).normalized();
}

}  // namespace

std::vector<physics::RayTarget> silhouette_rays(const MultiviewSupervision& sup, int frame, const Vertices& body,
                                                const Vertices& cloth, const Faces& faces,
                                                const SilhouetteRayOptions& o) {
  const int64_t nb = body.rows();
  WEFT_CHECK(faces.rows() == 0 || faces.maxCoeff() < nb + cloth.rows(), "silhouette_rays: faces index past the ",
             nb + cloth.rows(), " vertices of body and cloth");
  Vertices all(nb + cloth.rows(), 3);
  all << body, cloth;
  std::vector<physics::RayTarget> rays;
  for (int v = 0; v < sup.views(); ++v) {
    const Camera& cam = sup.silhouette_camera(frame, v);
    const std::vector<Eigen::Vector2d> contour = mask_contour(sup.mask(frame, v));
    if (contour.empty()) continue;  // nobody in this view
    const Eigen::Vector3d origin = cam.center() * o.metres_per_unit;
    for (int i : boundary_vertices(cam, all, faces)) {
      if (i < nb) continue;
      const Eigen::Vector3d x = all.row(i).transpose();
      if (cam.depth(x) <= 0) continue;
      const Eigen::Vector2d p = cam.project(x);
      double best = std::numeric_limits<double>::infinity();
      Eigen::Vector2d nearest;
      for (const Eigen::Vector2d& q : contour)
        if (const double d = (q - p).squaredNorm(); d < best) best = d, nearest = q;
      if (std::sqrt(best) > o.max_pixels) continue;
      rays.push_back({int(i - nb), origin, ray_direction(cam, nearest)});
    }
  }
  return rays;
}

}  // namespace weft::capture
