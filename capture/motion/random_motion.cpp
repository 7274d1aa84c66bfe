#include "capture/motion/random_motion.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "capture/io/portable_random.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

using namespace humanoid;
constexpr double kPi = std::numbers::pi;
constexpr double kReturn_s = 2.0;  // the last seconds of a random motion return to the neutral pose

// Default ranges (degrees), within the normal active ranges of motion of adults (AAOS
// tables: e.g. thoracolumbar flexion 80°, extension 25°, lateral bend 35°, rotation 45°;
// cervical flexion/extension 45°, lateral 45°, rotation 80°; shoulder flexion 180°,
// abduction 180°; elbow 150°; wrist flexion/extension 70–80°, deviation 20–30°) and
// kept short of their ends, so that poses look natural. Trunk and neck ranges are split
// between the two joints that carry them. Shoulder abduction below 0 (across the body)
// is scaled down while the arm is not raised forward (see draw_arm).
constexpr JointRanges kDefaultRanges[kRandomJointCount] = {
    {{-15, 40}, {-20, 20}, {-20, 20}},   // spine (lumbar)
    {{-10, 25}, {-15, 15}, {-25, 25}},   // chest (thoracic)
    {{-20, 30}, {-20, 20}, {-35, 35}},   // neck
    {{-20, 25}, {-15, 15}, {-40, 40}},   // head
    {{-10, 15}, {-5, 20}, {0, 0}},       // clavicle: protraction, elevation
    {{-40, 175}, {-35, 100}, {-45, 60}}, // shoulder
    {{0, 140}, {0, 0}, {0, 0}},          // elbow
    {{-50, 50}, {-20, 25}, {-30, 30}},   // wrist
};

constexpr int kSampledJoints[kRandomJointCount][2] = {
    {spine, spine}, {chest, chest}, {neck, neck}, {head, head}, {l_clavicle, r_clavicle},
    {l_shoulder, r_shoulder}, {l_elbow, r_elbow}, {l_wrist, r_wrist}};

bool is_arm(int j) { return j >= static_cast<int>(RandomJoint::clavicle); }
int curve_index(int joint, int side, int axis) { return (joint * 2 + side) * 3 + axis; }
double& axis_of(Angles& a, int axis) { return axis == 0 ? a.flex : axis == 1 ? a.abd : a.twist; }
const AngleRange& axis_of(const JointRanges& r, int axis) { return axis == 0 ? r.flex : axis == 1 ? r.abd : r.twist; }

std::string format_range(double lo, double hi) {
  std::ostringstream s;
  s << "[" << lo << ", " << hi << "]";
  return s.str();
}

// A [lo, hi] pair within [min, max]; lo > hi is an error naming the key.
AngleRange parse_range(const StrictYaml& y, const YAML::Node& n, const std::string& key, double min, double max,
                       bool contains_zero) {
  if (!n.IsSequence() || n.size() != 2) y.fail_at(n, key, "expected [min, max]");
  const AngleRange r{y.number(n[0], key + "[0]", min, max), y.number(n[1], key + "[1]", min, max)};
  if (r.lo > r.hi) y.fail_at(n, key, "min > max in " + format_range(r.lo, r.hi));
  if (contains_zero && (r.lo > 0 || r.hi < 0))
    y.fail_at(n, key, "the range " + format_range(r.lo, r.hi) + " must contain 0 (the neutral standing pose)");
  return r;
}

double probability(const StrictYaml& y, const YAML::Node& n, const std::string& key) {
  return y.number(n, key, 0, 1);
}

}  // namespace

const char* random_joint_name(RandomJoint j) {
  static const char* const names[kRandomJointCount] = {"spine",    "chest",    "neck",  "head",
                                                        "clavicle", "shoulder", "elbow", "wrist"};
  return names[static_cast<int>(j)];
}

RandomMotionConfig::RandomMotionConfig() {
  for (int j = 0; j < kRandomJointCount; ++j) joints[j] = kDefaultRanges[j];
}

