#include "capture/character/garment.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "capture/character/body_skeleton_fit.h"
#include "geometry/closest_point.h"
#include "graph/error.h"

namespace weft::capture {

using Eigen::Vector3d;

Eigen::VectorXd signed_distances(const TriangleMesh& body, const Vertices& points) {
  const ClosestTriangleQuery query(body.V, body.F);
  Eigen::VectorXd d(points.rows());
  tbb::parallel_for(tbb::blocked_range<Eigen::Index>(0, points.rows()), [&](const auto& r) {
    for (Eigen::Index i = r.begin(); i != r.end(); ++i) {
      const Vector3d p = points.row(i).transpose();
      const double dist = query.closest(p).distance;
      d(i) = inside_mesh(body.V, body.F, p) ? -dist : dist;
    }
  });
  return d;
}

namespace {

// The body without the excluded vertices' faces: what the garment must clear.
TriangleMesh kept_part(const TriangleMesh& body, const std::vector<char>& excluded) {
  if (excluded.empty()) return body;
  std::vector<int> faces;
  for (int f = 0; f < body.num_faces(); ++f) {
    bool all = true;
    for (int k = 0; k < 3; ++k) all = all && excluded[body.F(f, k)];
    if (!all) faces.push_back(f);
  }
  TriangleMesh out;
  out.V = body.V;
  out.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i) out.F.row(static_cast<Eigen::Index>(i)) = body.F.row(faces[i]);
  return out;
}

}  // namespace

TubeGarment generate_tube_garment(const TriangleMesh& body, const std::vector<char>& excluded,
                                  const TubeGarmentOptions& o) {
  if (o.segments < 8 || o.rings < 2) fail("garment: need at least 8 segments and 2 rings");
  if (!(o.length > 0) || !(o.clearance > 0) || !(o.flare >= 0)) fail("garment: length and clearance must be positive, flare ≥ 0");
  if (!excluded.empty() && static_cast<int>(excluded.size()) != body.num_vertices())
    fail("garment: excluded has ", excluded.size(), " entries, expected one per body vertex (", body.num_vertices(), ")");
  const int S = o.segments, R = o.rings;
  const double dy = o.length / (R - 1);
  const double two_pi = 2 * std::numbers::pi;

  // Axis: the centroid of the midline section at the top.
  TubeGarment g;
  {
    const auto sections = slice_mesh(body, Vector3d::UnitY(), o.top_y);
    const Section* best = nullptr;
    for (const Section& s : sections)
      if (s.lo.x() < o.mid_x && s.hi.x() > o.mid_x && (!best || s.area > best->area)) best = &s;
    if (!best) fail("garment: no body cross-section crosses x = ", o.mid_x, " at the top height ", o.top_y);
    g.centre = Eigen::Vector2d(best->centroid.x(), best->centroid.z());
  }

  // Body extent per ring and angle bin: the largest radius of a kept vertex within ±dy
  // (and ±clearance) of the ring's height, spread to the neighbouring bins so that the
  // surface between vertices is covered.
  const double band = std::max(dy, o.clearance);
  Eigen::MatrixXd extent = Eigen::MatrixXd::Zero(R, S);
  for (int v = 0; v < body.num_vertices(); ++v) {
    if (!excluded.empty() && excluded[v]) continue;
    const double y = body.V(v, 1);
    if (y > o.top_y + band || y < o.top_y - o.length - band) continue;
    const double x = body.V(v, 0) - g.centre.x(), z = body.V(v, 2) - g.centre.y();
    const double rho = std::hypot(x, z);
    double a = std::atan2(z, x);
    if (a < 0) a += two_pi;
    const int bin = static_cast<int>(std::floor(a / two_pi * S)) % S;
    const int i0 = std::max(0, static_cast<int>(std::ceil((o.top_y - y - band) / dy)));
    const int i1 = std::min(R - 1, static_cast<int>(std::floor((o.top_y - y + band) / dy)));
    for (int i = i0; i <= i1; ++i)
      for (int k = -1; k <= 2; ++k) {  // bins bin-1 .. bin+2 cover both edges of the vertex's bin
        double& e = extent(i, ((bin + k) % S + S) % S);
        e = std::max(e, rho);
      }
  }

  // Radii: clear the body, never shrink going down, plus the flare; then smooth around
  // each ring without going below the bound.
  Eigen::MatrixXd radius(R, S);
  for (int i = 0; i < R; ++i)
    for (int k = 0; k < S; ++k) {
      const double need = extent(i, k) + o.clearance;
      radius(i, k) = i == 0 ? need : std::max(need, radius(i - 1, k) + o.flare * dy);
    }
  for (int i = 0; i < R; ++i)
    for (int pass = 0; pass < 3; ++pass) {
      Eigen::VectorXd row = radius.row(i).transpose(), smooth(S);
      for (int k = 0; k < S; ++k)
        smooth(k) = 0.25 * row((k + S - 1) % S) + 0.5 * row(k) + 0.25 * row((k + 1) % S);
      for (int k = 0; k < S; ++k) radius(i, k) = std::max(smooth(k), row(k));
    }

  TriangleMesh& m = g.mesh;
  m.V.resize(R * S, 3);
  for (int i = 0; i < R; ++i)
    for (int k = 0; k < S; ++k) {
      const double a = two_pi * k / S;
      m.V.row(i * S + k) << g.centre.x() + radius(i, k) * std::cos(a), o.top_y - i * dy,
          g.centre.y() + radius(i, k) * std::sin(a);
    }
  // Angle grows from +x toward +z: (a, b, c) and (b, d, c) face outward.
  m.F.resize(2 * (R - 1) * S, 3);
  for (int i = 0; i + 1 < R; ++i)
    for (int k = 0; k < S; ++k) {
      const int a = i * S + k, b = i * S + (k + 1) % S, c = a + S, d = b + S;
      m.F.row(2 * (i * S + k)) << a, b, c;
      m.F.row(2 * (i * S + k) + 1) << b, d, c;
    }
  for (int k = 0; k < S; ++k) g.anchors.push_back(k);

  // Push vertices that are too close to the kept body straight outward (a few rounds).
  const TriangleMesh kept = kept_part(body, excluded);
  const ClosestTriangleQuery query(kept.V, kept.F);
  Eigen::VectorXd dist(m.num_vertices());
  for (int round = 0; round < 8; ++round) {
    tbb::parallel_for(tbb::blocked_range<int>(0, m.num_vertices()), [&](const auto& r) {
      for (int v = r.begin(); v != r.end(); ++v) dist(v) = query.closest(m.V.row(v).transpose()).distance;
    });
    int moved = 0;
    for (int v = 0; v < m.num_vertices(); ++v) {
      const Vector3d p = m.V.row(v).transpose();
      const double d = dist(v);
      if (d >= o.clearance) continue;
      Eigen::Vector2d dir(p.x() - g.centre.x(), p.z() - g.centre.y());
      dir.normalize();
      const double push = 1.05 * (o.clearance - d) + 1e-4 * o.clearance;
      m.V(v, 0) += push * dir.x();
      m.V(v, 2) += push * dir.y();
      ++moved;
    }
    if (!moved) break;
  }
  validate_mesh(m, "garment");
  const Eigen::VectorXd sd = signed_distances(body, m.V);
  g.min_distance = sd.cwiseAbs().minCoeff();
  g.inside = static_cast<int>((sd.array() < 0).count());
  return g;
}

