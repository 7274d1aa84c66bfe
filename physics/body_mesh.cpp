#include "physics/body_mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>

#include "geometry/closest_point.h"
#include "graph/error.h"

namespace weft::physics {

namespace {

double box_distance2(const Eigen::Vector3d& p, const Eigen::Vector3d& lo,
                     const Eigen::Vector3d& hi) {
  const Eigen::Vector3d d = (lo - p).cwiseMax(p - hi).cwiseMax(0.0);
  return d.squaredNorm();
}

}  // namespace

BodyMesh::BodyMesh(Eigen::MatrixX3d vertices, std::vector<std::array<int, 3>> faces,
                   std::vector<int> inactive_faces)
    : vertices_(std::move(vertices)), previous_vertices_(vertices_), faces_(std::move(faces)) {
  const int nv = static_cast<int>(vertices_.rows());
  std::vector<char> inactive(faces_.size(), 0);
  for (int f : inactive_faces) {
    WEFT_CHECK(f >= 0 && f < static_cast<int>(faces_.size()), "body mesh: inactive face ", f,
               " outside [0, ", faces_.size(), ")");
    inactive[f] = 1;
  }
  for (size_t f = 0; f < faces_.size(); ++f) {
    for (int v : faces_[f])
      WEFT_CHECK(v >= 0 && v < nv, "body mesh: face ", f, " has vertex ", v, " outside [0, ",
                 nv, ")");
    if (!inactive[f]) active_.push_back(static_cast<int>(f));
  }
  if (!active_.empty()) {
    nodes_.reserve(2 * active_.size());
    build(0, static_cast<int>(active_.size()));
  }
  // Edge ids of the active faces, once: the per-frame normals then sum into a vector
  // instead of a map (set_vertices runs every frame on a 27k-face body).
  std::map<std::pair<int, int>, int> edge_id;
  face_edges_.assign(faces_.size(), {-1, -1, -1});
  for (int f : active_)
    for (int k = 0; k < 3; ++k) {
      const int i = faces_[f][k], j = faces_[f][(k + 1) % 3];
      face_edges_[f][k] =
          edge_id.emplace(std::make_pair(std::min(i, j), std::max(i, j)), static_cast<int>(edge_id.size()))
              .first->second;
    }
  num_edges_ = static_cast<int>(edge_id.size());
  edge_vertices_.assign(num_edges_, {-1, -1});
  std::vector<int> edge_faces(num_edges_, 0);
  for (const auto& [ends, e] : edge_id) edge_vertices_[e] = {ends.first, ends.second};
  for (int f : active_)
    for (int e : face_edges_[f]) ++edge_faces[e];
  edge_weights_.resize(num_edges_);
  vertex_weights_.assign(nv, 1);
  for (int e = 0; e < num_edges_; ++e) {
    edge_weights_[e] = 1 - edge_faces[e];
    for (int v : edge_vertices_[e]) --vertex_weights_[v];  // − E_v
  }
  for (int f : active_)
    for (int v : faces_[f]) ++vertex_weights_[v];  // + F_v
  // A vertex of no active face is in no sum (1 + 0 − 0 would count it once).
  std::vector<char> used(nv, 0);
  for (int f : active_)
    for (int v : faces_[f]) used[v] = 1;
  for (int v = 0; v < nv; ++v)
    if (!used[v]) vertex_weights_[v] = 0;
  compute_normals();
}

int BodyMesh::build(int begin, int end) {
  const int id = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  Eigen::Vector3d clo = lo, chi = hi;  // centroid bounds
  for (int k = begin; k < end; ++k) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (int v : faces_[active_[k]]) {
      const Eigen::Vector3d p = vertices_.row(v).transpose();
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
      centroid += p / 3.0;
    }
    clo = clo.cwiseMin(centroid);
    chi = chi.cwiseMax(centroid);
  }
  nodes_[id].lo = lo;
  nodes_[id].hi = hi;
  if (end - begin <= 4) {
    nodes_[id].begin = begin;
    nodes_[id].end = end;
    return id;
  }
  int axis;
  (chi - clo).maxCoeff(&axis);
  const int mid = (begin + end) / 2;
  auto centroid_on = [&](int f) {
    double s = 0;
    for (int v : faces_[f]) s += vertices_(v, axis);
    return s;
  };
  std::nth_element(active_.begin() + begin, active_.begin() + mid, active_.begin() + end,
                   [&](int a, int b) { return centroid_on(a) < centroid_on(b); });
  const int left = build(begin, mid);
  const int right = build(mid, end);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

void BodyMesh::refit(int id) {
  Node& n = nodes_[id];
  if (n.left < 0) {
    n.lo = Eigen::Vector3d::Constant(1e300);
    n.hi = -n.lo;
    for (int k = n.begin; k < n.end; ++k)
      for (int v : faces_[active_[k]]) {
        n.lo = n.lo.cwiseMin(vertices_.row(v).transpose());
        n.hi = n.hi.cwiseMax(vertices_.row(v).transpose());
      }
    return;
  }
  refit(n.left);
  refit(n.right);
  n.lo = nodes_[n.left].lo.cwiseMin(nodes_[n.right].lo);
  n.hi = nodes_[n.left].hi.cwiseMax(nodes_[n.right].hi);
}

void BodyMesh::set_vertices(const Eigen::MatrixX3d& vertices) {
  set_vertices(vertices, vertices_);
}

void BodyMesh::set_vertices(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX3d& previous) {
  WEFT_CHECK(vertices.rows() == vertices_.rows() && previous.rows() == vertices_.rows(),
             "body mesh: ", vertices.rows(), " new vertices (", previous.rows(),
             " previous) for a mesh of ", vertices_.rows());
  // Either argument may alias a member (set_vertices(v) passes vertices_): copy first.
  Eigen::MatrixX3d now = vertices, before = previous;
  previous_vertices_ = std::move(before);
  vertices_ = std::move(now);
  if (!nodes_.empty()) refit(0);
  compute_normals();
}

void BodyMesh::compute_normals() {
  const int nv = static_cast<int>(vertices_.rows());
  face_normals_.assign(faces_.size(), Eigen::Vector3d::Zero());
  vertex_normals_.assign(nv, Eigen::Vector3d::Zero());
  edge_normals_.assign(faces_.size(), {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                       Eigen::Vector3d::Zero()});
  std::vector<Eigen::Vector3d> edge_sum(num_edges_, Eigen::Vector3d::Zero());
  for (int f : active_) {
    const auto& t = faces_[f];
    Eigen::Vector3d p[3];
    for (int k = 0; k < 3; ++k) p[k] = vertices_.row(t[k]).transpose();
    const Eigen::Vector3d n = (p[1] - p[0]).cross(p[2] - p[0]);
    const double len = n.norm();
    face_normals_[f] = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e1 = p[(k + 1) % 3] - p[k], e2 = p[(k + 2) % 3] - p[k];
      const double denom = e1.norm() * e2.norm();
      const double angle = denom > 0 ? std::acos(std::clamp(e1.dot(e2) / denom, -1.0, 1.0)) : 0;
      vertex_normals_[t[k]] += angle * face_normals_[f];
      edge_sum[face_edges_[f][k]] += face_normals_[f];
    }
  }
  for (auto& n : vertex_normals_)
    if (n.norm() > 0) n.normalize();
  // Folded: an incident face facing against the pseudo-normal, or incident faces facing so
  // many ways that their unit normals' mean is shorter than ½ (a fold, a spike's tip).
  folded_.assign(nv, 0);
  std::vector<Eigen::Vector3d> normal_sum(nv, Eigen::Vector3d::Zero());
  std::vector<int> incident(nv, 0);
  for (int f : active_)
    for (int v : faces_[f]) {
      if (face_normals_[f].dot(vertex_normals_[v]) < 0) folded_[v] = 1;
      normal_sum[v] += face_normals_[f];
      ++incident[v];
    }
  for (int v = 0; v < nv; ++v)
    if (incident[v] > 0 && normal_sum[v].norm() < 0.5 * incident[v]) folded_[v] = 1;
  for (int f : active_)
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& s = edge_sum[face_edges_[f][k]];
      edge_normals_[f][k] = s.norm() > 0 ? Eigen::Vector3d(s.normalized()) : face_normals_[f];
    }
}

