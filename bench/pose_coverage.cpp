// Do a set of training poses cover a test clip's? (issue 38: where the unseen motion's pose
// error comes from.) The procedural motions are retargeted onto the character as
// `virtual_poses` does (capture/training/virtual_poses.cpp: one pose per frame at FPS);
// the test clip is a Skeletool motion of the same character (a dataset's gt/pose.motion).
// For both, on the BODY_25 keypoints of the posed character:
//   trunk lean   = the angle of MidHip → Neck from the vertical, degrees (its distribution);
//   ankle gap    = the height of one ankle above the other, mm (a raised foot);
//   nearest pose = for each test frame, the smallest PA-MPJPE (frame_measures.h
//                  procrustes_aligned) over the pose set, mm: what a perfect lookup could reach;
//   nearest pose, upper body = the same over Neck, shoulders, elbows, wrists, head.
// Usage: bench_pose_coverage CHARACTER MAPPING FPS TEST_MOTION MOTION_YAML...
//   e.g. bench_pose_coverage DATA/character/character.yaml configs/retarget/humanoid_to_makehuman.yaml 10
//        DATA/gt/pose.motion configs/motions/virtual_poses.yaml
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/character/skeletool_io.h"
#include "capture/evaluation/frame_measures.h"
#include "capture/motion/motion_retarget.h"
#include "capture/motion/procedural_motion.h"
#include "bench/bench_tool.h"
#include "graph/error.h"

using namespace weft;
using namespace weft::capture;
using weft::bench::angle_from_vertical_deg;

namespace {

struct PoseSet {
  std::vector<Vertices> body25;  // per pose, MidHip at the origin
  std::vector<double> trunk_deg, ankle_gap_mm;
};

void add_pose(const Character& ch, const Eigen::VectorXd& dofs, PoseSet& s) {
  const PosedCharacter p = pose_character(ch, dofs);
  Vertices k = p.body25.rowwise() - p.body25.row(8);
  s.trunk_deg.push_back(angle_from_vertical_deg(k.row(1).transpose()));
  s.ankle_gap_mm.push_back(std::abs(k(11, 1) - k(14, 1)) * ch.metres_per_unit * 1e3);
  s.body25.push_back(std::move(k));
}

void print_distribution(const char* what, const std::vector<double>& v) {
  std::printf("%-40s median %6.1f   p5 %6.1f   p25 %6.1f   p75 %6.1f   p95 %6.1f   (%zu)\n", what, quantile(v, 0.5),
              quantile(v, 0.05), quantile(v, 0.25), quantile(v, 0.75), quantile(v, 0.95), v.size());
}

// The smallest PA-MPJPE (mm) of each test pose over the set, on the keypoint rows `rows`.
std::vector<double> nearest_pa_mm(const PoseSet& test, const PoseSet& set, const std::vector<int>& rows, double mpu) {
  std::vector<double> out(test.body25.size());
  auto pick = [&](const Vertices& k) {
    Vertices r(rows.size(), 3);
    for (size_t i = 0; i < rows.size(); ++i) r.row(i) = k.row(rows[i]);
    return r;
  };
  std::vector<Vertices> picked(set.body25.size());
  for (size_t i = 0; i < set.body25.size(); ++i) picked[i] = pick(set.body25[i]);
  tbb::parallel_for(size_t(0), test.body25.size(), [&](size_t t) {
    const Vertices truth = pick(test.body25[t]);
    double best = INFINITY;
    for (const Vertices& candidate : picked)
      best = std::min(best, mean_joint_error_mm(procrustes_aligned(candidate, truth), truth, mpu));
    out[t] = best;
  });
  return out;
}

int run(int argc, char** argv) {
  WEFT_CHECK(argc >= 6, "usage: bench_pose_coverage CHARACTER MAPPING FPS TEST_MOTION MOTION_YAML...");
  const Character ch = load_character(argv[1]);
  const RetargetMapping mapping = load_retarget_mapping(argv[2]);
  const double fps = std::stod(argv[3]);
  const Motion test_motion = read_motion(argv[4], ch.skeleton.num_dofs());

  PoseSet test, set;
  for (int f = 0; f < test_motion.num_frames(); ++f) add_pose(ch, test_motion.dofs.row(f).transpose(), test);
  for (int i = 5; i < argc; ++i) {
    const BvhMotion source = generate_motion(load_motion_spec(argv[i]), fps);
    RetargetOptions o;
    o.fps = fps;
    const RetargetResult r = retarget_motion(source, mapping, ch, o);
    const Motion& m = r.motion;
    for (int f = 0; f < m.num_frames(); ++f) add_pose(ch, m.dofs.row(f).transpose(), set);
    std::printf("%s: %d poses, retargeted with a bone-direction error of %.1f° mean, %.1f° in the worst frame\n",
                argv[i], m.num_frames(), r.mean_direction_error_deg, r.max_direction_error_deg);
  }
  print_distribution("trunk lean (deg), the pose set", set.trunk_deg);
  print_distribution("trunk lean (deg), the test clip", test.trunk_deg);
  print_distribution("ankle gap (mm), the pose set", set.ankle_gap_mm);
  print_distribution("ankle gap (mm), the test clip", test.ankle_gap_mm);

  std::vector<int> all, upper = {0, 1, 2, 3, 4, 5, 6, 7, 8, 15, 16, 17, 18};  // head, arms, trunk
  for (int j = 0; j < 25; ++j)
    if (test.body25[0].row(j).allFinite()) all.push_back(j);
  const std::vector<double> a = nearest_pa_mm(test, set, all, ch.metres_per_unit);
  const std::vector<double> u = nearest_pa_mm(test, set, upper, ch.metres_per_unit);
  double sum_a = 0, sum_u = 0;
  for (size_t t = 0; t < a.size(); ++t) sum_a += a[t], sum_u += u[t];
  print_distribution("nearest pose PA-MPJPE (mm), all", a);
  print_distribution("nearest pose PA-MPJPE (mm), upper body", u);
  std::printf("means: all %.1f mm, upper body %.1f mm\n", sum_a / a.size(), sum_u / u.size());
  return 0;
}

}  // namespace

int main(int argc, char** argv) { return weft::bench::run_tool("bench_pose_coverage", run, argc, argv); }
