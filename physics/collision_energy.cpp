#include "physics/collision_energy.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "geometry/closest_point.h"
#include "graph/error.h"

namespace weft::physics {

DistanceSample signed_distance(const SphereObstacle& sphere, const Eigen::Vector3d& x) {
  DistanceSample s;
  const Eigen::Vector3d r = x - sphere.center;
  const double len = r.norm();
  s.distance = len - sphere.radius;
  if (len > 1e-12) {
    s.gradient = r / len;
    s.hessian = (Eigen::Matrix3d::Identity() - s.gradient * s.gradient.transpose()) / len;
  } else {
    s.gradient = Eigen::Vector3d::UnitY();  // any direction out of the centre
  }
  return s;
}

DistanceSample signed_distance(const BodyMesh& body, const Eigen::Vector3d& x, BodyMesh::Side known) {
  return signed_distance(body.closest_point(x, std::numeric_limits<double>::infinity(), known), x);
}

DistanceSample signed_distance(const ClosestPoint& c, const Eigen::Vector3d& x) {
  DistanceSample s;
  if (c.face < 0) return s;
  s.distance = c.distance;
  const Eigen::Vector3d r = x - c.point;
  const double len = r.norm();
  if (c.face_interior || len < 1e-12) {
    s.gradient = c.normal;  // d = n·(x − p) is linear in x inside a face
  } else {
    const double sign = c.distance < 0 ? -1.0 : 1.0;
    const Eigen::Vector3d u = r / len;
    s.gradient = sign * u;
    // Curvature of the distance: none along an edge the closest point slides on.
    Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - u * u.transpose();
    if (c.on_edge) p -= c.edge_direction * c.edge_direction.transpose();
    s.hessian = sign * p / len;
  }
  return s;
}

CollisionEnergy::CollisionEnergy(int num_vertices, double thickness, double stiffness)
    : n_(num_vertices), thickness_(thickness), k_(stiffness) {
  WEFT_CHECK(thickness > 0, "collision: thickness must be > 0 m, got ", thickness);
  WEFT_CHECK(stiffness > 0, "collision: stiffness must be > 0 N/m, got ", stiffness);
}

void CollisionEnergy::set_second_sheet_angle(double degrees) {
  WEFT_CHECK(std::isfinite(degrees) && degrees >= 0 && degrees < 180,
             "collision: second_sheet_angle must be in [0, 180) degrees (0: off), got ", degrees);
  second_sheet_deg_ = degrees;
  second_sheet_cos_ = degrees > 0 ? std::cos(degrees * M_PI / 180.0) : 2.0;
}

void CollisionEnergy::set_bodies(std::vector<const BodyMesh*> bodies) {
  bodies_ = std::move(bodies);
  invalidate_cache();
}

void CollisionEnergy::invalidate_cache() {
  cache_.assign(bodies_.size(), std::vector<CacheEntry>(n_));
}

double CollisionEnergy::add_penalty(int i, const DistanceSample& s, Eigen::VectorXd* g,
                                    SparseHessian* H) const {
  if (!(s.distance < thickness_)) return 0.0;
  // E = k/(6δ)·gap³ with gap = δ − d: dE/dgap = k/(2δ)·gap², d²E/dgap² = k/δ·gap, and
  // ∂gap/∂x = −∇d.
  const double gap = thickness_ - s.distance;
  const double c = k_ / thickness_;
  const double de = 0.5 * c * gap * gap;
  if (g) g->segment<3>(3 * i) -= de * s.gradient;
  if (H) {
    Eigen::Matrix3d h = c * gap * (s.gradient * s.gradient.transpose()) - de * s.hessian;
    if (project_hessian_) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(h);
      h = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() *
          eig.eigenvectors().transpose();
    }
    H->add_diagonal_block(i, h);
  }
  return c / 6.0 * gap * gap * gap;
}