const std::vector<const char*>& random_motion_keys() {
  static const std::vector<const char*> keys{"seed",   "key_interval", "hold_probability", "max_speed", "turn",
                                             "step",   "crouch",       "pelvis",          "joints",
                                             "raise"};
  return keys;
}

RandomMotionConfig parse_random_motion_config(const StrictYaml& y, const YAML::Node& n, const std::string& where) {
  RandomMotionConfig c;
  const std::string w = where + ".";
  if (n["seed"]) c.seed = static_cast<uint64_t>(y.number(n["seed"], w + "seed", 0, 9.007199254740992e15));
  if (n["key_interval"]) {
    const AngleRange r = parse_range(y, n["key_interval"], w + "key_interval", 0.1, 60, false);
    c.key_interval_min_s = r.lo;
    c.key_interval_max_s = r.hi;
  }
  if (n["hold_probability"]) c.hold_probability = probability(y, n["hold_probability"], w + "hold_probability");
  if (n["max_speed"]) c.max_speed_deg_s = y.number(n["max_speed"], w + "max_speed", 1, 3600);
  if (const YAML::Node t = n["turn"]) {
    y.check_keys(t, w + "turn", {"probability", "max_angle"});
    if (t["probability"]) c.turn_probability = probability(y, t["probability"], w + "turn.probability");
    if (t["max_angle"]) c.max_turn_deg = y.number(t["max_angle"], w + "turn.max_angle", 0, 180);
  }
  if (const YAML::Node s = n["step"]) {
    y.check_keys(s, w + "step", {"probability", "frequency", "lift", "abduction"});
    if (s["probability"]) c.step_probability = probability(y, s["probability"], w + "step.probability");
    if (s["frequency"]) c.step_frequency_hz = y.number(s["frequency"], w + "step.frequency", 0.2, 4);
    if (s["lift"]) c.step_lift_m = parse_range(y, s["lift"], w + "step.lift", 0, 0.3, false);
    if (s["abduction"]) c.step_abduction_deg = parse_range(y, s["abduction"], w + "step.abduction", 0, 45, false);
  }
  if (const YAML::Node s = n["crouch"]) {
    y.check_keys(s, w + "crouch", {"probability", "depth"});
    if (s["probability"]) c.crouch_probability = probability(y, s["probability"], w + "crouch.probability");
    if (s["depth"]) c.crouch_depth_m = parse_range(y, s["depth"], w + "crouch.depth", 0, 0.5, false);
  }
  if (const YAML::Node s = n["raise"]) {
    y.check_keys(s, w + "raise", {"probability", "hip_flex", "knee", "abduction"});
    if (s["probability"]) c.raise_probability = probability(y, s["probability"], w + "raise.probability");
    if (s["hip_flex"]) c.raise_hip_flex_deg = parse_range(y, s["hip_flex"], w + "raise.hip_flex", -30, 130, false);
    if (s["knee"]) c.raise_knee_deg = parse_range(y, s["knee"], w + "raise.knee", 0, 150, false);
    if (s["abduction"]) c.raise_abduction_deg = parse_range(y, s["abduction"], w + "raise.abduction", 0, 50, false);
  }
  if (const YAML::Node s = n["pelvis"]) {
    y.check_keys(s, w + "pelvis", {"pitch"});
    if (s["pitch"]) c.pelvis_pitch_deg = parse_range(y, s["pitch"], w + "pelvis.pitch", -60, 90, true);
  }
  if (const YAML::Node js = n["joints"]) {
    std::vector<const char*> names;
    for (int j = 0; j < kRandomJointCount; ++j) names.push_back(random_joint_name(static_cast<RandomJoint>(j)));
    y.check_keys(js, w + "joints", names);
    for (int j = 0; j < kRandomJointCount; ++j) {
      const std::string name = names[j];
      const YAML::Node r = js[name];
      if (!r) continue;
      const std::string key = w + "joints." + name;
      y.check_keys(r, key, {"flex", "abduction", "twist"});
      const char* axes[3] = {"flex", "abduction", "twist"};
      for (int a = 0; a < 3; ++a)
        if (r[axes[a]]) {
          AngleRange& dst = a == 0 ? c.joints[j].flex : a == 1 ? c.joints[j].abd : c.joints[j].twist;
          dst = parse_range(y, r[axes[a]], key + "." + axes[a], -180, 180, true);
        }
    }
  }
  return c;
}

