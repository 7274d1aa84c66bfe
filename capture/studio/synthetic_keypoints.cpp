#include "capture/studio/synthetic_keypoints.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "graph/error.h"

namespace weft::capture {

namespace {

void check_keypoints(const Vertices& body25_world, const char* what) {
  if (body25_world.rows() != kBody25Count || body25_world.cols() != 3)
    fail(what, ": expected 25×3 BODY_25 world positions, got ", body25_world.rows(), "×", body25_world.cols());
}

bool mapped(const Vertices& body25_world, int k) { return body25_world.row(k).allFinite(); }

// How much of a left/right pair's length survives projection: 1 when the segment between
// them lies parallel to the image plane (the person seen face on or from behind), 0 when
// it points at the camera (seen from the side). 1 when either is unmapped or behind the
// camera.
double pair_foreshortening(const Camera& camera, const Vertices& body25_world, int a, int b) {
  if (!mapped(body25_world, a) || !mapped(body25_world, b)) return 1.0;
  const Eigen::Vector3d A = body25_world.row(a).transpose(), B = body25_world.row(b).transpose();
  const double za = camera.depth(A), zb = camera.depth(B), length = (A - B).norm();
  if (!(za > 0) || !(zb > 0) || !(length > 0)) return 1.0;
  const double focal_px = std::sqrt(camera.K(0, 0) * camera.K(1, 1));
  const double face_on_px = focal_px * length / (0.5 * (za + zb));
  return std::clamp((camera.project(A) - camera.project(B)).norm() / face_on_px, 0.0, 1.0);
}

// Both models' per-keypoint draws: a keypoint that is in the image is dropped at its
// visibility's rate, else moved by Gaussian noise of sigma_px(k) per axis and reported with
// confidence(base, |error| in σ per axis, jitter). The gaussian model is what every dataset
// before the openpose model was made with: its draws and outputs must not change.
template <class Sigma, class Confidence>
Body25 noisy_keypoints(const Camera& camera, const Body25& clean,
                       const std::array<KeypointVisibility, kBody25Count>& visibility,
                       const KeypointNoiseConfig& config, uint64_t seed, Sigma sigma_px, Confidence confidence) {
  Body25 out = Body25::Zero();
  for (int k = 0; k < kBody25Count; ++k) {
    // Every keypoint draws the same four numbers whatever happens to it, so streams stay
    // aligned and a change to one keypoint leaves the others' noise as it was.
    PortableRandom rng(mix_seed(seed, static_cast<uint64_t>(k), 0));
    const double noise_x = rng.gaussian(), noise_y = rng.gaussian();
    const double jitter = rng.uniform(-1.0, 1.0);
    const double drop = rng.uniform();
    const bool occluded = visibility[k] == KeypointVisibility::occluded;
    if (visibility[k] != KeypointVisibility::visible && !occluded) continue;
    if (drop < (occluded ? config.occluded_dropout : config.dropout)) continue;
    const double sigma = sigma_px(k);
    const Eigen::Vector2d uv(clean(k, 0) + sigma * noise_x, clean(k, 1) + sigma * noise_y);
    if (!in_camera_image(camera, uv)) continue;  // a detector reports nothing outside the frame
    const double base = occluded ? config.occluded_confidence : config.visible_confidence;
    const double error_sigmas = sigma > 0 ? std::hypot(noise_x, noise_y) : 0.0;
    out.row(k) << uv.x(), uv.y(), std::clamp(confidence(base, error_sigmas, jitter), 1e-3, 1.0);
  }
  return out;
}

Body25 gaussian_keypoints(const Camera& camera, const Body25& clean,
                          const std::array<KeypointVisibility, kBody25Count>& visibility,
                          const KeypointNoiseConfig& config, uint64_t seed) {
  return noisy_keypoints(
      camera, clean, visibility, config, seed, [&](int) { return config.noise_px; },
      [&](double base, double, double jitter) { return base + config.confidence_jitter * jitter; });
}

// The openpose model (header: synthesize_keypoints).
Body25 detector_keypoints(const Camera& camera, const Vertices& body25_world, const cv::Mat& depth,
                          const Body25& clean, const std::array<KeypointVisibility, kBody25Count>& visibility,
                          const KeypointNoiseConfig& config, uint64_t seed) {
  const double scale_px = person_scale_px(camera, body25_world, depth);
  Body25 out = noisy_keypoints(
      camera, clean, visibility, config, seed,
      // COCO's σ_k is the rms of the Euclidean distance: per axis it is σ_k / √2.
      [&](int k) { return config.scale_error_multiple * kBody25CocoSigma[k] * scale_px / std::sqrt(2.0); },
      [&](double base, double error_sigmas, double jitter) {
        const double falloff = error_sigmas / config.confidence_falloff;
        return base * std::exp(-0.5 * falloff * falloff) + config.confidence_jitter * jitter;
      });
  for (size_t p = 0; p < kBody25LeftRightPairs.size(); ++p) {
    const auto [right, left] = kBody25LeftRightPairs[p];
    PortableRandom rng(mix_seed(seed, static_cast<uint64_t>(kBody25Count + p), 0));
    const double u = rng.uniform();
    const double edge_on = 1.0 - pair_foreshortening(camera, body25_world, right, left);
    const double probability =
        config.swap_probability + (config.swap_probability_side - config.swap_probability) * edge_on;
    if (!(u < probability)) continue;
    out.row(right).swap(out.row(left));
    for (int k : {right, left})
      if (out(k, 2) > 0) out(k, 2) = std::max(out(k, 2) * config.swap_confidence_scale, 1e-3);
  }
  return out;
}

}  // namespace

const std::array<double, kBody25Count> kBody25CocoSigma = {
    0.026,                // Nose
    0.079,                // Neck: the shoulders'
    0.079, 0.072, 0.062,  // RShoulder, RElbow, RWrist
    0.079, 0.072, 0.062,  // LShoulder, LElbow, LWrist
    0.107,                // MidHip: the hips'
    0.107, 0.087, 0.089,  // RHip, RKnee, RAnkle
    0.107, 0.087, 0.089,  // LHip, LKnee, LAnkle
    0.025, 0.025,         // REye, LEye
    0.035, 0.035,         // REar, LEar
    0.089, 0.089, 0.089,  // LBigToe, LSmallToe, LHeel: the ankles'
    0.089, 0.089, 0.089,  // RBigToe, RSmallToe, RHeel
};

const std::array<std::pair<int, int>, 11> kBody25LeftRightPairs = {{
    {2, 5}, {3, 6}, {4, 7},        // shoulder, elbow, wrist
    {9, 12}, {10, 13}, {11, 14},   // hip, knee, ankle
    {15, 16}, {17, 18},            // eye, ear
    {22, 19}, {23, 20}, {24, 21},  // big toe, small toe, heel
}};

KeypointNoiseConfig KeypointNoiseConfig::openpose() {
  KeypointNoiseConfig c;
  c.model = KeypointErrorModel::openpose;
  // An assumption (no per-joint figure for OpenPose found): a joint hidden behind the body
  // is missed six times as often as a visible one; the confidence is as before.
  c.occluded_dropout = 0.3;
  return c;
}

double person_scale_px(const Camera& camera, const Vertices& body25_world, const cv::Mat& depth) {
  if (!depth.empty()) {
    if (depth.type() != CV_32FC1 || depth.channels() != 1)
      fail("person_scale_px: camera '", camera.name, "': expected a CV_32FC1 depth image, got type ", depth.type());
    return std::sqrt(static_cast<double>(cv::countNonZero(depth)));  // foreground: depth > 0
  }
  const Body25 clean = project_keypoints(camera, body25_world);
  Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  int n = 0;
  for (int k = 0; k < kBody25Count; ++k) {
    if (clean(k, 2) == 0) continue;
    lo = lo.cwiseMin(clean.row(k).head<2>().transpose());
    hi = hi.cwiseMax(clean.row(k).head<2>().transpose());
    ++n;
  }
  return n < 2 ? 0.0 : std::sqrt((hi - lo).prod());
}

void validate_keypoint_noise(const KeypointNoiseConfig& c, const std::string& what) {
  auto in_unit = [&](const char* key, double v, bool zero_allowed) {
    if (!(zero_allowed ? v >= 0 : v > 0) || !(v <= 1))
      fail(what, ": ", key, " must be in ", zero_allowed ? "[0, 1]" : "(0, 1]", ", got ", v);
  };
  in_unit("dropout", c.dropout, true);
  in_unit("occluded_dropout", c.occluded_dropout, true);
  in_unit("visible_confidence", c.visible_confidence, false);
  in_unit("occluded_confidence", c.occluded_confidence, false);
  in_unit("confidence_jitter", c.confidence_jitter, true);
  in_unit("swap_probability", c.swap_probability, true);
  in_unit("swap_probability_side", c.swap_probability_side, true);
  in_unit("swap_confidence_scale", c.swap_confidence_scale, true);
  for (auto [key, value] : {std::pair{"noise_px", c.noise_px},
                            {"depth_tolerance_m", c.depth_tolerance_m},
                            {"scale_error_multiple", c.scale_error_multiple}})
    if (!(value >= 0) || !std::isfinite(value)) fail(what, ": ", key, " must be ≥ 0 and finite, got ", value);
  if (!(c.confidence_falloff > 0) || !std::isfinite(c.confidence_falloff))
    fail(what, ": confidence_falloff must be positive, got ", c.confidence_falloff);
  if (!(c.metres_per_unit > 0) || !std::isfinite(c.metres_per_unit))
    fail(what, ": metres_per_unit must be positive, got ", c.metres_per_unit);
}

Body25 project_keypoints(const Camera& camera, const Vertices& body25_world) {
  check_keypoints(body25_world, "project_keypoints");
  Body25 out = Body25::Zero();
  for (int k = 0; k < kBody25Count; ++k) {
    if (!mapped(body25_world, k)) continue;
    const Eigen::Vector3d X = body25_world.row(k).transpose();
    if (!(camera.depth(X) > 0)) continue;
    const Eigen::Vector2d uv = camera.project(X);
    if (!in_camera_image(camera, uv)) continue;
    out.row(k) << uv.x(), uv.y(), 1.0;
  }
  return out;
}

std::array<KeypointVisibility, kBody25Count> keypoint_visibility(const Camera& camera, const Vertices& body25_world,
                                                                 const cv::Mat& depth,
                                                                 const KeypointNoiseConfig& config) {
  check_keypoints(body25_world, "keypoint_visibility");
  validate_keypoint_noise(config, "keypoint noise config");
  return keypoint_visibility(camera, body25_world, depth, config.depth_tolerance_m / config.metres_per_unit);
}

Body25 synthesize_keypoints(const Camera& camera, const Vertices& body25_world, const cv::Mat& depth,
                            const KeypointNoiseConfig& config, uint64_t seed) {
  const auto visibility = keypoint_visibility(camera, body25_world, depth, config);
  const Body25 clean = project_keypoints(camera, body25_world);
  switch (config.model) {
    case KeypointErrorModel::gaussian: return gaussian_keypoints(camera, clean, visibility, config, seed);
    case KeypointErrorModel::openpose:
      return detector_keypoints(camera, body25_world, depth, clean, visibility, config, seed);
  }
  fail("synthesize_keypoints: unknown keypoint error model");
}

}  // namespace weft::capture
