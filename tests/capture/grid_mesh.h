#pragma once
// A flat grid of nx × ny vertices spanning `size` (character units) in the x-y plane from
// `origin`, two triangles per cell: the garment of the evaluation's constructed cases.
#include <Eigen/Core>

#include "geometry/mesh.h"

namespace weft::capture::testing {

inline TriangleMesh grid_mesh(const Eigen::Vector3d& origin, double size, int nx, int ny) {
  TriangleMesh m;
  m.V.resize(nx * ny, 3);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      m.V.row(j * nx + i) = (origin + Eigen::Vector3d(size * i / (nx - 1), size * j / (ny - 1), 0)).transpose();
  m.F.resize(2 * (nx - 1) * (ny - 1), 3);
  int f = 0;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      const int a = j * nx + i;
      m.F.row(f++) << a, a + 1, a + nx + 1;
      m.F.row(f++) << a, a + nx + 1, a + nx;
    }
  return m;
}

}  // namespace weft::capture::testing
