#include "physics/cloth_model.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include "graph/error.h"

namespace weft::physics {

const char* to_string(MembraneModel model) {
  return model == MembraneModel::stvk ? "stvk" : "tension_field";
}

void validate(const ClothMaterial& m) {
  WEFT_CHECK(std::isfinite(m.density) && m.density > 0, "cloth material: density must be > 0 kg/m², got ", m.density);
  WEFT_CHECK(std::isfinite(m.youngs_modulus) && m.youngs_modulus >= 0,
             "cloth material: youngs_modulus must be >= 0 Pa, got ", m.youngs_modulus);
  WEFT_CHECK(std::isfinite(m.poisson_ratio) && m.poisson_ratio >= 0 && m.poisson_ratio < 0.5,
             "cloth material: poisson_ratio must be in [0, 0.5), got ", m.poisson_ratio);
  WEFT_CHECK(std::isfinite(m.bending_stiffness) && m.bending_stiffness >= 0,
             "cloth material: bending_stiffness must be >= 0 N·m, got ", m.bending_stiffness);
  WEFT_CHECK(std::isfinite(m.thickness) && m.thickness > 0,
             "cloth material: thickness must be > 0 m, got ", m.thickness);
  WEFT_CHECK(std::isfinite(m.compression_ratio) && m.compression_ratio >= 0 && m.compression_ratio <= 1,
             "cloth material: compression_ratio must be in [0, 1], got ", m.compression_ratio);
  WEFT_CHECK(std::isfinite(m.min_area_ratio) && m.min_area_ratio >= 0 && m.min_area_ratio < 1,
             "cloth material: min_area_ratio must be in [0, 1), got ", m.min_area_ratio);
}

ClothMesh make_cloth_mesh(const Positions& rest, std::vector<std::array<int, 3>> triangles,
                          double density) {
  WEFT_CHECK(rest.size() % 3 == 0, "cloth mesh: positions size ", rest.size(), " is not 3n");
  ClothMesh mesh;
  mesh.rest = rest;
  mesh.triangles = std::move(triangles);
  const int n = mesh.num_vertices();
  mesh.mass = Eigen::VectorXd::Zero(n);
  // Interior edge -> the triangles on each side, in the order they were met.
  std::map<std::pair<int, int>, std::vector<int>> edge_faces;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& f = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) {
      WEFT_CHECK(f[k] >= 0 && f[k] < n, "cloth mesh: triangle ", t, " has vertex ", f[k],
                 " outside [0, ", n, ")");
    }
    WEFT_CHECK(f[0] != f[1] && f[1] != f[2] && f[0] != f[2], "cloth mesh: triangle ", t,
               " repeats a vertex");
    const Vec3 a = mesh.rest_vertex(f[0]), b = mesh.rest_vertex(f[1]), c = mesh.rest_vertex(f[2]);
    const double area = 0.5 * (b - a).cross(c - a).norm();
    WEFT_CHECK(area > 1e-14, "cloth mesh: triangle ", t, " is degenerate (area ", area, " m²)");
    for (int k = 0; k < 3; ++k) {
      mesh.mass[f[k]] += density * area / 3.0;
      const int i = f[k], j = f[(k + 1) % 3];
      edge_faces[{std::min(i, j), std::max(i, j)}].push_back(static_cast<int>(t));
    }
  }
  for (const auto& [edge, faces] : edge_faces) {
    mesh.edges.push_back({edge.first, edge.second});
    WEFT_CHECK(faces.size() <= 2, "cloth mesh: edge (", edge.first, ", ", edge.second,
               ") is shared by ", faces.size(), " triangles (non-manifold)");
    if (faces.size() != 2) continue;
    // Orient the hinge by the first triangle: it holds the edge as (v0, v1) in its order.
    const auto& f0 = mesh.triangles[faces[0]];
    const auto& f1 = mesh.triangles[faces[1]];
    int v0 = -1, v1 = -1, v2 = -1, v3 = -1;
    for (int k = 0; k < 3; ++k) {
      const int a = f0[k], b = f0[(k + 1) % 3];
      if ((a == edge.first && b == edge.second) || (a == edge.second && b == edge.first)) {
        v0 = a;
        v1 = b;
        v2 = f0[(k + 2) % 3];
      }
    }
    for (int k = 0; k < 3; ++k)
      if (f1[k] != edge.first && f1[k] != edge.second) v3 = f1[k];
    mesh.hinges.push_back({{v0, v1, v2, v3}});
  }
  return mesh;
}

ClothMesh make_grid_cloth(const Vec3& origin, double size_u, double size_v, int nx, int ny,
                          const char* plane, double density) {
  WEFT_CHECK(nx >= 2 && ny >= 2, "grid cloth: resolution must be at least 2 x 2, got ", nx,
             " x ", ny);
  WEFT_CHECK(size_u > 0 && size_v > 0, "grid cloth: size must be positive, got ", size_u,
             " x ", size_v);
  const std::string p = plane;
  int axis_u = 0, axis_v = 2;
  if (p == "xy") {
    axis_u = 0, axis_v = 1;
  } else if (p == "xz") {
    axis_u = 0, axis_v = 2;
  } else if (p == "yz") {
    axis_u = 1, axis_v = 2;
  } else {
    fail("grid cloth: plane must be xy, xz or yz, got '", p, "'");
  }
  Positions rest(3 * nx * ny);
  for (int r = 0; r < ny; ++r)
    for (int c = 0; c < nx; ++c) {
      Vec3 x = origin;
      x[axis_u] += size_u * c / (nx - 1);
      x[axis_v] += size_v * r / (ny - 1);
      rest.segment<3>(3 * (r * nx + c)) = x;
    }
  std::vector<std::array<int, 3>> tris;
  tris.reserve(2 * (nx - 1) * (ny - 1));
  for (int r = 0; r + 1 < ny; ++r)
    for (int c = 0; c + 1 < nx; ++c) {
      const int a = r * nx + c, b = a + 1, d = a + nx, e = d + 1;
      // Alternate the diagonal so the grid has no preferred shear direction.
      if ((r + c) % 2 == 0) {
        tris.push_back({a, b, e});
        tris.push_back({a, e, d});
      } else {
        tris.push_back({a, b, d});
        tris.push_back({b, e, d});
      }
    }
  return make_cloth_mesh(rest, std::move(tris), density);
}

}  // namespace weft::physics
