#pragma once
// Pinhole cameras with OpenCV's distortion model, world → camera extrinsics, and their
// files: OpenCV FileStorage YAML (read/write) and Skeletool `.calibration` (import).
//
// A world point X (character units, e.g. mm) maps to camera coordinates x_c = R X + t;
// (a, b) = (x_c/z_c, y_c/z_c); r² = a² + b²;
//   a' = a (1 + k1 r² + k2 r⁴ + k3 r⁶) + 2 p1 a b + p2 (r² + 2a²)
//   b' = b (1 + k1 r² + k2 r⁴ + k3 r⁶) + p1 (r² + 2b²) + 2 p2 a b
//   u = fx a' + s b' + cx,  v = fy b' + cy   (pixels; s = K(0,1), usually 0)
// which is cv::projectPoints for zero skew.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "geometry/mesh.h"

namespace weft::capture {

using Points2 = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;

struct Camera {
  std::string name;
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();  // intrinsics (pixels)
  Eigen::Matrix<double, 5, 1> dist = Eigen::Matrix<double, 5, 1>::Zero();  // k1 k2 p1 p2 k3
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // world → camera rotation
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // world → camera translation (world units)
  int width = 0, height = 0;                        // image size (pixels)

  // Pixel coordinates of a world point (points behind the camera project too; check
  // depth() when it matters).
  Eigen::Vector2d project(const Eigen::Vector3d& world) const;
  double depth(const Eigen::Vector3d& world) const { return (R * world + t).z(); }
  Eigen::Vector3d center() const { return -R.transpose() * t; }
};

// Every vertex in front of the camera (projection refuses points behind it).
bool in_front(const Camera& camera, const Vertices& V);

Points2 project_points(const Camera& camera, const Vertices& world);

// Throws weft::Error (prefixed by `what`) unless K is finite with positive focal lengths,
// R is a rotation, and the image size is positive.
void validate_camera(const Camera& camera, const std::string& what);

// OpenCV FileStorage YAML: a sequence `cameras`, each a map with `name` (string), `K`
// (3×3), `dist` (1×4 or 1×5: k1 k2 p1 p2 [k3]), `R` (3×3), `t` (3×1), `image_width`,
// `image_height` (ints). Unknown keys are errors.
std::vector<Camera> read_cameras_yaml(const std::string& path);
void write_cameras_yaml(const std::string& path, const std::vector<Camera>& cameras);

// Skeletool `.calibration`: header "Skeletool Camera Calibration File V1.0", then per
// camera `name`, `sensor w h` (mm), `size W H`, `animated 0`, `intrinsic` (16 values, a
// 4×4 row-major matrix with K in the top-left), `extrinsic` (16 values, 4×4 world →
// camera), `radial k` (one or more radial coefficients: k1 [k2 [k3]]).
std::vector<Camera> read_skeletool_calibration(const std::string& path);

}  // namespace weft::capture