void add_shoulder_strap(TubeGarment& g, const TriangleMesh& body, double xs, double clearance, double anchor_y,
                        int S) {
  TriangleMesh& m = g.mesh;
  if (m.num_vertices() < S) fail("shoulder strap: the garment has no top ring of ", S, " vertices");
  const double top_y = m.V(0, 1), cz = g.centre.y();
  // The two top-ring vertices nearest to x = xs at the front (or back), sorted by x.
  auto pick = [&](double side) {
    int best = -1;
    for (int k = 0; k < S; ++k)
      if ((m.V(k, 2) - cz) * side > 0 && (best < 0 || std::abs(m.V(k, 0) - xs) < std::abs(m.V(best, 0) - xs))) best = k;
    if (best < 0) fail("shoulder strap: no top-ring vertex on that side");
    const int a = (best + 1) % S, b = (best + S - 1) % S;
    const int other = std::abs(m.V(a, 0) - xs) < std::abs(m.V(b, 0) - xs) ? a : b;
    return m.V(best, 0) < m.V(other, 0) ? std::pair<int, int>{best, other} : std::pair<int, int>{other, best};
  };
  const auto [f1, f2] = pick(1.0);
  const auto [b1, b2] = pick(-1.0);

  // The body's contour in the plane x = xs that reaches highest: its part above the top
  // ring is the way over the shoulder.
  const auto sections = slice_mesh(body, Vector3d::UnitX(), xs);
  const Section* sec = nullptr;
  for (const Section& c : sections)
    if (c.lo.y() < top_y && c.hi.y() > top_y && (!sec || c.hi.y() > sec->hi.y())) sec = &c;
  if (!sec) fail("shoulder strap: the plane x = ", xs, " does not cross the body above the top ring");
  const auto& P = sec->points;
  const int n = static_cast<int>(P.size());
  // The longest run of consecutive contour points above the top ring.
  int best_start = -1, best_len = 0;
  for (int i = 0; i < n; ++i) {
    if (!(P[i].y() > top_y && P[(i + n - 1) % n].y() <= top_y)) continue;
    int len = 0;
    while (len < n && P[(i + len) % n].y() > top_y) ++len;
    if (len > best_len) best_len = len, best_start = i;
  }
  if (best_len < 3) fail("shoulder strap: the body does not rise above the top ring at x = ", xs);
  std::vector<Vector3d> arc;
  for (int k = 0; k < best_len; ++k) {
    const int i = (best_start + k) % n;
    // Outward normal in the plane: perpendicular to the contour, away from its centroid.
    const Vector3d t = P[(i + 1) % n] - P[(i + n - 1) % n];
    Vector3d nrm(0, -t.z(), t.y());
    if (nrm.dot(P[i] - sec->centroid) < 0) nrm = -nrm;
    arc.push_back(P[i] + 1.5 * clearance * nrm.normalized());
  }
  if (arc.front().z() < arc.back().z()) std::reverse(arc.begin(), arc.end());  // front to back

  const Vector3d F1 = m.V.row(f1), F2 = m.V.row(f2), B1 = m.V.row(b1), B2 = m.V.row(b2);
  std::vector<Vector3d> path{0.5 * (F1 + F2)};
  path.insert(path.end(), arc.begin(), arc.end());
  path.push_back(0.5 * (B1 + B2));
  std::vector<double> at{0};
  for (size_t i = 1; i < path.size(); ++i) at.push_back(at.back() + (path[i] - path[i - 1]).norm());
  const double spacing = std::max(1e-6, (F2 - F1).norm());
  const int N = std::max(3, static_cast<int>(std::ceil(at.back() / spacing)) + 1);
  auto point_at = [&](double s) {
    size_t i = 1;
    while (i + 1 < at.size() && at[i] < s) ++i;
    const double u = at[i] > at[i - 1] ? (s - at[i - 1]) / (at[i] - at[i - 1]) : 0;
    return Vector3d(path[i - 1] + std::clamp(u, 0.0, 1.0) * (path[i] - path[i - 1]));
  };

  // Stations 0 and N−1 are the ring vertices; the others are new.
  std::vector<std::array<int, 2>> station(N);
  station[0] = {f1, f2};
  station[N - 1] = {b1, b2};
  const int first_new = m.num_vertices();
  m.V.conservativeResize(first_new + 2 * (N - 2), 3);
  for (int i = 1; i + 1 < N; ++i) {
    const double t = static_cast<double>(i) / (N - 1);
    const Vector3d c = point_at(t * at.back());
    const Vector3d a = (1 - t) * (F1 - path.front()) + t * (B1 - path.back());
    const Vector3d b = (1 - t) * (F2 - path.front()) + t * (B2 - path.back());
    const int va = first_new + 2 * (i - 1);
    m.V.row(va) = (c + a).transpose();
    m.V.row(va + 1) = (c + b).transpose();
    station[i] = {va, va + 1};
  }
  const int first_face = m.num_faces();
  m.F.conservativeResize(first_face + 2 * (N - 1), 3);
  for (int i = 0; i + 1 < N; ++i) {
    const auto [a0, b0] = station[i];
    const auto [a1, b1n] = station[i + 1];
    m.F.row(first_face + 2 * i) << a0, b0, a1;
    m.F.row(first_face + 2 * i + 1) << b0, b1n, a1;
  }
  // Push new vertices that are too close along the direction away from the body.
  const ClosestTriangleQuery query(body.V, body.F);
  for (int round = 0; round < 8; ++round) {
    int moved = 0;
    for (int v = first_new; v < m.num_vertices(); ++v) {
      const Vector3d p = m.V.row(v).transpose();
      const ClosestPoint c = query.closest(p);
      if (c.distance >= clearance) continue;
      m.V.row(v) += ((p - c.point).normalized() * (1.05 * (clearance - c.distance) + 1e-4 * clearance)).transpose();
      ++moved;
    }
    if (!moved) break;
  }
  // Outward triangles: flip the strap if its faces mostly point toward the body.
  const Vertices N_f = face_normals(m.V, m.F);
  int inward = 0;
  for (int f = first_face; f < m.num_faces(); ++f) {
    const Vector3d c = (m.V.row(m.F(f, 0)) + m.V.row(m.F(f, 1)) + m.V.row(m.F(f, 2))).transpose() / 3;
    inward += N_f.row(f).dot(c - query.closest(c).point) < 0;
  }
  if (2 * inward > m.num_faces() - first_face)
    for (int f = first_face; f < m.num_faces(); ++f) std::swap(m.F(f, 1), m.F(f, 2));
  for (int v = first_new; v < m.num_vertices(); ++v)
    if (m.V(v, 1) > anchor_y) g.anchors.push_back(v);
  validate_mesh(m, "garment with straps");
  const Eigen::VectorXd sd = signed_distances(body, m.V);
  g.min_distance = sd.cwiseAbs().minCoeff();
  g.inside = static_cast<int>((sd.array() < 0).count());
}

}  // namespace weft::capture