namespace {

// Unsigned distance of x to a point p of a feature, with the feature's curvature: none on a
// face's interior, none along an edge (direction e, unit) the closest point slides on.
DistanceSample unsigned_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& p, const Eigen::Vector3d* edge) {
  DistanceSample s;
  const Eigen::Vector3d r = x - p;
  s.distance = r.norm();
  if (!(s.distance > 1e-12)) return s;  // on the feature: no direction; the caller skips it
  s.gradient = r / s.distance;
  s.hessian = Eigen::Matrix3d::Identity() - s.gradient * s.gradient.transpose();
  if (edge) s.hessian -= *edge * edge->transpose();
  s.hessian /= s.distance;
  return s;
}

}  // namespace

void CollisionEnergy::accumulate_penalty(double w, const DistanceSample& s, double& e, Eigen::Vector3d& g,
                                         Eigen::Matrix3d& h) const {
  if (!(s.distance < thickness_) || w == 0) return;
  const double gap = thickness_ - s.distance;
  const double c = k_ / thickness_;
  const double de = 0.5 * c * gap * gap;
  e += w * c / 6.0 * gap * gap * gap;
  g -= w * de * s.gradient;
  h += w * (c * gap * (s.gradient * s.gradient.transpose()) - de * s.hessian);
}

double CollisionEnergy::add_feature_sum(int i, const Eigen::Vector3d& x, const BodyMesh& body,
                                        const std::vector<BodyMesh::FaceNear>& faces, Eigen::VectorXd* g,
                                        SparseHessian* H) const {
  thread_local std::vector<int> edges, vertices;
  edges.clear();
  vertices.clear();
  double e = 0;
  Eigen::Vector3d gi = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hi = Eigen::Matrix3d::Zero();
  const Eigen::MatrixX3d& V = body.vertices();
  auto vertex = [&](int v) -> Eigen::Vector3d { return V.row(v).transpose(); };
  for (const BodyMesh::FaceNear& near : faces) {
    const int f = near.face;
    const auto& t = body.faces()[f];
    const TriangleFeature feature = near.feature;
    const Eigen::Vector3d& p = near.point;
    Eigen::Vector3d along;
    const Eigen::Vector3d* edge = nullptr;
    if (feature == TriangleFeature::edge01 || feature == TriangleFeature::edge12 || feature == TriangleFeature::edge20) {
      const int k = feature == TriangleFeature::edge01 ? 0 : feature == TriangleFeature::edge12 ? 1 : 2;
      along = (vertex(t[(k + 1) % 3]) - vertex(t[k])).normalized();
      edge = &along;
    }
    const DistanceSample s = unsigned_distance(x, p, feature == TriangleFeature::face ? nullptr : edge);
    // On a face's interior the distance is the plane's: no curvature.
    if (feature == TriangleFeature::face) {
      DistanceSample plane = s;
      plane.hessian.setZero();
      accumulate_penalty(1.0, plane, e, gi, hi);
    } else {
      accumulate_penalty(1.0, s, e, gi, hi);
    }
    for (int k = 0; k < 3; ++k) {
      edges.push_back(body.face_edges(f)[k]);
      vertices.push_back(t[k]);
    }
  }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  std::sort(vertices.begin(), vertices.end());
  vertices.erase(std::unique(vertices.begin(), vertices.end()), vertices.end());
  for (int ed : edges) {
    const int w = body.edge_weight(ed);
    if (w == 0) continue;
    const Eigen::Vector3d a = vertex(body.edge_vertices(ed)[0]), b = vertex(body.edge_vertices(ed)[1]);
    const Eigen::Vector3d ab = b - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 0 ? std::clamp((x - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    const Eigen::Vector3d along = len2 > 0 ? Eigen::Vector3d(ab / std::sqrt(len2)) : Eigen::Vector3d::Zero();
    const bool inside = t > 0 && t < 1;
    accumulate_penalty(w, unsigned_distance(x, a + t * ab, inside ? &along : nullptr), e, gi, hi);
  }
  for (int v : vertices)
    if (const int w = body.vertex_weight(v); w != 0) accumulate_penalty(w, unsigned_distance(x, vertex(v), nullptr), e, gi, hi);
  if (g) g->segment<3>(3 * i) += gi;
  if (H) {
    if (project_hessian_) {
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(hi);
      hi = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    }
    H->add_diagonal_block(i, hi);
  }
  return e;
}

double CollisionEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                                 SparseHessian* H) const {
  if (H && secant_stiffness_) {
    // Keep this Hessian's own gradient for adjust_hessian, which follows at the same x.
    hessian_x_ = x;
    hessian_gradient_.setZero(x.size());
    const double e = evaluate_terms(x, &hessian_gradient_, H);
    if (g) *g += hessian_gradient_;
    return e;
  }
  return evaluate_terms(x, g, H);
}

double CollisionEnergy::evaluate_terms(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                                       SparseHessian* H) const {
  double energy = 0;
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d xi = x.segment<3>(3 * i);
    for (const auto& sphere : spheres_) energy += add_penalty(i, signed_distance(sphere, xi), g, H);
    for (size_t b = 0; b < bodies_.size(); ++b) {
      CacheEntry& c = cache_[b][i];
      if (c.d_ref > thickness_ && (xi - c.x_ref).norm() < c.d_ref - thickness_) continue;
      // With smooth creases one walk of the tree also gathers the faces within the band.
      thread_local std::vector<BodyMesh::FaceNear> near;
      const BodyMesh::Side known = c.side(xi);
      const ClosestPoint cp = smooth_creases_
                                  ? bodies_[b]->closest_point_and_faces_within(xi, thickness_, near, known)
                                  : bodies_[b]->closest_point(xi, std::numeric_limits<double>::infinity(), known);
      const DistanceSample s = signed_distance(cp, xi);
      c.x_ref = xi;
      c.d_ref = s.distance;
      if (smooth_creases_ && s.distance > 0 && s.distance < thickness_) {
        energy += add_feature_sum(i, xi, *bodies_[b], near, g, H);
        continue;
      }
      energy += add_penalty(i, s, g, H);
      if (second_sheet_cos_ <= 1 && cp.face >= 0 && s.distance < thickness_) {
        const ClosestPoint other = bodies_[b]->closest_point_facing_away(
            xi, thickness_, bodies_[b]->face_normal(cp.face), second_sheet_cos_);
        if (other.face >= 0) energy += add_penalty(i, signed_distance(other, xi), g, H);
      }
    }
  }
  return energy;
}

