// Is a clip's forward pelvis in its source, or made by the retargeting? (issue 38, decision
// b). The clip is retargeted onto the character at 30 fps as `weft synth` does, and every
// frame compares the source's own pelvis (the BVH root joint) and trunk (root → neck
// joint) with the retargeted character's (its pivot joint, and BODY_25 MidHip → Neck):
//   tilt  = the swing of the joint's rotation away from the vertical, relative to its zero
//           (BVH) or rest (character) pose: the pelvis's pitch and roll, degrees;
//   trunk = the angle of the root → neck direction from the vertical, degrees;
//   lumbar share = how much of the trunk's lean the spine above the pelvis takes, per frame
//           (trunk − tilt) / trunk where the trunk leans 10° or more (Tafazzol et al. 2014:
//           about 0.7 early in forward bending, 0.57 late).
// Usage: bench_pelvis_tilt CHARACTER MAPPING BVH_FILE START_S FRAMES [ROOT_JOINT NECK_JOINT]
//   e.g. bench_pelvis_tilt configs/characters/makehuman_skirt_coarse.yaml
//        configs/retarget/cmu_to_makehuman.yaml /usr/share/assimp/models/BVH/01_03.bvh 1.0 150
#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/character/skeletool_io.h"
#include "capture/evaluation/frame_measures.h"
#include "capture/model/capture_networks.h"
#include "capture/motion/bvh.h"
#include "capture/motion/motion_retarget.h"
#include "bench/bench_tool.h"
#include "graph/error.h"

using namespace weft;
using namespace weft::capture;
using weft::bench::angle_from_vertical_deg;

namespace {

void summary(const char* what, const std::vector<double>& v) {
  std::printf("%-44s median %6.1f   p5 %6.1f   p95 %6.1f   (%zu frames)\n", what, quantile(v, 0.5), quantile(v, 0.05),
              quantile(v, 0.95), v.size());
}

int run(int argc, char** argv) {
  WEFT_CHECK(argc == 6 || argc == 8,
             "usage: bench_pelvis_tilt CHARACTER MAPPING BVH_FILE START_S FRAMES [ROOT_JOINT NECK_JOINT]");
  const std::string character = argv[1], mapping = argv[2], bvh_path = argv[3];
  const double start_s = std::stod(argv[4]), fps = 30;
  const int frames = std::stoi(argv[5]);
  const std::string root_name = argc == 8 ? argv[6] : "Hips", neck_name = argc == 8 ? argv[7] : "Neck";
  const Character ch = load_character(character);
  const BvhMotion bvh = read_bvh(bvh_path);
  const RetargetResult retargeted = retarget_motion(
      bvh, load_retarget_mapping(mapping), ch, {.fps = fps, .start_s = start_s, .end_s = start_s + (frames - 0.5) / fps});
  const Motion& gt = retargeted.motion;
  const PoseParametrisation param = pose_parametrisation(ch);
  const Eigen::Matrix3d pivot_rest = pose_character(ch, ch.rest_dofs).joints[param.pivot_joint].linear();
  int root = -1, neck = -1;
  for (int j = 0; j < int(bvh.joints.size()); ++j) {
    if (bvh.joints[j].name == root_name) root = j;
    if (bvh.joints[j].name == neck_name) neck = j;
  }
  WEFT_CHECK(root >= 0 && neck >= 0, bvh_path, ": no joint '", root_name, "' or '", neck_name, "'");

  std::vector<double> src_tilt, src_trunk, src_share, chr_tilt, chr_trunk, chr_share;
  for (int f = 0; f < gt.num_frames(); ++f) {
    const BvhTransforms T = bvh_global_transforms_at(bvh, start_s + f / fps);
    const Eigen::Matrix3d R = T[root].linear();
    const double s_tilt = tilt_error_deg(R, Eigen::Matrix3d::Identity());
    const double s_trunk = angle_from_vertical_deg(T[neck].translation() - T[root].translation());
    src_tilt.push_back(s_tilt), src_trunk.push_back(s_trunk);
    if (s_trunk >= 10) src_share.push_back((s_trunk - s_tilt) / s_trunk);

    const PosedCharacter p = pose_character(ch, gt.dofs.row(f).transpose());
    const double c_tilt = tilt_error_deg(p.joints[param.pivot_joint].linear() * pivot_rest.transpose(),
                                         Eigen::Matrix3d::Identity());
    const double c_trunk = angle_from_vertical_deg((p.body25.row(1) - p.body25.row(8)).transpose());
    chr_tilt.push_back(c_tilt), chr_trunk.push_back(c_trunk);
    if (c_trunk >= 10) chr_share.push_back((c_trunk - c_tilt) / c_trunk);
  }
  std::printf("%s (%s from %.2f s) onto %s by %s: bone directions %.1f deg mean, %.1f deg worst frame; orientation "
              "targets %.1f deg mean\n",
              bvh_path.c_str(), root_name.c_str(), start_s, character.c_str(), mapping.c_str(),
              retargeted.mean_direction_error_deg, retargeted.max_direction_error_deg,
              retargeted.orientation_error_deg.size() ? retargeted.orientation_error_deg.mean() : 0.0);
  summary("source: pelvis tilt (deg)", src_tilt);
  summary("source: trunk lean, root -> neck (deg)", src_trunk);
  summary("source: lumbar share (trunk >= 10 deg)", src_share);
  summary("character: pelvis tilt (deg)", chr_tilt);
  summary("character: trunk lean, MidHip -> Neck (deg)", chr_trunk);
  summary("character: lumbar share (trunk >= 10 deg)", chr_share);
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return weft::bench::run_tool("bench_pelvis_tilt", run, argc, argv); }