// ------------------------------------------------------------------ the motion

RandomMotion::Curve RandomMotion::curve(std::vector<double> v) const {
  // Fritsch–Butland (Brodlie) slopes: a weighted harmonic mean of the neighbouring secants
  // where they agree in sign, else 0, and 0 at both ends. Each cubic piece is then
  // monotone between its two keys.
  const size_t K = v.size();
  std::vector<double> m(K, 0.0);
  for (size_t k = 1; k + 1 < K; ++k) {
    const double h0 = times_[k] - times_[k - 1], h1 = times_[k + 1] - times_[k];
    const double d0 = (v[k] - v[k - 1]) / h0, d1 = (v[k + 1] - v[k]) / h1;
    if (d0 * d1 <= 0) continue;
    m[k] = 3 * (h0 + h1) / ((2 * h1 + h0) / d0 + (h1 + 2 * h0) / d1);
  }
  return {std::move(v), std::move(m)};
}

double RandomMotion::eval(const Curve& c, double t) const {
  if (t <= times_.front()) return c.v.front();
  if (t >= times_.back()) return c.v.back();
  const size_t i = static_cast<size_t>(std::upper_bound(times_.begin(), times_.end(), t) - times_.begin()) - 1;
  const double h = times_[i + 1] - times_[i], s = (t - times_[i]) / h;
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * c.v[i] + (s3 - 2 * s2 + s) * h * c.m[i] + (-2 * s3 + 3 * s2) * c.v[i + 1] +
         (s3 - s2) * h * c.m[i + 1];
}