template <class Bound, class Visit>
void BodyMesh::traverse(const Eigen::Vector3d& x, const Bound& bound2, const Visit& visit) const {
  if (nodes_.empty()) return;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (box_distance2(x, n.lo, n.hi) >= bound2()) continue;
    if (n.left < 0) {
      for (int k = n.begin; k < n.end; ++k) visit(active_[k]);
      continue;
    }
    // Visit the nearer child first (pushed last), so that a shrinking bound prunes more.
    const double dl = box_distance2(x, nodes_[n.left].lo, nodes_[n.left].hi);
    const double dr = box_distance2(x, nodes_[n.right].lo, nodes_[n.right].hi);
    if (dl < dr) {
      stack[top++] = n.right;
      stack[top++] = n.left;
    } else {
      stack[top++] = n.left;
      stack[top++] = n.right;
    }
  }
}

BodyMesh::FaceNear BodyMesh::near_face(const Eigen::Vector3d& x, int f) const {
  const auto& t = faces_[f];
  FaceNear near;
  near.face = f;
  Eigen::Vector3d barycentric;
  near.point = closest_point_on_triangle(x, vertices_.row(t[0]).transpose(), vertices_.row(t[1]).transpose(),
                                         vertices_.row(t[2]).transpose(), barycentric, &near.feature);
  near.distance2 = (x - near.point).squaredNorm();
  return near;
}

