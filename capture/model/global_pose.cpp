#include "capture/model/global_pose.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "graph/error.h"
#include "ops/ops.h"

namespace weft::capture {

namespace {

// v [B,3] / ‖v‖ per row, ε under the root.
Tensor normalise_rows(const Tensor& v) {
  return ops::div(v, ops::sqrt(ops::add_scalar(ops::sum(ops::mul(v, v), {1}, true), 1e-12)));
}

// Columns of v [B,3] in the order `order`.
Tensor permute_xyz(const Tensor& v, const std::vector<int64_t>& order) {
  return ops::index_select(v, 1, Tensor::from_indices({3}, order));
}

// a × b for rows of [B,3]: a.yzx ⊙ b.zxy − a.zxy ⊙ b.yzx.
Tensor cross_rows(const Tensor& a, const Tensor& b) {
  const std::vector<int64_t> yzx{1, 2, 0}, zxy{2, 0, 1};
  return ops::sub(ops::mul(permute_xyz(a, yzx), permute_xyz(b, zxy)),
                  ops::mul(permute_xyz(a, zxy), permute_xyz(b, yzx)));
}

// The unit world direction of the ray through pixel (u, v): the normalised image point
// is undistorted by Newton's method on OpenCV's model (see camera.h), which converges in a
// few steps from the distorted point for any realistic lens.
Eigen::Vector3d pixel_ray(const Camera& c, double u, double v) {
  const double fx = c.K(0, 0), fy = c.K(1, 1), s = c.K(0, 1), cx = c.K(0, 2), cy = c.K(1, 2);
  const double k1 = c.dist[0], k2 = c.dist[1], p1 = c.dist[2], p2 = c.dist[3], k3 = c.dist[4];
  const double bd = (v - cy) / fy, ad = (u - cx - s * bd) / fx;
  Eigen::Vector2d x(ad, bd);
  for (int it = 0; it < 50; ++it) {
    const double a = x[0], b = x[1], r2 = a * a + b * b;
    const double radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3));
    const double dradial = k1 + r2 * (2 * k2 + 3 * k3 * r2);  // d radial / d r²
    const Eigen::Vector2d f(a * radial + 2 * p1 * a * b + p2 * (r2 + 2 * a * a) - ad,
                            b * radial + p1 * (r2 + 2 * b * b) + 2 * p2 * a * b - bd);
    Eigen::Matrix2d J;
    J << radial + 2 * a * a * dradial + 2 * p1 * b + 6 * p2 * a, 2 * a * b * dradial + 2 * p1 * a + 2 * p2 * b,
        2 * a * b * dradial + 2 * p1 * a + 2 * p2 * b, radial + 2 * b * b * dradial + 6 * p1 * b + 2 * p2 * a;
    const Eigen::Vector2d step = J.partialPivLu().solve(f);
    if (!step.allFinite()) break;
    x -= step;
    if (step.norm() <= 1e-15 * (1 + x.norm())) break;
  }
  return (c.R.transpose() * Eigen::Vector3d(x[0], x[1], 1)).normalized();
}

}  // namespace

Tensor rotation_from_6d(const Tensor& x) {
  if (x.dim() != 2 || x.size(1) != 6)
    fail("rotation_from_6d: x must be [B, 6], got ", shape_str(x.shape()));
  const Tensor a1 = ops::slice(x, 1, 0, 3), a2 = ops::slice(x, 1, 3, 6);
  const Tensor b1 = normalise_rows(a1);
  const Tensor b2 = normalise_rows(ops::sub(a2, ops::mul(ops::sum(ops::mul(b1, a2), {1}, true), b1)));
  const Tensor b3 = cross_rows(b1, b2);
  return ops::stack({b1, b2, b3}, 2);  // R[:, i, j] = b_j[i]: the b's are the columns
}

int mapped_detection_count(const Body25& detections, const std::vector<double>& keypoint_mask) {
  WEFT_CHECK(keypoint_mask.size() == size_t(kBody25Count), "mapped_detection_count: ", keypoint_mask.size(),
             " mask weights, expected ", kBody25Count);
  int n = 0;
  for (int k = 0; k < kBody25Count; ++k) n += detections(k, 2) > 0 && keypoint_mask[size_t(k)] > 0;
  return n;
}