void CollisionEnergy::adjust_hessian(const Eigen::VectorXd& x, const Eigen::VectorXd& g,
                                     SparseHessian& H) const {
  if (!secant_stiffness_) return;
  if (hessian_x_.size() != x.size() || hessian_x_ != x) {  // not the x of the last Hessian
    hessian_x_ = x;
    hessian_gradient_.setZero(x.size());
    evaluate_terms(x, &hessian_gradient_, nullptr);
  }
  const Eigen::VectorXd& own = hessian_gradient_;
  const double c = 0.5 * k_ / thickness_;  // force = c·gap² (N)
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d f = -own.segment<3>(3 * i);  // the collision force on vertex i
    const double f0 = f.norm();
    if (!(f0 > 0)) continue;
    const Eigen::Vector3d n = f / f0;
    const double gap0 = std::sqrt(f0 / c);
    const double push = (g.segment<3>(3 * i) + f).dot(n);  // the rest's force toward the obstacle
    const double gap_balance = push > 0 ? std::sqrt(push / c) : 0.0;
    // The normal stiffness 2c·gap₀ in H becomes c·(gap₀ + gap*).
    H.add_diagonal_block(i, (c * (gap_balance - gap0)) * (n * n.transpose()));
  }
}

void CollisionEnergy::step_bound_samples(int i, const Eigen::Vector3d& xi, double reach,
                                         std::vector<DistanceSample>& out) const {
  out.clear();
  for (const auto& sphere : spheres_) out.push_back(signed_distance(sphere, xi));
  for (size_t b = 0; b < bodies_.size(); ++b) {
    CacheEntry& c = cache_[b][i];
    // 1-Lipschitz: a vertex that cannot get within ½δ of the body needs no query.
    if (c.d_ref - (xi - c.x_ref).norm() - reach >= 0.5 * thickness_) continue;
    const DistanceSample s = signed_distance(*bodies_[b], xi, c.side(xi));
    c.x_ref = xi;
    c.d_ref = s.distance;
    out.push_back(s);
  }
}

