#pragma once
// Random motions of the generic humanoid (generic_humanoid.h) for training sets whose
// poses cover the space: smooth random trajectories within configured joint ranges that
// turn in place through the whole circle in both directions, step, crouch, reach (above
// the head, across the body), bend and twist the torso and turn the head. Played as the
// `random` segment of a procedural motion (procedural_motion.h, docs/MOTIONS.md).
//
// How: key times every key_interval (drawn in [min, max] s); at each key, per group
// (torso, head, left arm, right arm) with probability `hold` the group keeps its
// previous key, else every angle of the group is drawn uniformly in its range and moved
// toward at most max_speed × interval (so a key stays in the range). The
// heading turns toward a target drawn uniformly over the whole circle along the shorter
// arc (so both directions), at most `turn.max_angle` per key. Between keys each value
// follows a monotone cubic Hermite curve (Fritsch–Carlson slopes): C1, and never outside
// the two keys it joins, so never outside its range. The first and last keys are the
// neutral standing pose (every range contains 0) with zero velocity, so the segment joins
// its neighbours C1.
//
// Pelvis: tilted forward or back within its range (a bow at the hips), the hips flexing
// by the same angle so the legs stay where they were.
//
// Legs: a crouch bends hips, knees and ankles together and lowers the pelvis by exactly
// what the bent legs lose in height (humanoid::crouch), so the feet stay flat on the floor;
// stepping lifts one foot at a time (sin² profiles, C1) with the knee and ankle keeping it
// level, optionally swung out sideways, while the other stays down. A raised leg (off by
// default) lifts one foot and holds it over key intervals: hip flexion (or extension),
// knee flexion and abduction drawn in their ranges, as in stepping onto a box, kicking or
// a high knee; the other leg stands, a leg goes up only while the other is down, and
// neither a crouch nor a step overlaps a raise. Turning pivots on the feet (no foot
// placement), as the `turn` segment does; the pelvis does not translate.
//
// Deterministic: one seed gives the same motion on every platform (PortableRandom; every
// key draws the same number of values whatever the probabilities).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "files/strict_yaml.h"
#include "capture/motion/generic_humanoid.h"

namespace weft::capture {

struct AngleRange {
  double lo = 0, hi = 0;  // degrees, lo <= 0 <= hi
};

// Ranges of one joint's anatomical angles (generic_humanoid.h: flexion, abduction, twist).
struct JointRanges {
  AngleRange flex, abd, twist;
};

// The joints a random motion samples directly; arms are the same ranges on both sides.
enum class RandomJoint { spine, chest, neck, head, clavicle, shoulder, elbow, wrist, count };
inline constexpr int kRandomJointCount = static_cast<int>(RandomJoint::count);
const char* random_joint_name(RandomJoint j);

struct RandomMotionConfig {
  uint64_t seed = 1;
  double key_interval_min_s = 0.6, key_interval_max_s = 1.2;
  double hold_probability = 0.25;   // per group and key: keep the previous key
  double max_speed_deg_s = 150;     // a joint angle moves toward its drawn key at most this fast (mean over an interval)
  // Turning in place.
  double turn_probability = 0.6;    // per key: draw a new heading target (else keep the old one)
  double max_turn_deg = 100;        // heading change per key at most
  // Stepping in place: during a key interval, with this probability, one or more steps.
  double step_probability = 0.35;
  double step_frequency_hz = 1.8;   // steps per second (each step lifts one foot)
  AngleRange step_lift_m{0.03, 0.12};       // foot lift per step (m, lo..hi)
  AngleRange step_abduction_deg{0, 20};     // the swinging leg's sideways swing (degrees)
  // Crouching: per key, with this probability, a pelvis drop drawn in depth (m).
  double crouch_probability = 0.3;
  AngleRange crouch_depth_m{0.05, 0.35};
  // A raised leg: per key, with this probability (0: off, the motion of the seed before
  // the raise existed; its draws come from a stream of their own), one leg, drawn, lifted
  // to the drawn hip flexion (+ forward, − back), knee flexion and hip abduction (degrees,
  // anatomical: hip flexion 120°, extension 20–30°, abduction 45°, knee 135–140°, AAOS).
  double raise_probability = 0;
  AngleRange raise_hip_flex_deg{-15, 100};
  AngleRange raise_knee_deg{0, 120};
  AngleRange raise_abduction_deg{0, 30};
  // Pelvis tilt (degrees, + forward) with the legs kept in place (humanoid::tilt_pelvis):
  // bending at the hips. Drawn with the torso (same hold), from a stream of its own, so a
  // zero range gives the motion the seed gave before the tilt existed.
  AngleRange pelvis_pitch_deg{-10, 40};
  std::array<JointRanges, kRandomJointCount> joints{};  // set by default_random_joint_ranges()
  RandomMotionConfig();
};

// Keys of a random segment besides `type` and `duration`, and their parser; `where`
// names the segment in messages (e.g. "segments[2]"). Errors (unknown keys, lo > hi, a
// range without 0, probabilities outside [0, 1]) name the file, line and key.
const std::vector<const char*>& random_motion_keys();
RandomMotionConfig parse_random_motion_config(const StrictYaml& y, const YAML::Node& segment,
                                              const std::string& where);

// A random motion of `duration_s` seconds, sampled at any time in [0, duration].
class RandomMotion {
 public:
  RandomMotion(const RandomMotionConfig& config, double duration_s);
  // The pose at time t (s); its root offset holds the crouch's pelvis drop.
  humanoid::Pose pose(double t) const;
  // Heading (degrees about +y, + = left) relative to the start, at time t.
  double heading_deg(double t) const;
  double duration_s() const { return duration_; }
  const std::vector<double>& key_times() const { return times_; }

 private:
  struct Curve {  // monotone cubic Hermite through (times_[k], v[k]) with slopes m[k]
    std::vector<double> v, m;
  };
  double eval(const Curve& c, double t) const;
  Curve curve(std::vector<double> values) const;

  double duration_;
  std::vector<double> times_;
  // Anatomical angles per sampled joint and side (arms: 0 left, 1 right), in the order
  // flex, abd, twist.
  std::vector<Curve> angles_;  // index: (joint × 2 + side) × 3 + axis
  Curve heading_, crouch_knee_, pelvis_pitch_;
  std::vector<Curve> raise_;  // index: side × 3 + (hip flexion, knee flexion, hip abduction)
  struct Step {
    double start, end;  // s
    int side;           // 0 left, 1 right
    double hip_deg, abd_deg;
  };
  std::vector<Step> steps_;
};

}  // namespace weft::capture
