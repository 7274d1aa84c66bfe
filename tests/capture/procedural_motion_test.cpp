// Procedural motions: frame counts, C1 smoothness across segments, bounded per-frame
// change, walking feet that alternate, feet that stay put in a squat, determinism,
// strict YAML, and retargeting onto the humanoid's own Skeletool skeleton.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "capture/motion/bvh.h"
#include "capture/motion/motion_retarget.h"
#include "capture/motion/procedural_motion.h"
#include "tests/capture/motion_measures.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::max_acceleration;

namespace {

const std::string kMotions = WEFT_SOURCE_DIR "/configs/motions/";

TEST(Procedural, SpecsGiveDurationTimesFpsFrames) {
  for (const char* name : {"walk_in_place", "arm_swings", "squat_jump"}) {
    const MotionSpec spec = load_motion_spec(kMotions + name + ".yaml");
    EXPECT_EQ(spec.name, name);
    const BvhMotion m = generate_motion(spec);
    EXPECT_EQ(m.num_frames(), static_cast<int>(std::lround(spec.duration_s() * spec.fps))) << name;
    EXPECT_EQ(generate_motion(spec, 25).num_frames(), static_cast<int>(std::lround(spec.duration_s() * 25))) << name;
    EXPECT_DOUBLE_EQ(m.frame_time_s, 1.0 / spec.fps);
    EXPECT_TRUE(m.frames.allFinite()) << name;
    // Deterministic.
    EXPECT_EQ(generate_motion(spec).frames, m.frames) << name;
    // The motion is valid BVH: it survives the writer and reader.
    const BvhMotion back = parse_bvh(format_bvh(m), std::string(name) + ".bvh");
    EXPECT_LT((back.frames - m.frames).cwiseAbs().maxCoeff(), 1e-6) << name;
  }
}

TEST(Procedural, SmoothAcrossSegmentsAndBoundedPerFrame) {
  for (const char* name : {"walk_in_place", "arm_swings", "squat_jump"}) {
    const MotionSpec spec = load_motion_spec(kMotions + name + ".yaml");
    // C1: the acceleration estimate does not grow when sampling 4× finer.
    const double a1 = max_acceleration(generate_motion(spec, 500));
    const double a4 = max_acceleration(generate_motion(spec, 2000));
    EXPECT_LT(a4, 1.5 * a1) << name << ": acceleration " << a1 << " at 500 Hz, " << a4 << " at 2000 Hz";
    // Bounded per-frame change at 30 Hz: angles (degrees) and root position (metres).
    const BvhMotion m = generate_motion(spec, 30);
    const Eigen::MatrixXd step = (m.frames.bottomRows(m.num_frames() - 1) - m.frames.topRows(m.num_frames() - 1)).cwiseAbs();
    EXPECT_LT(step.leftCols(3).maxCoeff(), 0.1) << name;     // 3 m/s
    // 600°/s: a jump's push-off extends the knees about this fast.
    EXPECT_LT(step.rightCols(m.num_channels() - 3).maxCoeff(), 20.0) << name;
  }
  // The measure notices a kink: |t − 1| (a velocity jump of 2 units/s) sampled 4× finer
  // gives a 4× larger estimate.
  auto kinked = [](double fps) {
    BvhMotion k = generic_humanoid();
    k.frame_time_s = 1 / fps;
    const int n = static_cast<int>(2 * fps) + 1;
    k.frames.setZero(n, k.num_channels());
    for (int f = 0; f < n; ++f) k.frames(f, 10) = std::abs(f / fps - 1.0);
    return k;
  };
  EXPECT_GT(max_acceleration(kinked(2000)), 3.5 * max_acceleration(kinked(500)));
}

TEST(Procedural, WalkFeetAlternate) {
  const MotionSpec spec = load_motion_spec(kMotions + "walk_in_place.yaml");
  const BvhMotion m = generate_motion(spec, 30);
  const int la = m.joint_index("left_ankle"), ra = m.joint_index("right_ankle");
  const int lt = m.joint_index("left_toe"), rt = m.joint_index("right_toe");
  // The in-place walk is the second segment: 1 s .. 5 s.
  int switches = 0, last = 0;
  double left_max = 0, right_max = 0, ground_min = 1e9;
  const double ankle_rest = bvh_zero_pose(m)[la].translation().y() + generic_pelvis_height();
  for (int f = 30; f < 150; ++f) {
    const BvhTransforms G = bvh_global_transforms(m, f);
    const double l = G[la].translation().y() - ankle_rest, r = G[ra].translation().y() - ankle_rest;
    left_max = std::max(left_max, l);
    right_max = std::max(right_max, r);
    // Never both feet in the air; the lower foot stays on the floor (within the pelvis bob).
    EXPECT_LT(std::min(l, r), 0.01) << "frame " << f;
    ground_min = std::min({ground_min, G[lt].translation().y(), G[rt].translation().y()});
    const int side = l > r + 0.03 ? 1 : r > l + 0.03 ? -1 : 0;
    if (side != 0 && side != last) {
      if (last != 0) ++switches;
      last = side;
    }
  }
  // 1.8 steps/s over 4 s, ramps in and out: at least 5 changes of the lifted foot.
  EXPECT_GE(switches, 5);
  EXPECT_GT(left_max, 0.08);
  EXPECT_GT(right_max, 0.08);
  EXPECT_GT(ground_min, -0.01);  // toes not through the floor (y = 0)
  // The forward walk (8 .. 11 s after the quarter turn) moves the pelvis along the new
  // heading (+x after turning 90° left from +z).
  const BvhTransforms a = bvh_global_transforms(m, 7 * 30), b = bvh_global_transforms(m, 11 * 30 - 1);
  const Eigen::Vector3d moved = b[0].translation() - a[0].translation();
  EXPECT_GT(moved.x(), 0.8);
  EXPECT_LT(std::abs(moved.z()), 0.05);
}

TEST(Procedural, SquatKeepsFeetOnTheFloor) {
  const MotionSpec spec = parse_motion_spec("segments:\n  - {type: squat, duration: 3, depth: 0.3}\n", "s.yaml");
  const BvhMotion m = generate_motion(spec, 30);
  const int lt = m.joint_index("left_toe"), lte = m.joint_index("left_toe_end");
  const Eigen::Vector3d toe0 = bvh_global_transforms(m, 0)[lt].translation();
  double lowest_pelvis = 1e9;
  for (int f = 0; f < m.num_frames(); ++f) {
    const BvhTransforms G = bvh_global_transforms(m, f);
    lowest_pelvis = std::min(lowest_pelvis, G[0].translation().y());
    EXPECT_NEAR(G[lt].translation().y(), 0.0, 1e-9) << f;                       // on the floor
    EXPECT_NEAR(G[lte].translation().y(), 0.0, 1e-9) << f;                      // foot flat
    EXPECT_LT((G[lt].translation() - toe0).norm(), 0.012) << f;                 // not sliding
  }
  EXPECT_NEAR(lowest_pelvis, generic_pelvis_height() - 0.3, 0.002);  // frame 45 is the bottom
}

TEST(Procedural, JumpLeavesTheFloor) {
  const MotionSpec spec = parse_motion_spec("segments:\n  - {type: jump, duration: 2, height: 0.2}\n", "j.yaml");
  const BvhMotion m = generate_motion(spec, 200);
  double top = 0;
  for (int f = 0; f < m.num_frames(); ++f) top = std::max(top, m.frames(f, 1) - generic_pelvis_height());
  EXPECT_NEAR(top, 0.2, 0.002);
  expect_error([] { parse_motion_spec("segments:\n  - {type: jump, duration: 0.8, height: 0.3}\n", "j.yaml"); },
               {"j.yaml:2:", "segments[0]", "needs a duration of at least"});
}

TEST(Procedural, StrictYaml) {
  expect_error([] { parse_motion_spec("segments:\n  - {type: walk, duration: 2, stride: 0.5}\n", "/x/w.yaml"); },
               {"w.yaml:2:", "segments[0].stride", "unknown key"});
  expect_error([] { parse_motion_spec("fps: 30\nspeed: 2\nsegments:\n  - {type: idle, duration: 1}\n", "w.yaml"); },
               {"w.yaml:2:", "speed", "unknown key"});
  expect_error([] { parse_motion_spec("segments:\n  - {type: cartwheel, duration: 2}\n", "w.yaml"); },
               {"w.yaml:2:", "cartwheel"});
  expect_error([] { parse_motion_spec("segments:\n  - {type: idle}\n", "w.yaml"); }, {"w.yaml:2:", "duration"});
  expect_error([] { parse_motion_spec("segments:\n  - {type: squat, duration: 1, depth: 2}\n", "w.yaml"); },
               {"w.yaml:2:", "depth"});
  expect_error([] { parse_motion_spec("segments: []\n", "w.yaml"); }, {"w.yaml", "segments"});
  expect_error([] { parse_motion_spec("segments: [\n", "w.yaml"); }, {"w.yaml", "invalid YAML"});
  expect_error([] { load_motion_spec("/nonexistent/m.yaml"); }, {"m.yaml", "cannot open"});
}

// Retargeted onto the humanoid's own Skeletool skeleton, the motion comes back exactly
// (same proportions, every joint mapped), and its dofs change smoothly.
TEST(Procedural, RetargetsOntoItsOwnSkeleton) {
  const MotionSpec spec = load_motion_spec(kMotions + "squat_jump.yaml");
  const BvhMotion m = generate_motion(spec, 30);
  const Skeleton s = skeleton_from_bvh(m);
  std::string yaml = "source_units_m: 1\njoints:\n";
  for (const BvhJoint& j : m.joints) yaml += "  " + j.name + ": " + j.name + "\n";
  yaml += "extra_bones: [[right_hip, left_hip], [right_shoulder, left_shoulder]]\n"
          "root: {joints: [pelvis], scale: 1, vertical: source, horizontal: source}\n"
          "solver: {iterations: 60, smoothness: 1.0e-6, rest_weight: 0, tolerance: 1.0e-14}\n";
  const RetargetMapping mapping = parse_retarget_mapping(yaml, "self.yaml");
  RetargetOptions o;
  o.end_s = 6.0;  // squats and the first jump
  const RetargetResult r = retarget_motion(m, mapping, s, bvh_frame_dofs(m, 0), 1.0, o);
  EXPECT_LT(r.max_direction_error_deg, 0.01);
  double max_position_error = 0;
  for (int f = 0; f < r.motion.num_frames(); ++f) {
    const auto P = joint_positions(forward_kinematics(s, r.motion.dofs.row(f).transpose()));
    const auto Q = joint_positions(forward_kinematics(s, bvh_frame_dofs(m, f)));
    max_position_error = std::max(max_position_error, (P - Q).rowwise().norm().maxCoeff());
  }
  EXPECT_LT(max_position_error, 1e-4);  // metres
  const Eigen::MatrixXd step = (r.motion.dofs.bottomRows(r.motion.num_frames() - 1) -
                                r.motion.dofs.topRows(r.motion.num_frames() - 1)).cwiseAbs();
  EXPECT_LT(step.maxCoeff(), 0.26);  // radians (15°) or metres per frame
}

}  // namespace
