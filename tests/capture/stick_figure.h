#pragma once
// A 1.7 m stick figure's joint positions (left at +x, facing +z) and the generated
// skeleton built on them (build_body_skeleton), for tests that need the generated
// skeleton without the MakeHuman mesh.
#include <map>
#include <string>

#include "capture/character/body_skeleton_fit.h"

namespace weft::capture::testing {

inline std::map<std::string, Eigen::Vector3d> stick_figure_joints() {
  std::map<std::string, Eigen::Vector3d> pos;
  pos["hips"] = {0, 0.9, 0};
  pos["spine"] = {0, 1.05, 0};
  pos["chest"] = {0, 1.25, 0};
  pos["neck"] = {0, 1.45, 0};
  pos["head"] = {0, 1.52, 0};
  pos["head_end"] = {0, 1.68, 0};
  for (const double s : {1.0, -1.0}) {
    const std::string p = s > 0 ? "l_" : "r_";
    pos[p + "clavicle"] = {s * 0.03, 1.4, 0};
    pos[p + "shoulder"] = {s * 0.18, 1.4, 0};
    pos[p + "elbow"] = {s * 0.38, 1.2, 0};
    pos[p + "wrist"] = {s * 0.55, 1.03, 0};
    pos[p + "hand_end"] = {s * 0.62, 0.96, 0};
    pos[p + "hip"] = {s * 0.1, 0.9, 0};
    pos[p + "knee"] = {s * 0.12, 0.48, 0};
    pos[p + "ankle"] = {s * 0.13, 0.07, 0};
    pos[p + "toe"] = {s * 0.13, 0.02, 0.14};
    pos[p + "toe_end"] = {s * 0.13, 0.02, 0.19};
  }
  return pos;
}

inline Skeleton stick_figure_skeleton() { return build_body_skeleton(stick_figure_joints(), {}); }

}  // namespace weft::capture::testing