RootTranslationTerms root_translation_terms(const std::vector<std::vector<KeypointView>>& views,
                                            const std::vector<double>& keypoint_mask, DType dtype) {
  constexpr int M = kBody25Count;
  if (keypoint_mask.size() != static_cast<size_t>(M))
    fail("root_translation_terms: keypoint_mask has ", keypoint_mask.size(), " entries, expected ", M);
  for (int m = 0; m < M; ++m)
    if (!std::isfinite(keypoint_mask[m]) || keypoint_mask[m] < 0)
      fail("root_translation_terms: keypoint_mask[", m, "] = ", keypoint_mask[m], " must be finite and ≥ 0");
  const int64_t B = static_cast<int64_t>(views.size());
  RootTranslationTerms terms{Tensor::empty({B, 3}, dtype), Tensor::empty({B, M, 3, 3}, dtype)};
  for (int64_t b = 0; b < B; ++b) {
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    Eigen::Vector3d Ao = Eigen::Vector3d::Zero();
    std::vector<Eigen::Matrix3d> A(M, Eigen::Matrix3d::Zero());  // Σ_c A_cm
    for (size_t c = 0; c < views[b].size(); ++c) {
      const KeypointView& view = views[b][c];
      const Eigen::Vector3d o = view.camera.center();
      for (int m = 0; m < M; ++m) {
        const double conf = view.detections(m, 2);
        if (!std::isfinite(conf) || conf < 0)
          fail("root_translation_terms: frame ", b, " view ", c, " keypoint ", m, " has confidence ",
               conf, ", expected finite and ≥ 0");
        const double w = conf * keypoint_mask[m];
        if (w == 0) continue;
        const Eigen::Vector3d d = pixel_ray(view.camera, view.detections(m, 0), view.detections(m, 1));
        const Eigen::Matrix3d Acm = w * (Eigen::Matrix3d::Identity() - d * d.transpose());
        A[m] += Acm;
        S += Acm;
        Ao += Acm * o;
      }
    }
    S.diagonal().array() += 1e-9 * std::max(S.trace() / 3, 1.0);
    const Eigen::Matrix3d S_inv = S.inverse();  // SPD 3×3: closed form
    const Eigen::Vector3d offset = S_inv * Ao;
    for (int i = 0; i < 3; ++i) terms.offset.set({b, i}, offset[i]);
    for (int m = 0; m < M; ++m) {
      const Eigen::Matrix3d C = S_inv * A[m];
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) terms.weights.set({b, m, i, j}, C(i, j));
    }
  }
  return terms;
}

Body25 triangulate_keypoints(const std::vector<KeypointView>& views, const std::vector<double>& keypoint_mask,
                             double min_confidence) {
  constexpr int M = kBody25Count;
  if (keypoint_mask.size() != static_cast<size_t>(M))
    fail("triangulate_keypoints: keypoint_mask has ", keypoint_mask.size(), " entries, expected ", M);
  Body25 out;
  out.setConstant(std::numeric_limits<double>::quiet_NaN());
  for (int m = 0; m < M; ++m) {
    if (!(keypoint_mask[m] > 0)) continue;
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int seen = 0;
    for (const KeypointView& view : views) {
      const double conf = view.detections(m, 2);
      if (!std::isfinite(conf) || conf < min_confidence) continue;
      const Eigen::Vector3d d = pixel_ray(view.camera, view.detections(m, 0), view.detections(m, 1));
      const Eigen::Matrix3d A = conf * keypoint_mask[m] * (Eigen::Matrix3d::Identity() - d * d.transpose());
      S += A;
      b += A * view.camera.center();
      ++seen;
    }
    if (seen < 2) continue;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(S);
    if (!(eig.eigenvalues()[0] > 1e-4 * eig.eigenvalues()[2])) continue;
    out.row(m) = S.ldlt().solve(b).transpose();
  }
  return out;
}

Tensor solve_root_translation(const RootTranslationTerms& terms, const Tensor& points) {
  const int64_t B = terms.offset.size(0), M = terms.weights.size(1);
  if (points.shape() != Shape{B, M, 3})
    fail("solve_root_translation: points must be [B, M, 3] = ", shape_str({B, M, 3}), ", got ",
         shape_str(points.shape()));
  if (points.dtype() != terms.offset.dtype())
    fail("solve_root_translation: points are ", describe(points), ", the terms ", describe(terms.offset));
  // (C_m P_m)_i = Σ_j C_m[i, j] P_m[j]: broadcast P over i, sum over m and j.
  const Tensor CP = ops::mul(terms.weights, ops::reshape(points, {B, M, 1, 3}));
  return ops::sub(terms.offset, ops::sum(CP, {1, 3}));
}

}  // namespace weft::capture