RandomMotion::RandomMotion(const RandomMotionConfig& c, double duration_s) : duration_(duration_s) {
  if (!(duration_s > 0)) fail("random motion: duration must be > 0, got ", duration_s);
  PortableRandom rng(c.seed);
  // Key times: intervals drawn in [min, max]; a last interval shorter than half the
  // minimum is merged into the one before.
  times_ = {0.0};
  for (;;) {
    const double next = times_.back() + rng.uniform(c.key_interval_min_s, c.key_interval_max_s);
    if (next > duration_s - 0.5 * c.key_interval_min_s) break;
    times_.push_back(next);
  }
  times_.push_back(duration_s);
  const size_t K = times_.size();

  // Values per key. Interior keys draw every value (fixed count per key); the first and
  // last keys are the neutral pose.
  std::vector<std::vector<double>> angles(kRandomJointCount * 2 * 3, std::vector<double>(K, 0.0));
  std::vector<double> heading(K, 0.0), knee(K, 0.0), pitch(K, 0.0);
  PortableRandom pelvis_rng(c.seed ^ 0x9e3779b97f4a7c15ull);  // its own stream: see pelvis_pitch_deg
  PortableRandom raise_rng(c.seed ^ 0x7261697365ull);         // its own stream: see raise_probability
  std::vector<std::vector<double>> raise(6, std::vector<double>(K, 0.0));
  double target = 0;  // heading target (degrees, relative to the start)
  enum Group { torso, neck_head, left_arm, right_arm, kGroups };
  auto group_of = [](int j, int side) {
    if (j <= static_cast<int>(RandomJoint::chest)) return torso;
    if (j <= static_cast<int>(RandomJoint::head)) return neck_head;
    return side == 0 ? left_arm : right_arm;
  };
  for (size_t k = 1; k < K; ++k) {
    bool hold[kGroups];
    for (bool& h : hold) h = rng.uniform() < c.hold_probability;
    // The rule of every key (degrees): the last key is the neutral pose, and keys in the
    // last kReturn_s seconds head back to it; otherwise a held group keeps its value and
    // any other moves toward its drawn value by at most max_speed × the key interval.
    const bool last = k + 1 == K, returning = times_[k] > duration_s - kReturn_s;
    const double step = c.max_speed_deg_s * (times_[k] - times_[k - 1]);
    auto next_key = [&](double previous, double drawn, bool held) {
      if (last) return 0.0;
      if (held && !returning) return previous;
      return previous + std::clamp((returning ? 0.0 : drawn) - previous, -step, step);
    };
    for (int j = 0; j < kRandomJointCount; ++j)
      for (int side = 0; side < (is_arm(j) ? 2 : 1); ++side) {
        double drawn[3];
        for (int a = 0; a < 3; ++a) {
          const AngleRange& r = axis_of(c.joints[j], a);
          drawn[a] = rng.uniform(r.lo, r.hi);
        }
        if (j == static_cast<int>(RandomJoint::shoulder) && drawn[1] < 0) {
          // Across the body only in front of it: full adduction from 70° of flexion on.
          drawn[1] *= std::clamp((drawn[0] - 20) / 50, 0.0, 1.0);
        }
        for (int a = 0; a < 3; ++a) {
          std::vector<double>& v = angles[curve_index(j, side, a)];
          v[k] = next_key(v[k - 1], drawn[a], hold[group_of(j, side)]);
        }
      }
    pitch[k] = next_key(pitch[k - 1], pelvis_rng.uniform(c.pelvis_pitch_deg.lo, c.pelvis_pitch_deg.hi), hold[torso]);
    const double u_turn = rng.uniform(), new_target = rng.uniform(0, 360);
    if (u_turn < c.turn_probability) target = heading[k - 1] + std::remainder(new_target - heading[k - 1], 360.0);
    heading[k] = heading[k - 1] + std::clamp(target - heading[k - 1], -c.max_turn_deg, c.max_turn_deg);
    const double u_crouch = rng.uniform(), depth = rng.uniform(c.crouch_depth_m.lo, c.crouch_depth_m.hi);
    knee[k] = k + 1 < K && u_crouch < c.crouch_probability ? knee_for_drop(depth) : 0.0;

    // A raised leg (its own stream, a fixed number of draws per key). It may start only
    // after a key without a crouch, and a key with a leg up has no crouch (nor the key after
    // it), so the two never overlap; one leg goes up only while the other is down.
    const double u_raise = raise_rng.uniform(), side_draw = raise_rng.uniform();
    const double raise_drawn[3] = {raise_rng.uniform(c.raise_hip_flex_deg.lo, c.raise_hip_flex_deg.hi),
                                   raise_rng.uniform(c.raise_knee_deg.lo, c.raise_knee_deg.hi),
                                   raise_rng.uniform(c.raise_abduction_deg.lo, c.raise_abduction_deg.hi)};
    if (c.raise_probability > 0) {
      auto up = [&](int side, size_t key) {
        for (int a = 0; a < 3; ++a)
          if (raise[side * 3 + a][key] != 0) return true;
        return false;
      };
      const int up_before = up(0, k - 1) ? 0 : up(1, k - 1) ? 1 : -1;
      if (up_before >= 0) knee[k] = 0;
      int side = u_raise < c.raise_probability && knee[k - 1] == 0 ? (side_draw < 0.5 ? 0 : 1) : -1;
      if (up_before >= 0 && side != up_before) side = -1;  // the other leg comes down first
      for (int s = 0; s < 2; ++s)
        for (int a = 0; a < 3; ++a) {
          std::vector<double>& v = raise[s * 3 + a];
          v[k] = next_key(v[k - 1], s == side ? raise_drawn[a] : 0.0, false);
        }
      if (up(0, k) || up(1, k)) knee[k] = 0;
    }
  }
  for (const auto& v : raise) raise_.push_back(curve(v));
  for (const auto& v : angles) angles_.push_back(curve(v));
  heading_ = curve(heading);
  crouch_knee_ = curve(knee);
  pelvis_pitch_ = curve(pitch);

  // Steps: in an interval that starts and ends standing (the knee then stays straight
  // through it, so a lifted foot never needs more knee than its lift), with probability
  // step_probability, floor(interval × frequency) steps (at least one), alternating feet.
  for (size_t k = 0; k + 1 < K; ++k) {
    const double h = times_[k + 1] - times_[k];
    const int n = std::max(1, static_cast<int>(h * c.step_frequency_hz));  // no step shorter than 1/frequency
    bool raised = false;  // a leg up at either end: no step in between
    for (const std::vector<double>& v : raise) raised = raised || v[k] != 0 || v[k + 1] != 0;
    const bool step = rng.uniform() < c.step_probability && knee[k] == 0 && knee[k + 1] == 0 && !raised;
    const int first_side = rng.uniform() < 0.5 ? 0 : 1;
    for (int i = 0; i < n; ++i) {
      const double lift = rng.uniform(c.step_lift_m.lo, c.step_lift_m.hi);
      const double abd = rng.uniform(c.step_abduction_deg.lo, c.step_abduction_deg.hi);
      if (step)
        steps_.push_back({times_[k] + i * h / n, times_[k] + (i + 1) * h / n, (first_side + i) % 2,
                          hip_for_foot_lift(lift), abd});
    }
  }
}

