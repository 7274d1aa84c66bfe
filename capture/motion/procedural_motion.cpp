#include "capture/motion/procedural_motion.h"


#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <numbers>
#include <optional>

#include "files/text_reader.h"
#include "files/strict_yaml.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kGravity = 9.81;  // m/s²
double deg(double radians) { return radians * 180.0 / kPi; }
double rad(double degrees) { return degrees * kPi / 180.0; }

using namespace humanoid;

// ----------------------------------------------------------------- profiles

double smoothstep(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * (3 - 2 * u);
}

// Ramps 0→1 over the first tau seconds and 1→0 over the last, C1 (zero slope at ends).
double envelope(double u, double T, double tau) {
  if (tau <= 0) return 1.0;
  return std::min(smoothstep(u / tau), smoothstep((T - u) / tau));
}

// ∫0^u envelope: distance factor for a walk (seconds).
double envelope_integral(double u, double T, double tau) {
  if (tau <= 0) return std::clamp(u, 0.0, T);
  auto S = [](double x) { x = std::clamp(x, 0.0, 1.0); return x * x * x - 0.5 * x * x * x * x; };
  if (u <= tau) return tau * S(u / tau);
  if (u <= T - tau) return tau / 2 + (u - tau);
  return (T - tau) - tau * S((T - u) / tau);
}

// Cubic Hermite through keys (time, value, slope): C1 by construction.
struct Key {
  double t, v, m;
};
double hermite(const std::vector<Key>& k, double t) {
  if (t <= k.front().t) return k.front().v;
  if (t >= k.back().t) return k.back().v;
  size_t i = 0;
  while (t > k[i + 1].t) ++i;
  const double h = k[i + 1].t - k[i].t, s = (t - k[i].t) / h;
  const double s2 = s * s, s3 = s2 * s;
  return (2 * s3 - 3 * s2 + 1) * k[i].v + (s3 - 2 * s2 + s) * h * k[i].m + (-2 * s3 + 3 * s2) * k[i + 1].v +
         (s3 - s2) * h * k[i + 1].m;
}

// Stepping: phase φ = π f u (a gait cycle is two steps); the left foot swings while
// sin φ > 0. Swing lift uses max(0, ±sin φ)², C1 where the feet change over.
void stepping(Pose& p, const MotionSegment& s, double u, double e) {
  const double phase = kPi * s.step_frequency_hz * u, sn = std::sin(phase);
  const double swing_hip = deg(std::asin(std::min(1.0, s.step_length_m / (2 * kLeg))));  // ±, per step
  const double lift_hip = hip_for_foot_lift(s.foot_lift_m);
  for (int side = 0; side < 2; ++side) {
    const double sgn = side ? -1.0 : 1.0;
    const double lift = std::pow(std::max(0.0, sgn * sn), 2);
    const double swing = sgn * swing_hip * sn;
    p.a[side ? r_hip : l_hip].flex += e * (swing + lift_hip * lift);
    p.a[side ? r_knee : l_knee].flex += e * 2 * lift_hip * lift;
    p.a[side ? r_ankle : l_ankle].flex += e * (lift_hip * lift - swing);  // keeps the foot level
    p.a[side ? r_shoulder : l_shoulder].flex -= e * sgn * s.arm_swing_deg * sn;
    p.a[side ? r_elbow : l_elbow].flex += e * 10;
  }
  p.root_offset.y() -= e * kLeg * (1 - std::cos(rad(swing_hip * sn)));
}

void check_jump(const MotionSegment& s, double& a, double& b, double& land, double& c) {
  const double v0 = std::sqrt(2 * kGravity * s.height_m);
  a = 0.35;                      // crouch (s)
  b = a + 0.25;                  // push-off
  land = b + 2 * v0 / kGravity;  // ballistic flight
  c = land + 0.25;               // landing absorbed
  if (s.duration_s < c + 0.3)
    fail("jump of height ", s.height_m, " m needs a duration of at least ", c + 0.3, " s, got ", s.duration_s);
}

