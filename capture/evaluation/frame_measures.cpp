#include "capture/evaluation/frame_measures.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numbers>
#include <cmath>
#include <limits>

#include "geometry/closest_point.h"
#include "capture/garment/garment_simulator.h"
#include "capture/render/silhouette_iou.h"
#include "graph/error.h"

namespace weft::capture {

std::vector<double> vertex_distances_mm(const Vertices& a, const Vertices& b, double mpu) {
  WEFT_CHECK(a.rows() == b.rows(), "vertex_distances_mm: ", a.rows(), " against ", b.rows(), " vertices");
  std::vector<double> d(a.rows());
  for (int i = 0; i < a.rows(); ++i) d[i] = (a.row(i) - b.row(i)).norm() * mpu * 1e3;
  return d;
}

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const double pos = std::clamp(q, 0.0, 1.0) * double(v.size() - 1);
  const size_t lo = size_t(std::floor(pos)), hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (pos - double(lo)) * (v[hi] - v[lo]);
}

double mean_joint_error_mm(const Vertices& p, const Vertices& g, double mpu) {
  WEFT_CHECK(p.rows() == g.rows(), "mean_joint_error_mm: ", p.rows(), " against ", g.rows(), " keypoints");
  double sum = 0;
  int n = 0;
  for (int m = 0; m < p.rows(); ++m) {
    if (!p.row(m).allFinite() || !g.row(m).allFinite()) continue;
    sum += (p.row(m) - g.row(m)).norm() * mpu * 1e3;
    ++n;
  }
  return n ? sum / n : std::numeric_limits<double>::quiet_NaN();
}

Penetration cloth_penetration(const Character& ch, const Vertices& body, const Vertices& cloth) {
  return body_penetration(body_obstacle(ch, Eigen::MatrixX3d(body * ch.metres_per_unit)),
                          to_positions(cloth, ch.metres_per_unit));
}

std::vector<double> cloth_signed_distances_mm(const Character& ch, const Vertices& body, const Vertices& cloth) {
  const physics::BodyMesh obstacle = body_obstacle(ch, Eigen::MatrixX3d(body * ch.metres_per_unit));
  std::vector<double> d(cloth.rows());
  for (int i = 0; i < cloth.rows(); ++i) {
    const physics::ClosestPoint c = obstacle.closest_point(cloth.row(i).transpose() * ch.metres_per_unit);
    d[i] = c.face >= 0 ? c.distance * 1e3 : std::numeric_limits<double>::infinity();
  }
  return d;
}

double chamfer_distance_mm(const Vertices& a, const Vertices& b, const Faces& F, double mpu) {
  WEFT_CHECK(a.rows() == b.rows(), "chamfer_distance_mm: ", a.rows(), " against ", b.rows(), " vertices");
  WEFT_CHECK(a.rows() > 0 && F.rows() > 0, "chamfer_distance_mm: empty mesh");
  auto one_way = [&](const Vertices& from, const Vertices& to) {
    const ClosestTriangleQuery q(to, F);
    std::vector<double> d(from.rows());
    tbb::parallel_for(0, int(from.rows()), [&](int i) { d[i] = q.closest(from.row(i).transpose()).distance; });
    double sum = 0;
    for (double x : d) sum += x;
    return sum / d.size();
  };
  return 0.5 * (one_way(a, b) + one_way(b, a)) * mpu * 1e3;
}

Distribution distribution(const std::vector<double>& v) {
  Distribution d;
  d.count = int64_t(v.size());
  if (v.empty()) return d;
  double sum = 0;
  for (double x : v) sum += x;
  d.mean = sum / v.size();
  d.p95 = quantile(v, 0.95);
  d.p99 = quantile(v, 0.99);
  d.max = *std::max_element(v.begin(), v.end());
  return d;
}

ClothBalance cloth_out_of_balance(const Character& ch, const SynthSimulationConfig& simulation, double fps,
                                  const Vertices& body_prev, const Vertices& body, const Vertices& cloth_prev2,
                                  const Vertices& cloth_prev, const Vertices& cloth) {
  const double mpu = ch.metres_per_unit;
  // Pinned where predicted: the anchors' targets are the predicted anchors themselves.
  auto sim = make_garment_simulator(ch, simulation, fps, Eigen::MatrixX3d(body_prev * mpu),
                                    garment_pin_targets(ch, cloth));
  sim->body(0).set_vertices(Eigen::MatrixX3d(body * mpu));
  const physics::Positions x2 = to_positions(cloth_prev2, mpu), x1 = to_positions(cloth_prev, mpu),
                           x = to_positions(cloth, mpu);
  ClothBalance b;
  b.vertices = physics::vertex_balance(*sim, x2, x1, x, 1.0 / fps);
  const std::vector<int> anchors = garment_pin_vertices(ch);
  physics::summarize_out_of_balance(b.vertices, b.all);
  physics::summarize_out_of_balance(b.vertices, b.free, anchors);
  std::vector<char> held(cloth.rows(), 0);
  for (int a : anchors) held[a] = 1;
  for (int i = 0; i < cloth.rows(); ++i)
    if (!held[i]) b.free_vertices.push_back(i);
  return b;
}

std::vector<double> silhouette_ious(const Character& ch, const Vertices& body, const Vertices* cloth,
                                    const std::vector<Camera>& cameras, const std::vector<cv::Mat>& masks) {
  WEFT_CHECK(cameras.size() == masks.size(), "silhouette_ious: ", cameras.size(), " cameras and ", masks.size(),
             " masks");
  std::vector<double> iou(cameras.size());
  tbb::parallel_for(size_t(0), cameras.size(), [&](size_t k) {
    iou[k] = rendered_silhouette_iou(cameras[k], ch.body.mesh, body, ch.has_cloth() ? &ch.cloth->mesh : nullptr, cloth,
                                     masks[k]);
  });
  return iou;
}

double rotation_error_deg(const Eigen::Matrix3d& predicted, const Eigen::Matrix3d& truth) {
  return Eigen::AngleAxisd(predicted.transpose() * truth).angle() * 180 / std::numbers::pi;
}

RotationErrorSummary summarize_rotation_errors(const std::vector<double>& errors_deg) {
  RotationErrorSummary s;
  if (errors_deg.empty()) return s;
  s.median_deg = quantile(errors_deg, 0.5);
  s.p95_deg = quantile(errors_deg, 0.95);
  s.above_45 = double(std::count_if(errors_deg.begin(), errors_deg.end(), [](double a) { return a > 45; })) /
               errors_deg.size();
  return s;
}

}  // namespace weft::capture
