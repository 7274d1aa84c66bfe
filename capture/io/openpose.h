#pragma once
// OpenPose BODY_25 keypoint files: {"version", "people": [{"pose_keypoints_2d":
// [x0, y0, c0, …, x24, y24, c24]}]}, pixels and confidences; an undetected keypoint is
// 0, 0, 0. Order as in DESIGN.md (0 Nose, 1 Neck, … 24 RHeel).
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

namespace weft::capture {

constexpr int kBody25Count = 25;
extern const std::array<const char*, kBody25Count> kBody25Names;
// Index of a BODY_25 keypoint name ("Nose", "RShoulder", …), or -1.
int body25_index(const std::string& name);

// 25×3 rows (x px, y px, confidence in [0, 1]).
using Body25 = Eigen::Matrix<double, kBody25Count, 3, Eigen::RowMajor>;

struct OpenPoseFrame {
  std::vector<Body25> people;
};

OpenPoseFrame read_openpose_json(const std::string& path);
OpenPoseFrame parse_openpose_json(const std::string& text, const std::string& name);
void write_openpose_json(const std::string& path, const OpenPoseFrame& frame);

}  // namespace weft::capture
