#include "capture/evaluation/frame_measures.h"

#include <tbb/parallel_for.h>

#include <Eigen/Geometry>

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
                          to_positions(cloth, ch.metres_per_unit), kContactDistanceM);
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

std::vector<double> joint_distances_mm(const Vertices& a, const Vertices& b, double mpu) {
  WEFT_CHECK(a.rows() == b.rows(), "joint_distances_mm: ", a.rows(), " and ", b.rows(), " rows");
  std::vector<double> d(a.rows(), kNotMeasured);
  for (int i = 0; i < a.rows(); ++i)
    if (a.row(i).allFinite() && b.row(i).allFinite()) d[i] = (a.row(i) - b.row(i)).norm() * mpu * 1e3;
  return d;
}

Vertices procrustes_aligned(const Vertices& predicted, const Vertices& truth) {
  WEFT_CHECK(predicted.rows() == truth.rows(), "procrustes_aligned: ", predicted.rows(), " and ", truth.rows(),
             " rows");
  std::vector<int> rows;
  for (int i = 0; i < predicted.rows(); ++i)
    if (predicted.row(i).allFinite() && truth.row(i).allFinite()) rows.push_back(i);
  Vertices out = Vertices::Constant(predicted.rows(), 3, kNotMeasured);
  if (rows.size() < 3) return out;
  Eigen::Matrix3Xd src(3, rows.size()), dst(3, rows.size());
  for (size_t k = 0; k < rows.size(); ++k)
    src.col(k) = predicted.row(rows[k]).transpose(), dst.col(k) = truth.row(rows[k]).transpose();
  const Eigen::Matrix4d T = Eigen::umeyama(src, dst, true);
  for (int i : rows)
    out.row(i) = (T.topLeftCorner<3, 3>() * predicted.row(i).transpose() + T.topRightCorner<3, 1>()).transpose();
  return out;
}

ViewErrorSplit view_error_split(const Vertices& p, const Vertices& t, const Eigen::Matrix3d& R, double mpu) {
  WEFT_CHECK(p.rows() == t.rows(), "view_error_split: ", p.rows(), " and ", t.rows(), " rows");
  MeasuredMean depth, plane;
  for (int i = 0; i < p.rows(); ++i) {
    if (!p.row(i).allFinite() || !t.row(i).allFinite()) continue;
    const Eigen::Vector3d e = R * (p.row(i) - t.row(i)).transpose() * mpu * 1e3;
    depth.add(std::abs(e.z()));
    plane.add(e.head<2>().norm());
  }
  return {depth.value(), plane.value()};
}

Eigen::Matrix3d heading_rotation(const Eigen::Matrix3d& rotation) {
  // Swing–twist about y: the twist is (w, 0, y, 0) normalised; (0, 0, 0, 0) only for a
  // half-turn about a horizontal axis, whose heading is then taken as none.
  const Eigen::Quaterniond q(rotation);
  const double n = std::hypot(q.w(), q.y());
  if (n < 1e-12) return Eigen::Matrix3d::Identity();
  return Eigen::Quaterniond(q.w() / n, 0, q.y() / n, 0).toRotationMatrix();
}

double rotation_error_deg(const Eigen::Matrix3d& predicted, const Eigen::Matrix3d& truth) {
  return Eigen::AngleAxisd(predicted.transpose() * truth).angle() * 180 / std::numbers::pi;
}

double heading_error_deg(const Eigen::Matrix3d& predicted, const Eigen::Matrix3d& truth) {
  // Swing–twist: the twist of q about the axis u is (w, (v·u) u), normalised; its angle is
  // 2 atan2(|v·u|, |w|) (the sign of a quaternion is free).
  const Eigen::Quaterniond q(predicted * truth.transpose());
  return 2 * std::atan2(std::abs(q.y()), std::abs(q.w())) * 180 / std::numbers::pi;
}

double tilt_error_deg(const Eigen::Matrix3d& predicted, const Eigen::Matrix3d& truth) {
  // q = swing · twist (twist about y): the swing's angle is 2 atan2(|(x, z)|, |(w, y)|).
  const Eigen::Quaterniond q(predicted * truth.transpose());
  return 2 * std::atan2(std::hypot(q.x(), q.z()), std::hypot(q.w(), q.y())) * 180 / std::numbers::pi;
}

