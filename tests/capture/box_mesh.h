#pragma once
// An axis-aligned box as a closed triangle mesh, outward-facing, for the capture tests.
#include <Eigen/Core>

#include "geometry/mesh.h"

namespace weft::capture::testing {

// The box from corner lo to corner hi: 8 vertices (vertex k takes hi's x when bit 0 of k is
// set, y for bit 1, z for bit 2), 12 triangles.
inline TriangleMesh box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  TriangleMesh m;
  m.V.resize(8, 3);
  for (int k = 0; k < 8; ++k)
    m.V.row(k) << (k & 1 ? hi.x() : lo.x()), (k & 2 ? hi.y() : lo.y()), (k & 4 ? hi.z() : lo.z());
  m.F.resize(12, 3);
  m.F << 0, 2, 1, 1, 2, 3, 4, 5, 6, 5, 7, 6, 0, 1, 4, 1, 5, 4, 2, 6, 3, 3, 6, 7, 0, 4, 2, 2, 4, 6, 1, 3, 5, 3, 7, 5;
  return m;
}

}  // namespace weft::capture::testing
