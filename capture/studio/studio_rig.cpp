#include "capture/studio/studio_rig.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>

#include "capture/io/portable_random.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

constexpr double kDegree = M_PI / 180.0;

void check_image(const char* what, int width, int height, double vertical_fov_deg) {
  if (width <= 0 || height <= 0) fail(what, ": width and height must be positive pixels, got ", width, "x", height);
  if (!(vertical_fov_deg > 0 && vertical_fov_deg < 180))
    fail(what, ": vertical_fov_deg must be in (0, 180), got ", vertical_fov_deg);
}

void check_finite(const char* what, const char* key, double value) {
  if (!std::isfinite(value)) fail(what, ": ", key, " must be finite, got ", value);
}

void check_positive(const char* what, const char* key, double value) {
  if (!(value > 0) || !std::isfinite(value)) fail(what, ": ", key, " must be positive and finite, got ", value);
}

std::string numbered(const char* prefix, int index, int digits) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%s%0*d", prefix, digits, index);
  return buffer;
}

// A bounded, smooth random signal in [−1, 1]: Σ w_k sin(2π f_k t + φ_k) with weights
// summing to 1, frequencies in [0.4, 1] · max_frequency_hz and phases drawn from a seed.
// Its rate of change is at most 2π · max_frequency_hz per second.
class SmoothNoise {
 public:
  SmoothNoise(uint64_t seed, double max_frequency_hz) {
    PortableRandom rng(seed);
    for (int k = 0; k < 3; ++k) {
      frequency_hz_[k] = max_frequency_hz * rng.uniform(0.4, 1.0);
      phase_[k] = rng.uniform(0.0, 2 * M_PI);
    }
  }
  double operator()(double t_seconds) const {
    double sum = 0;
    for (int k = 0; k < 3; ++k) sum += kWeight[k] * std::sin(2 * M_PI * frequency_hz_[k] * t_seconds + phase_[k]);
    return sum;
  }

 private:
  static constexpr double kWeight[3] = {0.5, 0.3, 0.2};
  std::array<double, 3> frequency_hz_{}, phase_{};
};

// Streams of the wild path; each signal has its own seed so adding one leaves the others.
enum Stream : uint64_t { position_shake = 1, rotation_shake = 2, exposure = 3 };

void check_wild(const WildCameraConfig& c, int frames, double fps) {
  const char* what = "wild camera config";
  check_image(what, c.width, c.height, c.vertical_fov_deg);
  check_positive(what, "radius_start_m", c.radius_start_m);
  check_positive(what, "radius_end_m", c.radius_end_m);
  check_positive(what, "metres_per_unit", c.metres_per_unit);
  for (auto [key, value] : {std::pair{"height_m", c.height_m}, {"start_azimuth_deg", c.start_azimuth_deg},
                            {"arc_deg", c.arc_deg}, {"k1", c.k1}})
    check_finite(what, key, value);
  if (!c.target_m.allFinite()) fail(what, ": target_m must be finite");
  for (auto [key, value] : {std::pair{"shake_position_m", c.shake_position_m},
                            {"shake_rotation_deg", c.shake_rotation_deg},
                            {"shake_frequency_hz", c.shake_frequency_hz},
                            {"exposure_frequency_hz", c.exposure_frequency_hz},
                            {"follow_smoothing_s", c.follow_smoothing_s}})
    if (!(value >= 0) || !std::isfinite(value)) fail(what, ": ", key, " must be ≥ 0 and finite, got ", value);
  if (!(c.exposure_min > 0) || !(c.exposure_max >= c.exposure_min) || !std::isfinite(c.exposure_max))
    fail(what, ": expected 0 < exposure_min ≤ exposure_max, got ", c.exposure_min, " and ", c.exposure_max);
  if (frames < 1) fail(what, ": frames must be at least 1, got ", frames);
  if (!(fps > 0) || !std::isfinite(fps)) fail(what, ": fps must be positive, got ", fps);
}

}  // namespace

