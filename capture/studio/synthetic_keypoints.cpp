#include "capture/studio/synthetic_keypoints.h"

#include <algorithm>
#include <cmath>

#include "graph/error.h"

namespace weft::capture {

namespace {

void check_keypoints(const Vertices& body25_world, const char* what) {
  if (body25_world.rows() != kBody25Count || body25_world.cols() != 3)
    fail(what, ": expected 25×3 BODY_25 world positions, got ", body25_world.rows(), "×", body25_world.cols());
}

bool in_image(const Camera& camera, const Eigen::Vector2d& uv) {
  return uv.x() >= -0.5 && uv.x() < camera.width - 0.5 && uv.y() >= -0.5 && uv.y() < camera.height - 0.5;
}

bool mapped(const Vertices& body25_world, int k) { return body25_world.row(k).allFinite(); }

}  // namespace

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
  for (auto [key, value] : {std::pair{"noise_px", c.noise_px}, {"depth_tolerance_m", c.depth_tolerance_m}})
    if (!(value >= 0) || !std::isfinite(value)) fail(what, ": ", key, " must be ≥ 0 and finite, got ", value);
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
    if (!in_image(camera, uv)) continue;
    out.row(k) << uv.x(), uv.y(), 1.0;
  }
  return out;
}

std::array<KeypointVisibility, kBody25Count> keypoint_visibility(const Camera& camera, const Vertices& body25_world,
                                                                 const cv::Mat& depth,
                                                                 const KeypointNoiseConfig& config) {
  check_keypoints(body25_world, "keypoint_visibility");
  validate_keypoint_noise(config, "keypoint noise config");
  if (!depth.empty() && (depth.type() != CV_32FC1 || depth.cols != camera.width || depth.rows != camera.height))
    fail("keypoint_visibility: camera '", camera.name, "': expected a CV_32FC1 depth image of ", camera.width, "x",
         camera.height, " (render()'s depth), got type ", depth.type(), " of ", depth.cols, "x", depth.rows);
  const double tolerance = config.depth_tolerance_m / config.metres_per_unit;  // world units
  std::array<KeypointVisibility, kBody25Count> out;
  for (int k = 0; k < kBody25Count; ++k) {
    if (!mapped(body25_world, k)) {
      out[k] = KeypointVisibility::unmapped;
      continue;
    }
    const Eigen::Vector3d X = body25_world.row(k).transpose();
    const double z = camera.depth(X);
    const Eigen::Vector2d uv = camera.project(X);
    if (!(z > 0) || !in_image(camera, uv)) {
      out[k] = KeypointVisibility::outside;
      continue;
    }
    out[k] = KeypointVisibility::visible;
    if (depth.empty()) continue;
    // The pixel whose centre is nearest: pixel (x, y) covers [x − ½, x + ½).
    const int x = std::clamp(static_cast<int>(std::floor(uv.x() + 0.5)), 0, camera.width - 1);
    const int y = std::clamp(static_cast<int>(std::floor(uv.y() + 0.5)), 0, camera.height - 1);
    const double surface = depth.at<float>(y, x);
    if (surface > 0 && z - surface > tolerance) out[k] = KeypointVisibility::occluded;
  }
  return out;
}

Body25 synthesize_keypoints(const Camera& camera, const Vertices& body25_world, const cv::Mat& depth,
                            const KeypointNoiseConfig& config, uint64_t seed) {
  const auto visibility = keypoint_visibility(camera, body25_world, depth, config);
  const Body25 clean = project_keypoints(camera, body25_world);
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
    const Eigen::Vector2d uv(clean(k, 0) + config.noise_px * noise_x, clean(k, 1) + config.noise_px * noise_y);
    if (!in_image(camera, uv)) continue;  // a detector reports nothing outside the frame
    const double base = occluded ? config.occluded_confidence : config.visible_confidence;
    const double confidence = std::clamp(base + config.confidence_jitter * jitter, 1e-3, 1.0);
    out.row(k) << uv.x(), uv.y(), confidence;
  }
  return out;
}

}  // namespace weft::capture