void CollisionEnergy::limit_vertex_steps(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                                         Eigen::VectorXd& limits) const {
  thread_local std::vector<DistanceSample> samples;
  const double target = 0.5 * thickness_;
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d xi = x.segment<3>(3 * i), step = dx.segment<3>(3 * i);
    step_bound_samples(i, xi, step.norm(), samples);
    for (const DistanceSample& s : samples) {
      // Inside the band the penalty's own Hessian already shapes the Newton step.
      if (!(s.distance >= thickness_)) continue;
      const double approach = -s.gradient.dot(step);
      if (approach > 0 && s.distance - approach < target)
        limits[i] = std::min(limits[i], (s.distance - target) / approach);
    }
  }
}

void CollisionEnergy::clip_vertex_steps(const Eigen::VectorXd& x, Eigen::VectorXd& dx) const {
  if (!planar_step_bounds_) {
    Energy::clip_vertex_steps(x, dx);
    return;
  }
  thread_local std::vector<DistanceSample> samples;
  const double target = 0.5 * thickness_;  // m, the closest a move may bring a vertex
  const double slide = 2.0 * thickness_;    // m, see the header
  for (int i = 0; i < n_; ++i) {
    const Eigen::Vector3d xi = x.segment<3>(3 * i);
    Eigen::Vector3d step = dx.segment<3>(3 * i);
    step_bound_samples(i, xi, step.norm(), samples);
    bool clipped = false;
    double nearest = std::numeric_limits<double>::infinity();  // m, over the bounding planes
    for (const DistanceSample& s : samples) {
      if (!(s.distance >= thickness_)) continue;  // in the band: the penalty's Hessian
      const double excess = -s.gradient.dot(step) - (s.distance - target);  // m past the plane's bound
      if (excess > 0) {
        step += excess * s.gradient;  // only the normal component changes
        clipped = true;
      }
      nearest = std::min(nearest, s.distance);
    }
    if (!clipped) continue;
    double alpha = 1.0;  // a projection onto one plane may approach another
    for (const DistanceSample& s : samples) {
      if (!(s.distance >= thickness_)) continue;
      const double approach = -s.gradient.dot(step);
      if (approach > s.distance - target) alpha = std::min(alpha, (s.distance - target) / approach);
    }
    const double cap = std::max(nearest - target, slide);
    const double length = alpha * step.norm();
    if (length > cap) alpha *= cap / length;
    dx.segment<3>(3 * i) = std::max(alpha, 0.0) * step;
  }
}

std::string CollisionEnergy::describe_vertex(const Eigen::VectorXd& x, int i) const {
  const Eigen::Vector3d xi = x.segment<3>(3 * i);
  std::string out;
  char buf[160];
  for (size_t b = 0; b < bodies_.size(); ++b) {
    const ClosestPoint cp = bodies_[b]->closest_point(xi);
    if (cp.face < 0) continue;
    const char* where = cp.face_interior ? "interior" : cp.on_edge ? "edge" : "vertex";
    std::snprintf(buf, sizeof buf, "[body %zu face %d %s d %.3f mm", b, cp.face, where, 1e3 * cp.distance);
    out += buf;
    const Eigen::Vector3d& n = bodies_[b]->face_normal(cp.face);
    for (double deg : {5.0, 20.0, second_sheet_deg_}) {
      if (!(deg > 0)) continue;
      const ClosestPoint o = bodies_[b]->closest_point_facing_away(xi, 2 * thickness_, n, std::cos(deg * M_PI / 180));
      if (o.face < 0) continue;
      const double angle = std::acos(std::clamp(n.dot(bodies_[b]->face_normal(o.face)), -1.0, 1.0)) * 180 / M_PI;
      std::snprintf(buf, sizeof buf, "; >%.0f°: face %d at %.1f° d %.3f mm", deg, o.face, angle, 1e3 * o.distance);
      out += buf;
    }
    out += "]";
  }
  return out;
}

double CollisionEnergy::min_signed_distance(const Eigen::Vector3d& x) const {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& sphere : spheres_) d = std::min(d, signed_distance(sphere, x).distance);
  for (const BodyMesh* body : bodies_) d = std::min(d, signed_distance(*body, x).distance);
  return d;
}

}  // namespace weft::physics