Camera look_at_camera(const std::string& name, const Eigen::Vector3d& centre, const Eigen::Vector3d& target,
                      int width, int height, double vertical_fov_deg, double k1) {
  const std::string what = "camera '" + name + "'";
  check_image(what.c_str(), width, height, vertical_fov_deg);
  if (!centre.allFinite() || !target.allFinite()) fail(what, ": centre and target must be finite");
  const Eigen::Vector3d view = target - centre;
  if (!(view.norm() > 0)) fail(what, ": the camera centre equals its target");
  const Eigen::Vector3d forward = view.normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitY());
  if (right.norm() < 1e-9) fail(what, ": looks straight up or down (no image 'up' from the world's +y)");
  Camera c;
  c.name = name;
  c.R.row(0) = right.normalized().transpose();
  c.R.row(1) = forward.cross(right.normalized()).transpose();  // image down
  c.R.row(2) = forward.transpose();
  c.t = -c.R * centre;
  const double focal_px = 0.5 * height / std::tan(0.5 * vertical_fov_deg * kDegree);
  c.K << focal_px, 0, 0.5 * (width - 1), 0, focal_px, 0.5 * (height - 1), 0, 0, 1;
  c.dist.setZero();
  c.dist(0) = k1;
  c.width = width;
  c.height = height;
  validate_camera(c, what);
  return c;
}

int studio_rig_rings(const StudioRigConfig& config) {
  return config.rings > 0 ? config.rings : (config.views + 8) / 9;
}

std::vector<Camera> studio_rig(const StudioRigConfig& c) {
  const char* what = "studio rig config";
  if (c.views < 1 || c.views > 72) fail(what, ": views must be in 1..72, got ", c.views);
  if (c.rings < 0 || c.rings > c.views) fail(what, ": rings must be in 0..views (", c.views, "), got ", c.rings);
  check_image(what, c.width, c.height, c.vertical_fov_deg);
  check_positive(what, "radius_m", c.radius_m);
  check_positive(what, "metres_per_unit", c.metres_per_unit);
  for (auto [key, value] : {std::pair{"height_m", c.height_m}, {"first_azimuth_deg", c.first_azimuth_deg},
                            {"ring_spacing_m", c.ring_spacing_m}, {"k1", c.k1}})
    check_finite(what, key, value);
  if (!c.target_m.allFinite()) fail(what, ": target_m must be finite");

  const double unit = 1.0 / c.metres_per_unit;  // character units per metre
  const Eigen::Vector3d target = c.target_m * unit;
  const int rings = studio_rig_rings(c);
  std::vector<Camera> cameras;
  cameras.reserve(c.views);
  for (int r = 0; r < rings; ++r) {
    const int in_ring = c.views / rings + (r < c.views % rings ? 1 : 0);
    const double step_deg = 360.0 / in_ring;
    const double height_m = c.height_m + (r - 0.5 * (rings - 1)) * c.ring_spacing_m;
    for (int k = 0; k < in_ring; ++k) {
      const double azimuth = (c.first_azimuth_deg + (k + double(r) / rings) * step_deg) * kDegree;
      const Eigen::Vector3d centre(c.target_m.x() + c.radius_m * std::sin(azimuth), height_m,
                                   c.target_m.z() + c.radius_m * std::cos(azimuth));
      cameras.push_back(look_at_camera(numbered("cam", static_cast<int>(cameras.size()), 2), centre * unit,
                                       target, c.width, c.height, c.vertical_fov_deg, c.k1));
    }
  }
  return cameras;
}

std::vector<Eigen::Vector3d> smooth_track(const std::vector<Eigen::Vector3d>& track, double sigma_frames) {
  if (!(sigma_frames >= 0) || !std::isfinite(sigma_frames))
    fail("smooth_track: sigma must be ≥ 0 and finite, got ", sigma_frames);
  if (sigma_frames == 0) return track;
  const int n = static_cast<int>(track.size());
  const int reach = static_cast<int>(std::ceil(3 * sigma_frames));
  // At each frame, a straight line fitted by Gaussian-weighted least squares, evaluated
  // there: the weighted mean in the interior, and no lag behind a steady walk at the ends.
  std::vector<Eigen::Vector3d> out(n);
  for (int i = 0; i < n; ++i) {
    double s0 = 0, s1 = 0, s2 = 0;  // Σw, Σw·d, Σw·d² with d = j − i
    Eigen::Vector3d sy = Eigen::Vector3d::Zero(), sdy = Eigen::Vector3d::Zero();
    for (int j = std::max(0, i - reach); j <= std::min(n - 1, i + reach); ++j) {
      const double d = j - i, w = std::exp(-0.5 * d * d / (sigma_frames * sigma_frames));
      s0 += w, s1 += w * d, s2 += w * d * d;
      sy += w * track[j];
      sdy += w * d * track[j];
    }
    const double det = s0 * s2 - s1 * s1;
    out[i] = det > 1e-12 * s0 * s2 ? Eigen::Vector3d((s2 * sy - s1 * sdy) / det) : Eigen::Vector3d(sy / s0);
  }
  return out;
}

