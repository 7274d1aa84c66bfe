#pragma once
// Reference silhouettes for the renderer and the synthetic studio, from OpenCV alone
// (cv::projectPoints with the camera's parameters), independent of capture/renderer.
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include <vector>

#include "capture/io/camera.h"
#include "geometry/mesh.h"

namespace weft::capture::testing {

// Projected vertices of `m` in `cam`, and whether each is in front of the camera.
inline std::vector<cv::Point2d> opencv_projection(const Camera& cam, const TriangleMesh& m,
                                                  std::vector<char>* in_front = nullptr) {
  cv::Mat K, R, rvec, dist(1, 5, CV_64F), t(3, 1, CV_64F);
  cv::eigen2cv(cam.K, K);
  cv::eigen2cv(cam.R, R);
  cv::Rodrigues(R, rvec);
  for (int k = 0; k < 5; ++k) dist.at<double>(k) = cam.dist(k);
  for (int k = 0; k < 3; ++k) t.at<double>(k) = cam.t(k);
  std::vector<cv::Point3d> world;
  for (int i = 0; i < m.num_vertices(); ++i) world.emplace_back(m.V(i, 0), m.V(i, 1), m.V(i, 2));
  std::vector<cv::Point2d> image;
  cv::projectPoints(world, rvec, t, K, dist, image);
  if (in_front) {
    in_front->resize(m.num_vertices());
    for (int i = 0; i < m.num_vertices(); ++i) (*in_front)[i] = (cam.R * m.V.row(i).transpose() + cam.t).z() > 0;
  }
  return image;
}

// Each triangle in front of the camera filled by cv::fillConvexPoly (which also fills
// pixels an edge merely touches: about half a pixel wider than centre sampling).
inline cv::Mat opencv_silhouette(const Camera& cam, const std::vector<const TriangleMesh*>& meshes) {
  cv::Mat out = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  constexpr int shift = 8;
  for (const TriangleMesh* m : meshes) {
    std::vector<char> front;
    const std::vector<cv::Point2d> image = opencv_projection(cam, *m, &front);
    for (int f = 0; f < m->num_faces(); ++f) {
      cv::Point pts[3];
      bool in_front = true;
      for (int k = 0; k < 3; ++k) {
        const int v = m->F(f, k);
        in_front = in_front && front[v];
        pts[k] = cv::Point(static_cast<int>(std::lround(image[v].x * (1 << shift))),
                           static_cast<int>(std::lround(image[v].y * (1 << shift))));
      }
      if (in_front) cv::fillConvexPoly(out, pts, 3, cv::Scalar(255), cv::LINE_8, shift);
    }
  }
  return out;
}

// The same silhouette sampled at pixel centres, the renderer's convention: a pixel is
// foreground when cv::pointPolygonTest puts its centre inside or on a projected triangle.
inline cv::Mat centre_sampled_silhouette(const Camera& cam, const std::vector<const TriangleMesh*>& meshes) {
  cv::Mat out = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  for (const TriangleMesh* m : meshes) {
    std::vector<char> front;
    const std::vector<cv::Point2d> image = opencv_projection(cam, *m, &front);
    for (int f = 0; f < m->num_faces(); ++f) {
      std::vector<cv::Point2f> tri;
      bool in_front = true;
      for (int k = 0; k < 3; ++k) {
        const int v = m->F(f, k);
        in_front = in_front && front[v];
        tri.emplace_back(static_cast<float>(image[v].x), static_cast<float>(image[v].y));
      }
      if (!in_front) continue;
      const cv::Rect box = cv::boundingRect(tri) & cv::Rect(0, 0, cam.width, cam.height);
      for (int y = box.y; y < box.y + box.height; ++y)
        for (int x = box.x; x < box.x + box.width; ++x)
          if (cv::pointPolygonTest(tri, cv::Point2f(x, y), false) >= 0) out.at<uchar>(y, x) = 255;
    }
  }
  return out;
}

}  // namespace weft::capture::testing
