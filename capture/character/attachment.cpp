#include "capture/character/attachment.h"

#include "geometry/closest_point.h"
#include "graph/error.h"

namespace weft::capture {

Vertices Attachment::targets(const Vertices& body_V) const {
  Vertices out(size(), 3);
  for (int i = 0; i < size(); ++i) {
    out.row(i).setZero();
    for (int k = 0; k < 3; ++k) out.row(i) += barycentric(i, k) * body_V.row(body_vertices(i, k));
  }
  return out;
}

Attachment attach_to_body(const TriangleMesh& body, const TriangleMesh& cloth,
                          const std::vector<int>& anchors) {
  Attachment a;
  const int n = static_cast<int>(anchors.size());
  a.anchors.resize(n);
  a.triangles.resize(n);
  a.body_vertices.resize(n, 3);
  a.barycentric.resize(n, 3);
  a.rest_distance.resize(n);
  if (n == 0) return a;
  const ClosestTriangleQuery query(body.V, body.F);
  for (int i = 0; i < n; ++i) {
    const int v = anchors[i];
    if (v < 0 || v >= cloth.num_vertices())
      fail("attachment: anchor vertex ", v, " out of range (cloth has ", cloth.num_vertices(), " vertices)");
    const ClosestPoint cp = query.closest(cloth.V.row(v).transpose());
    a.anchors(i) = v;
    a.triangles(i) = cp.face;
    a.body_vertices.row(i) = body.F.row(cp.face);
    a.barycentric.row(i) = cp.barycentric.transpose();
    a.rest_distance(i) = cp.distance;
  }
  return a;
}

}  // namespace weft::capture