// The segment's pose at local time u (root heading/position handled by the caller).
Pose segment_pose(const MotionSegment& s, double u, double tau) {
  Pose p;
  const double T = s.duration_s, e = envelope(u, T, tau);
  switch (s.type) {
    case SegmentType::idle: {
      // Breathing and a slow weight shift keep a standing subject from freezing.
      p.a[spine].flex += e * 1.5 * std::sin(2 * kPi * 0.25 * u);
      p.root_offset.x() += e * 0.01 * std::sin(2 * kPi * 0.2 * u);
      break;
    }
    case SegmentType::walk:
      stepping(p, s, u, e);
      break;
    case SegmentType::turn:
      if (s.step_frequency_hz > 0) {
        MotionSegment in_place = s;
        in_place.step_length_m = 0;
        in_place.arm_swing_deg = 0;
        stepping(p, in_place, u, e);
      }
      break;
    case SegmentType::arm_swings: {
      const double w = std::sin(2 * kPi * s.frequency_hz * u), A = e * s.amplitude_deg;
      if (s.mode == "alternate") {
        p.a[l_shoulder].flex += A * w;
        p.a[r_shoulder].flex -= A * w;
      } else if (s.mode == "together") {
        p.a[l_shoulder].flex += A * w;
        p.a[r_shoulder].flex += A * w;
      } else {  // sideways: both arms rise and fall, never crossing the body
        const double up = A * (1 - std::cos(2 * kPi * s.frequency_hz * u)) / 2;
        p.a[l_shoulder].abd += up;
        p.a[r_shoulder].abd += up;
      }
      p.a[l_elbow].flex += e * 10;
      p.a[r_elbow].flex += e * 10;
      break;
    }
    case SegmentType::squat: {
      const double kappa = knee_for_drop(s.depth_m) * (1 - std::cos(2 * kPi * s.repetitions * u / T)) / 2;
      crouch(p, kappa);
      p.a[spine].flex += 0.25 * kappa;  // lean forward over the feet
      p.a[chest].flex += 0.1 * kappa;
      p.a[l_shoulder].flex += 0.8 * kappa;
      p.a[r_shoulder].flex += 0.8 * kappa;
      break;
    }
    case SegmentType::random:  // RandomMotion::pose (random_motion.h)
      break;
    case SegmentType::jump: {
      double a, b, land, c;
      check_jump(s, a, b, land, c);
      const double v0 = std::sqrt(2 * kGravity * s.height_m), d = s.depth_m;
      const double kd = knee_for_drop(d), kl = knee_for_drop(0.6 * d);
      const double kappa = hermite({{0, 0, 0}, {a, kd, 0}, {b, 0, 0}, {land, 0, 0}, {c, kl, 0}, {T, 0, 0}}, u);
      crouch(p, kappa);
      // The pelvis follows its own C1 profile: down, up to take-off speed, ballistic
      // flight, landing at that speed, absorbed, back to standing. It replaces the drop
      // crouch() set, which has zero velocity at take-off.
      double y;
      if (u <= b) y = hermite({{0, 0, 0}, {a, -d, 0}, {b, 0, v0}}, u);
      else if (u <= land) y = v0 * (u - b) - 0.5 * kGravity * (u - b) * (u - b);
      else y = hermite({{land, 0, -v0}, {c, -0.6 * d, 0}, {T, 0, 0}}, u);
      p.root_offset.y() = y;
      const double plantar = hermite({{0, 0, 0}, {a, 0, 0}, {b, 30, 0}, {land, 10, 0}, {c, 0, 0}, {T, 0, 0}}, u);
      p.a[l_ankle].flex -= plantar;
      p.a[r_ankle].flex -= plantar;
      p.a[spine].flex += 0.25 * kappa;
      // Arms swing back in the crouch and forward-up through the flight.
      const double arms = hermite({{0, 0, 0}, {a, -30, 0}, {land, 80, 0}, {c, 20, 0}, {T, 0, 0}}, u);
      p.a[l_shoulder].flex += arms;
      p.a[r_shoulder].flex += arms;
      break;
    }
  }
  return p;
}

void parse_spec_body(const StrictYaml& y, const YAML::Node& root, MotionSpec& spec);

}  // namespace

