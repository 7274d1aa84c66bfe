#include "geometry/mesh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <utility>

#include "graph/error.h"

namespace weft {

void validate_mesh(const TriangleMesh& mesh, const std::string& what) {
  const int n = mesh.num_vertices();
  if (!mesh.V.allFinite()) fail(what, ": non-finite vertex coordinate");
  for (int f = 0; f < mesh.num_faces(); ++f)
    for (int c = 0; c < 3; ++c)
      if (mesh.F(f, c) < 0 || mesh.F(f, c) >= n)
        fail(what, ": face ", f, " has vertex index ", mesh.F(f, c), " out of range (", n,
             " vertices)");
  if (mesh.colors.rows() != 0 && mesh.colors.rows() != n)
    fail(what, ": ", mesh.colors.rows(), " colours for ", n, " vertices");
  if (mesh.uv_faces.rows() != 0) {
    if (mesh.uv_faces.rows() != mesh.F.rows())
      fail(what, ": ", mesh.uv_faces.rows(), " texture faces for ", mesh.F.rows(), " faces");
    if (mesh.uv_faces.size() > 0 &&
        (mesh.uv_faces.minCoeff() < 0 || mesh.uv_faces.maxCoeff() >= mesh.uv.rows()))
      fail(what, ": texture coordinate index out of range (", mesh.uv.rows(), " coordinates)");
  }
}

Vertices face_normals(const Vertices& V, const Faces& F) {
  Vertices N(F.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    N.row(f) = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
  }
  return N;
}

Vertices vertex_normals(const Vertices& V, const Faces& F) {
  Vertices N = Vertices::Zero(V.rows(), 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);  // length = 2 × area
    for (int k = 0; k < 3; ++k) N.row(F(f, k)) += n;
  }
  for (Eigen::Index i = 0; i < N.rows(); ++i) {
    const double len = N.row(i).norm();
    if (len > 0) N.row(i) /= len;
  }
  return N;
}

Eigen::VectorXd face_areas(const Vertices& V, const Faces& F) {
  Eigen::VectorXd A(F.rows());
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Eigen::Vector3d a = V.row(F(f, 0)), b = V.row(F(f, 1)), c = V.row(F(f, 2));
    A(f) = 0.5 * (b - a).cross(c - a).norm();
  }
  return A;
}

Edges unique_edges(const Faces& F) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(F.rows() * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = F(f, k), b = F(f, (k + 1) % 3);
      if (a != b) edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  Edges E(edges.size(), 2);
  for (size_t i = 0; i < edges.size(); ++i) E.row(i) << edges[i].first, edges[i].second;
  return E;
}

std::vector<std::vector<int>> vertex_adjacency(const Faces& F, int num_vertices) {
  std::vector<std::vector<int>> adj(num_vertices);
  const Edges E = unique_edges(F);
  for (Eigen::Index e = 0; e < E.rows(); ++e) {
    adj[E(e, 0)].push_back(E(e, 1));
    adj[E(e, 1)].push_back(E(e, 0));
  }
  for (auto& a : adj) std::sort(a.begin(), a.end());
  return adj;
}

TriangleMesh uv_sphere(const Eigen::Vector3d& centre, double radius, int rings, int segments) {
  if (rings < 2 || segments < 3) fail("uv_sphere: need at least 2 rings and 3 segments, got ", rings, " and ", segments);
  TriangleMesh m;
  m.V.resize((rings + 1) * (segments + 1), 3);
  m.uv.resize(m.V.rows(), 2);
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j <= segments; ++j) {
      const double theta = M_PI * i / rings, phi = 2 * M_PI * j / segments;
      const int k = i * (segments + 1) + j;
      m.V.row(k) = centre.transpose() + radius * Eigen::RowVector3d(std::sin(theta) * std::cos(phi),
                                                                    -std::cos(theta),
                                                                    std::sin(theta) * std::sin(phi));
      m.uv.row(k) << static_cast<double>(j) / segments, static_cast<double>(i) / rings;
    }
  std::vector<Eigen::RowVector3i> faces;
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * (segments + 1) + j, b = a + 1, c = a + segments + 1, d = c + 1;
      if (i > 0) faces.emplace_back(a, c, b);  // the other one is degenerate at the pole
      if (i < rings - 1) faces.emplace_back(b, c, d);
    }
  m.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f) m.F.row(static_cast<Eigen::Index>(f)) = faces[f];
  m.uv_faces = m.F;
  return m;
}

}  // namespace weft