ClosestPoint BodyMesh::signed_closest_point(const Eigen::Vector3d& x, const FaceNear& near, Side known) const {
  ClosestPoint best;
  if (near.face < 0) return best;
  best.point = near.point;
  best.face = near.face;
  const auto& t = faces_[near.face];
  switch (near.feature) {
    case TriangleFeature::face: best.normal = face_normals_[near.face]; break;
    case TriangleFeature::edge01: best.normal = edge_normals_[near.face][0]; break;
    case TriangleFeature::edge12: best.normal = edge_normals_[near.face][1]; break;
    case TriangleFeature::edge20: best.normal = edge_normals_[near.face][2]; break;
    case TriangleFeature::vertex0: best.normal = vertex_normals_[t[0]]; break;
    case TriangleFeature::vertex1: best.normal = vertex_normals_[t[1]]; break;
    case TriangleFeature::vertex2: best.normal = vertex_normals_[t[2]]; break;
  }
  best.face_interior = near.feature == TriangleFeature::face;
  const int edge = near.feature == TriangleFeature::edge01   ? 0
                   : near.feature == TriangleFeature::edge12 ? 1
                   : near.feature == TriangleFeature::edge20 ? 2
                                                             : -1;
  if (edge >= 0) {
    best.on_edge = true;
    best.edge_direction = (vertices_.row(t[(edge + 1) % 3]) - vertices_.row(t[edge])).transpose().normalized();
  }
  const double unsigned_distance = std::sqrt(near.distance2);
  best.distance = (x - best.point).dot(best.normal) < 0 ? -unsigned_distance : unsigned_distance;
  // On a folded surface the pseudo-normal's sign is not to be trusted (see the header).
  if (best.distance < 0 && (folded_[t[0]] || folded_[t[1]] || folded_[t[2]]) &&
      (known == Side::unknown ? winding_number(x) < 0.5 : known == Side::outside)) {
    best.distance = unsigned_distance;
    best.normal = -best.normal;  // d = n·(x − p) inside a face, with d now > 0
  }
  return best;
}

double BodyMesh::winding_number(const Eigen::Vector3d& x) const {
  // Each triangle's signed solid angle Ω from x: tan(Ω/2) = a·(b×c) / (|a||b||c| + (a·b)|c| +
  // (b·c)|a| + (c·a)|b|), with a, b, c the corners relative to x.
  double sum = 0;
  for (const auto& t : faces_) {
    const Eigen::Vector3d a = vertices_.row(t[0]).transpose() - x, b = vertices_.row(t[1]).transpose() - x,
                          c = vertices_.row(t[2]).transpose() - x;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    sum += 2 * std::atan2(numerator, denominator);
  }
  return sum / (4 * M_PI);
}

template <class Accept>
ClosestPoint BodyMesh::closest_point_where(const Eigen::Vector3d& x, double max_distance, const Accept& accept,
                                           Side known) const {
  FaceNear best;
  best.distance2 = std::isfinite(max_distance) ? max_distance * max_distance : std::numeric_limits<double>::infinity();
  traverse(x, [&] { return best.distance2; }, [&](int f) {
    if (!accept(f)) return;
    const FaceNear near = near_face(x, f);
    if (near.distance2 < best.distance2) best = near;
  });
  return signed_closest_point(x, best, known);
}

ClosestPoint BodyMesh::closest_point(const Eigen::Vector3d& x, double max_distance, Side known) const {
  return closest_point_where(x, max_distance, [](int) { return true; }, known);
}

ClosestPoint BodyMesh::closest_point_and_faces_within(const Eigen::Vector3d& x, double band,
                                                      std::vector<FaceNear>& faces, Side known) const {
  faces.clear();
  const double band2 = band * band;
  FaceNear best;
  best.distance2 = std::numeric_limits<double>::infinity();
  traverse(x, [&] { return std::max(band2, best.distance2); }, [&](int f) {
    const FaceNear near = near_face(x, f);
    if (near.distance2 < band2) faces.push_back(near);
    if (near.distance2 < best.distance2) best = near;
  });
  return signed_closest_point(x, best, known);
}

ClosestPoint BodyMesh::closest_point_facing_away(const Eigen::Vector3d& x, double max_distance,
                                                 const Eigen::Vector3d& facing, double max_cos) const {
  return closest_point_where(
      x, max_distance, [&](int f) { return face_normals_[f].dot(facing) < max_cos; }, Side::unknown);
}

}  // namespace weft::physics