const char* segment_type_name(SegmentType t) {
  switch (t) {
    case SegmentType::idle: return "idle";
    case SegmentType::walk: return "walk";
    case SegmentType::turn: return "turn";
    case SegmentType::arm_swings: return "arm_swings";
    case SegmentType::squat: return "squat";
    case SegmentType::jump: return "jump";
    case SegmentType::random: return "random";
  }
  return "?";
}

double MotionSpec::duration_s() const {
  double d = 0;
  for (const MotionSegment& s : segments) d += s.duration_s;
  return d;
}

MotionSpec parse_motion_spec(const std::string& text, const std::string& name) {
  const StrictYaml y{display_name(name)};
  const YAML::Node root = y.parse(text);
  MotionSpec spec;
  spec.file = name;
  try {
    parse_spec_body(y, root, spec);
  } catch (const YAML::Exception& e) {  // conversions deep inside yaml-cpp
    fail(y.file, ":", e.mark.line + 1, ": ", e.msg);
  }
  return spec;
}

namespace {

void parse_spec_body(const StrictYaml& y, const YAML::Node& root, MotionSpec& spec) {
  y.check_keys(root, "", {"name", "fps", "transition", "segments"});
  spec.name = root["name"] ? root["name"].as<std::string>()
                           : std::filesystem::path(spec.file).stem().string();
  if (root["fps"]) spec.fps = y.number(root["fps"], "fps", 1, 1000);
  if (root["transition"]) spec.transition_s = y.number(root["transition"], "transition", 0.01, 10);
  const YAML::Node segs = root["segments"];
  if (!segs) y.fail_at(root, "segments", "missing key (a list of segments)");
  if (!segs.IsSequence() || segs.size() == 0) y.fail_at(segs, "segments", "expected a non-empty list");
  for (size_t i = 0; i < segs.size(); ++i) {
    const YAML::Node n = segs[i];
    const std::string where = "segments[" + std::to_string(i) + "]";
    if (!n.IsMap() || !n["type"]) y.fail_at(n, where, "expected a mapping with a 'type'");
    const std::string type = n["type"].as<std::string>();
    MotionSegment s;
    std::vector<const char*> keys{"type", "duration"};
    if (type == "idle") {
      s.type = SegmentType::idle;
    } else if (type == "walk") {
      s.type = SegmentType::walk;
      keys.insert(keys.end(), {"step_length", "step_frequency", "foot_lift", "arm_swing"});
    } else if (type == "turn") {
      s.type = SegmentType::turn;
      s.step_frequency_hz = 0;
      keys.insert(keys.end(), {"angle", "step_frequency", "foot_lift"});
    } else if (type == "arm_swings") {
      s.type = SegmentType::arm_swings;
      keys.insert(keys.end(), {"amplitude", "frequency", "mode"});
    } else if (type == "squat") {
      s.type = SegmentType::squat;
      keys.insert(keys.end(), {"depth", "repetitions"});
    } else if (type == "jump") {
      s.type = SegmentType::jump;
      s.depth_m = 0.15;
      keys.insert(keys.end(), {"height", "depth"});
    } else if (type == "random") {
      s.type = SegmentType::random;
      keys.insert(keys.end(), random_motion_keys().begin(), random_motion_keys().end());
    } else {
      y.fail_at(n["type"], where + ".type",
                "unknown segment type '" + type + "' (expected idle, walk, turn, arm_swings, squat, jump or random)");
    }
    y.check_keys(n, where, keys);
    if (!n["duration"]) y.fail_at(n, where + ".duration", "missing key (seconds)");
    s.duration_s = y.number(n["duration"], where + ".duration", 0.05, 3600);
    auto opt = [&](const char* key, double& field, double lo, double hi) {
      if (n[key]) field = y.number(n[key], where + "." + key, lo, hi);
    };
    opt("step_length", s.step_length_m, 0, 1.2);
    opt("step_frequency", s.step_frequency_hz, s.type == SegmentType::turn ? 0.0 : 0.2, 4);
    opt("foot_lift", s.foot_lift_m, 0, 0.4);
    opt("arm_swing", s.arm_swing_deg, 0, 90);
    opt("angle", s.angle_deg, -1080, 1080);
    opt("amplitude", s.amplitude_deg, 0, 170);
    opt("frequency", s.frequency_hz, 0.05, 4);
    opt("depth", s.depth_m, 0, 0.6);
    opt("height", s.height_m, 0, 0.8);
    if (n["repetitions"]) s.repetitions = static_cast<int>(y.number(n["repetitions"], where + ".repetitions", 1, 100));
    if (n["mode"]) {
      s.mode = n["mode"].as<std::string>();
      if (s.mode != "alternate" && s.mode != "together" && s.mode != "sideways")
        y.fail_at(n["mode"], where + ".mode", "expected alternate, together or sideways, found '" + s.mode + "'");
    }
    if (s.type == SegmentType::random) s.random = parse_random_motion_config(y, n, where);
    if (s.type == SegmentType::jump) {
      double a, b, land, c;
      try {
        check_jump(s, a, b, land, c);
      } catch (const weft::Error& e) {
        y.fail_at(n, where, e.what());
      }
    }
    spec.segments.push_back(s);
  }
}

}  // namespace