double RandomMotion::heading_deg(double t) const { return eval(heading_, t); }

Pose RandomMotion::pose(double t) const {
  Pose p;
  for (int j = 0; j < kRandomJointCount; ++j)
    for (int side = 0; side < (is_arm(j) ? 2 : 1); ++side) {
      Angles& a = p.a[kSampledJoints[j][side]];
      for (int axis = 0; axis < 3; ++axis) axis_of(a, axis) += eval(angles_[curve_index(j, side, axis)], t);
    }
  crouch(p, std::max(0.0, eval(crouch_knee_, t)));
  tilt_pelvis(p, eval(pelvis_pitch_, t));
  for (int side = 0; side < 2; ++side) {
    // The raised foot is kept near level as far as the ankle goes: the angle that levels
    // it, saturated smoothly (tanh, C1) at dorsiflexion 20° and plantar flexion 45°, so its
    // toes stay above the standing foot's.
    const int hip = side ? r_hip : l_hip, knee = side ? r_knee : l_knee, ankle = side ? r_ankle : l_ankle;
    const double hip_flex = eval(raise_[side * 3 + 0], t), knee_flex = eval(raise_[side * 3 + 1], t);
    p.a[hip].flex += hip_flex;
    p.a[knee].flex += knee_flex;
    const double level = knee_flex - hip_flex, limit = level > 0 ? 20.0 : 45.0;
    p.a[ankle].flex += limit * std::tanh(level / limit);
    p.a[hip].abd += eval(raise_[side * 3 + 2], t);
  }
  for (const Step& s : steps_) {
    if (t <= s.start || t >= s.end) continue;
    const double lift = std::pow(std::sin(kPi * (t - s.start) / (s.end - s.start)), 2);  // C1: zero slope at the ends
    const int hip = s.side ? r_hip : l_hip, knee = s.side ? r_knee : l_knee, ankle = s.side ? r_ankle : l_ankle;
    p.a[hip].flex += s.hip_deg * lift;
    p.a[knee].flex += 2 * s.hip_deg * lift;
    p.a[ankle].flex += s.hip_deg * lift;  // keeps the foot level
    p.a[hip].abd += s.abd_deg * lift;
    p.a[ankle].abd -= s.abd_deg * lift;
  }
  return p;
}

}  // namespace weft::capture
