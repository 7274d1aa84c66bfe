#include "capture/inference/silhouette_translation.h"

#include <algorithm>

#include "graph/error.h"

namespace weft::capture {

Eigen::Vector3d translation_from_silhouette(const Camera& cam, const Vertices& relative, const cv::Rect& box) {
  WEFT_CHECK(relative.rows() > 0 && relative.allFinite(), "translation_from_silhouette: no or non-finite vertices");
  WEFT_CHECK(box.width > 0 && box.height > 0, "translation_from_silhouette: empty mask box");
  const Eigen::Vector3d centroid = relative.colwise().mean().transpose();
  const int stride = std::max<int>(1, int(relative.rows()) / 2000);
  Vertices sample(relative.rows() / stride, 3);
  for (Eigen::Index i = 0; i < sample.rows(); ++i) sample.row(i) = relative.row(i * stride);
  // Start: the centroid on the ray through the box centre, at the depth where the body's
  // vertical extent (camera y) spans the box's height.
  Eigen::VectorXd ys = ((cam.R * sample.transpose()).row(1)).transpose();
  const double height = std::max(1e-9, ys.maxCoeff() - ys.minCoeff());
  const double depth = cam.K(1, 1) * height / std::max(1, box.height);
  const Eigen::Vector3d ray = cam.K.inverse() * Eigen::Vector3d(box.x + 0.5 * (box.width - 1), box.y + 0.5 * (box.height - 1), 1);
  Eigen::Vector3d q = ray * depth;  // camera coordinates of the centroid
  for (int round = 0; round < 6; ++round) {
    const Eigen::Vector3d t = cam.R.transpose() * (q - cam.t) - centroid;
    const Points2 uv = project_points(cam, Vertices(sample.rowwise() + t.transpose()));
    const double u0 = uv.col(0).minCoeff(), u1 = uv.col(0).maxCoeff(), v0 = uv.col(1).minCoeff(),
                 v1 = uv.col(1).maxCoeff();
    const double ratio = std::max(1e-9, v1 - v0 + 1) / std::max(1, box.height);
    q *= ratio;  // about the camera centre: the projection scales about the principal point
    const double du = (box.x + 0.5 * (box.width - 1)) - (cam.K(0, 2) + (0.5 * (u0 + u1) - cam.K(0, 2)) / ratio);
    const double dv = (box.y + 0.5 * (box.height - 1)) - (cam.K(1, 2) + (0.5 * (v0 + v1) - cam.K(1, 2)) / ratio);
    q.x() += du * q.z() / cam.K(0, 0);
    q.y() += dv * q.z() / cam.K(1, 1);
  }
  return cam.R.transpose() * (q - cam.t) - centroid;
}

}  // namespace weft::capture