std::vector<Camera> wild_camera_path(const WildCameraConfig& c, int frames, double fps, uint64_t seed,
                                     const std::vector<Eigen::Vector3d>& subject_track) {
  check_wild(c, frames, fps);
  const double unit = 1.0 / c.metres_per_unit;
  // The subject's displacement over the ground since frame 0, metres, per frame.
  std::vector<Eigen::Vector3d> follow(frames, Eigen::Vector3d::Zero());
  if (!subject_track.empty() && c.follow_subject) {
    if (static_cast<int>(subject_track.size()) != frames)
      fail("wild camera path: the subject track has ", subject_track.size(), " positions for ", frames, " frames");
    for (size_t i = 0; i < subject_track.size(); ++i)
      if (!subject_track[i].allFinite()) fail("wild camera path: the subject track is not finite at frame ", i);
    const std::vector<Eigen::Vector3d> smooth = smooth_track(subject_track, c.follow_smoothing_s * fps);
    for (int i = 0; i < frames; ++i) {
      follow[i] = (smooth[i] - smooth[0]) * c.metres_per_unit;
      follow[i].y() = 0;
    }
  }
  std::array<SmoothNoise, 3> position{SmoothNoise(mix_seed(seed, position_shake, 0), c.shake_frequency_hz),
                                      SmoothNoise(mix_seed(seed, position_shake, 1), c.shake_frequency_hz),
                                      SmoothNoise(mix_seed(seed, position_shake, 2), c.shake_frequency_hz)};
  std::array<SmoothNoise, 3> rotation{SmoothNoise(mix_seed(seed, rotation_shake, 0), c.shake_frequency_hz),
                                      SmoothNoise(mix_seed(seed, rotation_shake, 1), c.shake_frequency_hz),
                                      SmoothNoise(mix_seed(seed, rotation_shake, 2), c.shake_frequency_hz)};
  std::vector<Camera> cameras;
  cameras.reserve(frames);
  for (int i = 0; i < frames; ++i) {
    const double t = i / fps;
    const double s = frames > 1 ? double(i) / (frames - 1) : 0.0;
    const double ease = s * s * (3 - 2 * s);  // smoothstep: starts and stops at rest
    const double azimuth = (c.start_azimuth_deg + c.arc_deg * ease) * kDegree;
    const double radius = c.radius_start_m + (c.radius_end_m - c.radius_start_m) * ease;
    const Eigen::Vector3d target = c.target_m + follow[i];
    Eigen::Vector3d centre(target.x() + radius * std::sin(azimuth), c.height_m, target.z() + radius * std::cos(azimuth));
    for (int a = 0; a < 3; ++a) centre(a) += c.shake_position_m * position[a](t);
    Camera cam = look_at_camera(numbered("wild", i, 4), centre * unit, target * unit, c.width, c.height,
                                c.vertical_fov_deg, c.k1);
    // Hand-held wobble of the viewing direction, in the camera's own axes.
    const double yaw = c.shake_rotation_deg * kDegree * rotation[0](t);
    const double pitch = c.shake_rotation_deg * kDegree * rotation[1](t);
    const double roll = c.shake_rotation_deg * kDegree * rotation[2](t);
    const Eigen::Matrix3d shake = (Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX()) *
                                   Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()))
                                      .toRotationMatrix();
    const Eigen::Vector3d camera_centre = cam.center();
    cam.R = shake * cam.R;
    cam.t = -cam.R * camera_centre;
    validate_camera(cam, "wild camera path");
    cameras.push_back(std::move(cam));
  }
  return cameras;
}

std::vector<double> wild_exposure(const WildCameraConfig& c, int frames, double fps, uint64_t seed) {
  check_wild(c, frames, fps);
  const SmoothNoise noise(mix_seed(seed, exposure, 0), c.exposure_frequency_hz);
  std::vector<double> out(frames);
  for (int i = 0; i < frames; ++i) {
    const double unit_interval = 0.5 + 0.5 * noise(i / fps);
    out[i] = std::clamp(c.exposure_min + (c.exposure_max - c.exposure_min) * unit_interval, c.exposure_min,
                        c.exposure_max);  // rounding must not step outside the promised range
  }
  return out;
}

}  // namespace weft::capture
