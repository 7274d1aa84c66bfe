#pragma once
// Triangle meshes: plain Eigen arrays, row-major so that a vertex is 3 contiguous
// doubles and V.data() is an N×3 C array. Units are the user's: a character's (ddc:
// millimetres) in capture/, metres in physics/. The one mesh type of weft, below physics/
// and capture/.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace weft {

using Vertices = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
using Faces = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
using TexCoords = Eigen::Matrix<double, Eigen::Dynamic, 2, Eigen::RowMajor>;
using Edges = Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor>;

struct TriangleMesh {
  Vertices V;  // N×3 positions
  Faces F;     // M×3 vertex indices, counter-clockwise seen from outside
  // Optional texture coordinates, per face corner as in OBJ: uv is T×2, uv_faces M×3
  // indices into uv. Both empty when the mesh has none.
  TexCoords uv;
  Faces uv_faces;
  // Optional per-vertex RGB colours in [0, 1], N×3; empty when absent.
  Vertices colors;

  int num_vertices() const { return static_cast<int>(V.rows()); }
  int num_faces() const { return static_cast<int>(F.rows()); }
  bool has_uv() const { return uv_faces.rows() == F.rows() && F.rows() > 0 && uv.rows() > 0; }
  bool has_colors() const { return colors.rows() == V.rows() && V.rows() > 0; }
};

// Throws weft::Error (naming `what`) if an index is out of range, a value is not finite,
// or the optional arrays have inconsistent sizes.
void validate_mesh(const TriangleMesh& mesh, const std::string& what);

// A latitude–longitude sphere around `centre`: (rings + 1) × (segments + 1) vertices (the
// seam and the poles repeated, so uv is per vertex: u = j / segments around from +x
// towards +z, v = i / rings from the south pole, −y, up), two triangles per cell except at
// the poles, outward-facing; uv_faces = F.
TriangleMesh uv_sphere(const Eigen::Vector3d& centre, double radius, int rings, int segments);

// Unit face normals (M×3); degenerate faces get a zero normal.
Vertices face_normals(const Vertices& V, const Faces& F);
// Area-weighted unit vertex normals (N×3).
Vertices vertex_normals(const Vertices& V, const Faces& F);
// Face areas (M), in squared units.
Eigen::VectorXd face_areas(const Vertices& V, const Faces& F);
// The unique undirected edges (i < j), sorted.
Edges unique_edges(const Faces& F);
// Per-vertex neighbour lists from the faces, each sorted.
std::vector<std::vector<int>> vertex_adjacency(const Faces& F, int num_vertices);

}  // namespace weft
