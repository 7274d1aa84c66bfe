#include "capture/garment.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "capture/body_skeleton_fit.h"
#include "capture/closest_point.h"
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
      if (s.lo.x() < 0 && s.hi.x() > 0 && (!best || s.area > best->area)) best = &s;
    if (!best) fail("garment: no body cross-section crosses x = 0 at the top height ", o.top_y);
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

}  // namespace weft::capture