MotionSpec load_motion_spec(const std::string& path) { return parse_motion_spec(read_file_bytes(path), path); }

BvhMotion generate_motion(const MotionSpec& spec, double fps) {
  if (spec.segments.empty()) fail(display_name(spec.file), ": no segments");
  if (fps <= 0) fps = spec.fps;
  BvhMotion m = generic_humanoid();
  m.source = spec.file.empty() ? spec.name : spec.file;
  m.frame_time_s = 1.0 / fps;
  const int frames = static_cast<int>(std::lround(spec.duration_s() * fps));
  m.frames.setZero(frames, m.num_channels());

  // Heading (degrees about +y) and floor position (x, z) at each segment's start.
  const size_t S = spec.segments.size();
  std::vector<double> start(S + 1, 0), heading(S + 1, 0);
  std::vector<Eigen::Vector2d> position(S + 1, Eigen::Vector2d::Zero());
  auto tau_of = [&](const MotionSegment& s) { return std::min(spec.transition_s, s.duration_s / 2); };
  auto speed_of = [](const MotionSegment& s) { return s.step_length_m * s.step_frequency_hz; };  // m/s
  auto forward = [](double heading_deg) { return Eigen::Vector2d(std::sin(rad(heading_deg)), std::cos(rad(heading_deg))); };
  std::vector<std::optional<RandomMotion>> randoms(S);
  for (size_t i = 0; i < S; ++i) {
    const MotionSegment& s = spec.segments[i];
    if (s.type == SegmentType::jump) {
      double a, b, land, c;
      check_jump(s, a, b, land, c);
    }
    if (s.type == SegmentType::random) randoms[i].emplace(s.random, s.duration_s);
    start[i + 1] = start[i] + s.duration_s;
    heading[i + 1] = heading[i] + (s.type == SegmentType::turn ? s.angle_deg : 0) +
                     (s.type == SegmentType::random ? randoms[i]->heading_deg(s.duration_s) : 0);
    position[i + 1] = position[i];
    if (s.type == SegmentType::walk)
      position[i + 1] += forward(heading[i]) * speed_of(s) * envelope_integral(s.duration_s, s.duration_s, tau_of(s));
  }

  size_t i = 0;
  for (int f = 0; f < frames; ++f) {
    const double t = f / fps;
    while (i + 1 < S && t >= start[i + 1]) ++i;
    const MotionSegment& s = spec.segments[i];
    const double u = std::clamp(t - start[i], 0.0, s.duration_s), tau = tau_of(s);
    const Pose p = s.type == SegmentType::random ? randoms[i]->pose(u) : segment_pose(s, u, tau);
    double yaw = heading[i];
    if (s.type == SegmentType::random) yaw += randoms[i]->heading_deg(u);
    Eigen::Vector2d pos = position[i];
    if (s.type == SegmentType::turn) yaw += s.angle_deg * smoothstep(u / s.duration_s);
    if (s.type == SegmentType::walk) pos += forward(heading[i]) * speed_of(s) * envelope_integral(u, s.duration_s, tau);
    set_humanoid_frame(m, f, p, yaw, pos);
  }
  return m;
}

}  // namespace weft::capture
