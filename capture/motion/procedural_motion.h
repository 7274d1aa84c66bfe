#pragma once
// Procedural motions from a YAML spec (configs/motions/*.yaml, docs/MOTIONS.md): a
// sequence of segments (idle, walk, turn, arm_swings, squat, jump, random), each lasting some
// seconds, played on a generic humanoid and sampled at a frame rate. The result is a
// BvhMotion of that humanoid, so that the same retargeting (and mapping format) that
// brings motion capture onto a character brings these motions onto it too.
//
// The generic humanoid and its anatomical joint angles: generic_humanoid.h.
//
// Smoothness: every segment's joint angles and root offsets start and end at the neutral
// standing pose with zero velocity (envelopes and cosine/Hermite profiles), and the
// heading and position carried from one segment to the next change with zero velocity
// at the boundaries, so the motion is C1 across segments. Deterministic: the `random`
// segment (random_motion.h) draws from its own seed, the same on every platform.
#include <string>
#include <vector>

#include "capture/motion/bvh.h"
#include "capture/motion/generic_humanoid.h"
#include "capture/motion/random_motion.h"

namespace weft::capture {

enum class SegmentType { idle, walk, turn, arm_swings, squat, jump, random };

struct MotionSegment {
  SegmentType type = SegmentType::idle;
  double duration_s = 1.0;
  // walk / turn (stepping in place when step_length is 0)
  double step_length_m = 0.0;     // forward distance per step
  double step_frequency_hz = 1.8; // steps per second (a gait cycle is two steps); 0 in turn: no steps
  double foot_lift_m = 0.08;      // how high the swing foot rises
  double arm_swing_deg = 15.0;    // shoulder flexion amplitude while walking
  // turn
  double angle_deg = 90.0;        // positive: to the left (about +y)
  // arm_swings
  double amplitude_deg = 60.0;
  double frequency_hz = 0.8;
  std::string mode = "alternate"; // alternate | together | sideways
  // squat / jump
  double depth_m = 0.3;           // pelvis drop (squat; the jump's crouch)
  int repetitions = 1;            // squats in the segment
  double height_m = 0.2;          // jump: rise of the pelvis at the apex of the flight
  // random: starts and ends at the neutral pose by itself (no transition envelope)
  RandomMotionConfig random;
};

struct MotionSpec {
  std::string file;
  std::string name;
  double fps = 30.0;             // default sample rate
  double transition_s = 0.3;     // envelope ramps at segment ends (at most half a segment)
  std::vector<MotionSegment> segments;
  double duration_s() const;
};

MotionSpec load_motion_spec(const std::string& path);
// Parses YAML text as if read from `name`; unknown keys are errors naming key and file.
MotionSpec parse_motion_spec(const std::string& yaml_text, const std::string& name);

// Samples the spec: frames at t = k/fps for k = 0 .. round(duration·fps) − 1 (fps <= 0:
// the spec's). Throws weft::Error for segments that cannot be played (e.g. a jump too
// short for its flight time).
BvhMotion generate_motion(const MotionSpec& spec, double fps = 0);

const char* segment_type_name(SegmentType type);

}  // namespace weft::capture