double trunk_direction_error_deg(const Vertices& predicted_body25, const Vertices& true_body25) {
  constexpr int kNeck = 1, kMidHip = 8;
  if (predicted_body25.rows() <= kMidHip || true_body25.rows() <= kMidHip) return kNotMeasured;
  const Eigen::Vector3d p = (predicted_body25.row(kNeck) - predicted_body25.row(kMidHip)).transpose();
  const Eigen::Vector3d t = (true_body25.row(kNeck) - true_body25.row(kMidHip)).transpose();
  if (!p.allFinite() || !t.allFinite() || p.norm() == 0 || t.norm() == 0) return kNotMeasured;
  return std::atan2(p.cross(t).norm(), p.dot(t)) * 180 / std::numbers::pi;
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

const std::vector<FrameMetric>& frame_metrics() {
  using M = FrameMeasures;
  static const std::vector<FrameMetric> table = {
      {"pivot_error_mm", "mm", "distance of the pivot joint (the global translation's error)", &M::pivot_error_mm},
      {"mpjpe_mm", "mm", "mean joint error over the mapped BODY_25 keypoints", &M::mpjpe_mm},
      {"mpjpe_root_relative_mm", "mm", "the same with both pivots at the origin", &M::mpjpe_root_relative_mm},
      {"pa_mpjpe_mm", "mm", "the same after the similarity (scale, rotation, translation) that best aligns the "
       "predicted keypoints to the true ones (PA-MPJPE)", &M::pa_mpjpe_mm},
      {"mpjpe_depth_mm", "mm", "root-relative joint error along the input camera's axis (depth), mean size",
       &M::mpjpe_depth_mm},
      {"mpjpe_image_plane_mm", "mm", "root-relative joint error across the input camera's axis (image plane), mean "
       "size", &M::mpjpe_image_plane_mm},
      {"root_rotation_error_deg", "°", "geodesic angle between the pivot joint's global rotations",
       &M::root_rotation_error_deg},
      {"root_heading_error_deg", "°", "the twist about the vertical of that rotation error: front/back confusion, "
       "without the pelvis's tilt", &M::root_heading_error_deg},
      {"root_tilt_error_deg", "°", "the rest of that rotation error, its swing away from the vertical: the pelvis's "
       "pitch and roll", &M::root_tilt_error_deg},
      {"trunk_direction_error_deg", "°", "angle between the directions MidHip → Neck (BODY_25), which 3D keypoints "
       "determine", &M::trunk_direction_error_deg},
      {"body_error_mean_mm", "mm", "mean body vertex distance", &M::body_error_mean_mm},
      {"body_error_p95_mm", "mm", "95th percentile of the body vertex distances", &M::body_error_p95_mm},
      {"cloth_error_mean_mm", "mm", "mean cloth vertex distance", &M::cloth_error_mean_mm},
      {"cloth_error_p95_mm", "mm", "95th percentile of the cloth vertex distances", &M::cloth_error_p95_mm},
      {"cloth_chamfer_mm", "mm", "symmetric Chamfer distance of the cloth surfaces", &M::cloth_chamfer_mm},
      {"penetration_mean_mm", "mm", "depth of free cloth vertices (not anchors) inside the body, mean over those inside",
       &M::penetration_mean_mm},
      {"penetration_mean_all_mm", "mm", "the same depth, mean over every free cloth vertex (0 outside)",
       &M::penetration_mean_all_mm},
      {"penetration_max_mm", "mm", "the deepest free cloth vertex", &M::penetration_max_mm},
      {"penetrating_fraction", "", "the fraction of free cloth vertices inside the body", &M::penetrating_fraction},
      {"contact_fraction", "", "the fraction of free cloth vertices outside the body but within 4 mm of it (contact)",
       &M::contact_fraction},
      {"oob_force_mean_n", "N", "out-of-balance force, mean over the free vertices", &M::oob_force_mean_n},
      {"oob_force_p95_n", "N", "its 95th percentile", &M::oob_force_p95_n},
      {"oob_force_p99_n", "N", "its 99th percentile", &M::oob_force_p99_n},
      {"oob_force_max_n", "N", "its maximum", &M::oob_force_max_n},
      {"oob_force_mean_rel", "× m g", "the same relative to each vertex's weight, mean", &M::oob_force_mean_rel},
      {"oob_force_max_rel", "× m g", "relative, maximum", &M::oob_force_max_rel},
      {"oob_force_outside_mean_n", "N", "mean over the free vertices outside the body",
       &M::oob_force_outside_mean_n},
      {"oob_force_all_vertices_mean_n", "N", "mean over every vertex, anchors included",
       &M::oob_force_all_vertices_mean_n},
      {"oob_force_all_vertices_max_n", "N", "maximum over every vertex", &M::oob_force_all_vertices_max_n},
      {"inertia_mean_n", "N", "mean size of m a over the free vertices", &M::inertia_mean_n},
      {"elastic_mean_n", "N", "mean size of the membrane + bending force", &M::elastic_mean_n},
      {"collision_mean_n", "N", "mean size of the collision penalty force", &M::collision_mean_n},
      {"friction_mean_n", "N", "mean size of the friction force", &M::friction_mean_n},
      {"amv_iou", "", "silhouette IoU, mean over all views", &M::amv_iou},
      {"rv_iou", "", "silhouette IoU, mean over all views but the input view", &M::rv_iou},
      {"sv_iou", "", "silhouette IoU of the input view", &M::sv_iou},
  };
  return table;
}

FrameMetricMeans::FrameMetricMeans() : means_(frame_metrics().size()) {}

void FrameMetricMeans::add(const FrameMeasures& m) {
  const std::vector<FrameMetric>& table = frame_metrics();
  for (size_t k = 0; k < table.size(); ++k) means_[k].add(m.*table[k].value);
}

double FrameMetricMeans::mean(const std::string& name) const {
  const std::vector<FrameMetric>& table = frame_metrics();
  for (size_t k = 0; k < table.size(); ++k)
    if (name == table[k].name) return means_[k].value();
  fail("FrameMetricMeans: no metric named '", name, "' (frame_metrics() lists them)");
}

namespace {

double mean_of(const std::vector<double>& v) {
  if (v.empty()) return kNotMeasured;
  double sum = 0;
  for (double x : v) sum += x;
  return sum / double(v.size());
}

}  // namespace

Vertices free_cloth_vertices(const Character& ch, const Vertices& cloth) {
  std::vector<char> held(size_t(cloth.rows()), 0);
  for (int i = 0; i < ch.attachment.size(); ++i) {
    const int a = ch.attachment.anchors[i];
    WEFT_CHECK(a >= 0 && a < cloth.rows(), "free_cloth_vertices: anchor ", a, " of a garment with ", cloth.rows(),
               " vertices");
    held[size_t(a)] = 1;
  }
  Vertices free(cloth.rows() - std::count(held.begin(), held.end(), 1), 3);
  for (int i = 0, k = 0; i < cloth.rows(); ++i)
    if (!held[size_t(i)]) free.row(k++) = cloth.row(i);
  return free;
}

void measure_penetration(const Character& ch, const Vertices& body, const Vertices& all_cloth, FrameMeasures& m) {
  const Vertices cloth = free_cloth_vertices(ch, all_cloth);
  const Penetration p = cloth_penetration(ch, body, cloth);
  m.cloth_vertices = cloth.rows();
  m.penetrating_vertices = p.vertices_inside;
  m.penetration_depth_sum_mm = p.depth_sum * 1e3;
  m.penetration_mean_mm = p.vertices_inside ? p.depth_sum * 1e3 / p.vertices_inside : 0.0;
  m.penetration_mean_all_mm = cloth.rows() ? p.depth_sum * 1e3 / double(cloth.rows()) : kNotMeasured;
  m.penetration_max_mm = p.max_depth * 1e3;
  m.penetrating_fraction = cloth.rows() ? double(p.vertices_inside) / double(cloth.rows()) : kNotMeasured;
  m.contact_fraction = cloth.rows() ? double(p.vertices_in_contact) / double(cloth.rows()) : kNotMeasured;
}

void measure_geometry(const Character& ch, const PosedFrame& p, const PosedFrame& t, bool cloth_error,
                      FrameMeasures& m) {
  const double mpu = ch.metres_per_unit;
  m.pivot_error_mm = (p.pivot - t.pivot).norm() * mpu * 1e3;
  m.mpjpe_mm = mean_joint_error_mm(p.body25, t.body25, mpu);
  const Vertices p_rel = p.body25.rowwise() - p.pivot.transpose(), t_rel = t.body25.rowwise() - t.pivot.transpose();
  m.mpjpe_root_relative_mm = mean_joint_error_mm(p_rel, t_rel, mpu);
  const Vertices aligned = procrustes_aligned(p.body25, t.body25);
  m.pa_mpjpe_mm = mean_joint_error_mm(aligned, t.body25, mpu);
  m.joint_errors_root_relative_mm = joint_distances_mm(p_rel, t_rel, mpu);
  m.joint_errors_pa_mm = joint_distances_mm(aligned, t.body25, mpu);
  if (t.view_rotation) {
    const ViewErrorSplit split = view_error_split(p_rel, t_rel, *t.view_rotation, mpu);
    m.mpjpe_depth_mm = split.depth_mm, m.mpjpe_image_plane_mm = split.image_plane_mm;
  }
  if (p.root_rotation && t.root_rotation) {
    m.root_rotation_error_deg = rotation_error_deg(*p.root_rotation, *t.root_rotation);
    m.root_heading_error_deg = heading_error_deg(*p.root_rotation, *t.root_rotation);
    m.root_tilt_error_deg = tilt_error_deg(*p.root_rotation, *t.root_rotation);
  }
  m.trunk_direction_error_deg = trunk_direction_error_deg(p.body25, t.body25);
  m.body_distances_mm = vertex_distances_mm(p.body, t.body, mpu);
  m.body_error_mean_mm = mean_of(m.body_distances_mm);
  m.body_error_p95_mm = quantile(m.body_distances_mm, 0.95);
  if (p.cloth.rows() == 0) return;
  if (cloth_error) {
    WEFT_CHECK(ch.has_cloth(), "measure_geometry: a predicted cloth for a character without a garment");
    m.cloth_distances_mm = vertex_distances_mm(p.cloth, t.cloth, mpu);
    m.cloth_error_mean_mm = mean_of(m.cloth_distances_mm);
    m.cloth_error_p95_mm = quantile(m.cloth_distances_mm, 0.95);
    m.cloth_chamfer_mm = chamfer_distance_mm(p.cloth, t.cloth, ch.cloth->mesh.F, mpu);
  }
  measure_penetration(ch, p.body, p.cloth, m);
}

void measure_balance(const Character& ch, const SynthSimulationConfig& simulation, double fps,
                     const Vertices& body_prev, const Vertices& body, const Vertices& cloth_prev2,
                     const Vertices& cloth_prev, const Vertices& cloth, FrameMeasures& m, BalancePool* pool) {
  const ClothBalance cb =
      cloth_out_of_balance(ch, simulation, fps, body_prev, body, cloth_prev2, cloth_prev, cloth);
  const std::vector<double> depth = cloth_signed_distances_mm(ch, body, cloth);
  const physics::VertexBalance& vb = cb.vertices;
  std::vector<double> n, rel, outside;
  MeasuredMean inertia, elastic, collision, friction;
  for (int i : cb.free_vertices) {
    n.push_back(vb.residual[i]);
    rel.push_back(vb.weight[i] > 0 ? vb.residual[i] / vb.weight[i] : 0.0);
    if (depth[i] >= 0) outside.push_back(vb.residual[i]);
    inertia.add(vb.inertia[i]), elastic.add(vb.elastic[i]), collision.add(vb.collision[i]), friction.add(vb.friction[i]);
  }
  const Distribution d = distribution(n), r = distribution(rel);
  m.oob_force_mean_n = d.mean, m.oob_force_p95_n = d.p95, m.oob_force_p99_n = d.p99, m.oob_force_max_n = d.max;
  m.oob_force_mean_rel = r.mean, m.oob_force_max_rel = r.max;
  m.oob_force_outside_mean_n = mean_of(outside);
  m.oob_force_all_vertices_mean_n = cb.all.oob_force_mean, m.oob_force_all_vertices_max_n = cb.all.oob_force_max;
  m.inertia_mean_n = inertia.value(), m.elastic_mean_n = elastic.value(), m.collision_mean_n = collision.value(),
  m.friction_mean_n = friction.value();
  if (!pool) return;
  ++pool->frames;
  pool->n.insert(pool->n.end(), n.begin(), n.end());
  pool->rel.insert(pool->rel.end(), rel.begin(), rel.end());
  pool->outside_n.insert(pool->outside_n.end(), outside.begin(), outside.end());
  for (size_t i = 0; i < vb.residual.size(); ++i) {
    pool->all_n.push_back(vb.residual[i]);
    pool->all_rel.push_back(vb.weight[i] > 0 ? vb.residual[i] / vb.weight[i] : 0.0);
  }
  for (int i : cb.free_vertices)
    pool->inertia.add(vb.inertia[i]), pool->elastic.add(vb.elastic[i]), pool->collision.add(vb.collision[i]),
        pool->friction.add(vb.friction[i]);
}

void measure_ious(const std::vector<double>& iou, int input_view, FrameMeasures& m) {
  WEFT_CHECK(input_view >= 0 && input_view < int(iou.size()), "measure_ious: input view ", input_view, " of ",
             iou.size(), " views");
  MeasuredMean all, rest;
  for (size_t v = 0; v < iou.size(); ++v) {
    all.add(iou[v]);
    if (int(v) != input_view) rest.add(iou[v]);
  }
  m.amv_iou = all.value(), m.rv_iou = rest.value(), m.sv_iou = iou[input_view];
}

}  // namespace weft::capture
