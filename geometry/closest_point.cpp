#include "geometry/closest_point.h"

#include <limits>

#include "graph/error.h"

namespace weft {

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                          Eigen::Vector3d& bary, TriangleFeature* feature) {
  const auto found = [&](TriangleFeature f, const Eigen::Vector3d& weights, const Eigen::Vector3d& q) {
    if (feature) *feature = f;
    bary = weights;
    return q;
  };
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return found(TriangleFeature::vertex0, {1, 0, 0}, a);
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return found(TriangleFeature::vertex1, {0, 1, 0}, b);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return found(TriangleFeature::edge01, {1 - v, v, 0}, a + v * ab);
  }
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return found(TriangleFeature::vertex2, {0, 0, 1}, c);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double w = d2 / (d2 - d6);
    return found(TriangleFeature::edge20, {1 - w, 0, w}, a + w * ac);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return found(TriangleFeature::edge12, {0, 1 - w, w}, b + w * (c - b));
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) return found(TriangleFeature::vertex0, {1, 0, 0}, a);  // zero area: the first vertex
  const double v = vb / sum, w = vc / sum;
  return found(TriangleFeature::face, {1 - v - w, v, w}, a + v * ab + w * ac);
}

ClosestTriangleQuery::ClosestTriangleQuery(const Vertices& V, const Faces& F)
    : V_(V), F_(F), centers_(F.rows(), 3), radii_(F.rows()) {
  if (F.rows() == 0) fail("closest-point query: the mesh has no triangles");
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d c = (V.row(F(f, 0)) + V.row(F(f, 1)) + V.row(F(f, 2))) / 3.0;
    centers_.row(f) = c;
    double r = 0;
    for (int k = 0; k < 3; ++k) r = std::max(r, (V.row(F(f, k)).transpose() - c).norm());
    radii_(f) = r;
  }
}

ClosestPoint ClosestTriangleQuery::closest(const Eigen::Vector3d& p) const {
  const Eigen::Index m = F_.rows();
  Eigen::VectorXd lower(m);
  Eigen::Index seed = 0;
  for (Eigen::Index f = 0; f < m; ++f) {
    lower(f) = std::max(0.0, (centers_.row(f).transpose() - p).norm() - radii_(f));
    if (lower(f) < lower(seed)) seed = f;
  }
  ClosestPoint best;
  double best_d2 = std::numeric_limits<double>::infinity();
  auto test = [&](Eigen::Index f) {
    Eigen::Vector3d bary;
    const Eigen::Vector3d q = closest_point_on_triangle(p, V_.row(F_(f, 0)), V_.row(F_(f, 1)),
                                                        V_.row(F_(f, 2)), bary);
    const double d2 = (q - p).squaredNorm();
    if (d2 < best_d2 || (d2 == best_d2 && f < best.face)) {
      best_d2 = d2;
      best.face = static_cast<int>(f);
      best.barycentric = bary;
      best.point = q;
    }
  };
  test(seed);
  for (Eigen::Index f = 0; f < m; ++f) {
    const double lb = lower(f);
    if (lb * lb <= best_d2 && f != seed) test(f);
  }
  best.distance = std::sqrt(best_d2);
  return best;
}

}  // namespace weft
