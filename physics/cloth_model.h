#pragma once
// The cloth model: a triangle mesh at rest, its derived topology (edges, hinges),
// lumped vertex masses and the material. SI units throughout: metres, kilograms,
// seconds; areal density in kg/m², Young's modulus in Pa (a 3D modulus, multiplied by
// the thickness in metres it gives the membrane stiffness in N/m), bending stiffness in
// N·m (joules).
#include <Eigen/Core>
#include <array>
#include <vector>

namespace weft::physics {

using Vec3 = Eigen::Vector3d;
using Positions = Eigen::VectorXd;  // 3n, vertex i at [3i, 3i+3)

// How the membrane answers compression (physics/membrane_energy.h).
enum class MembraneModel {
  stvk,           // Saint Venant-Kirchhoff in tension and compression alike
  tension_field,  // StVK in tension; compression relaxed (wrinkling below the mesh scale)
                  // and resisted only by compression_ratio × StVK
};
const char* to_string(MembraneModel model);

struct ClothMaterial {
  double density = 0.2;            // kg/m² (areal)
  double youngs_modulus = 5.0e5;   // Pa
  double poisson_ratio = 0.3;      // dimensionless, in [0, 0.5)
  double bending_stiffness = 1e-5; // N·m
  double thickness = 0.001;        // m (membrane stiffness = E · thickness)
  MembraneModel membrane = MembraneModel::tension_field;
  // tension_field: the share of StVK's compressive energy kept, in [0, 1] (1 is StVK).
  double compression_ratio = 1e-3;
  // tension_field: an element compressed below this area ratio (current / rest area)
  // meets a barrier against collapse; in [0, 1), 0 for none.
  double min_area_ratio = 0.5;

  bool operator==(const ClothMaterial&) const = default;
};

// Throws weft::Error naming the field if a value is non-physical.
void validate(const ClothMaterial& material);

// Two triangles sharing the edge (v0, v1): v2 is opposite in the first triangle
// (v0, v1, v2), v3 opposite in the second (v1, v0, v3). Orientation follows the first.
struct Hinge {
  std::array<int, 4> v;
};

struct ClothMesh {
  Positions rest;                           // 3n rest positions, metres
  std::vector<std::array<int, 3>> triangles;
  std::vector<std::array<int, 2>> edges;    // unique, v0 < v1
  std::vector<Hinge> hinges;                // interior edges only
  Eigen::VectorXd mass;                     // n lumped masses, kg

  int num_vertices() const { return static_cast<int>(rest.size() / 3); }
  Vec3 rest_vertex(int i) const { return rest.segment<3>(3 * i); }
};

// Builds edges, hinges and lumped masses (a third of each triangle's area times the
// density per vertex). Throws on out-of-range indices, degenerate triangles or
// non-manifold edges (more than two triangles).
ClothMesh make_cloth_mesh(const Positions& rest, std::vector<std::array<int, 3>> triangles,
                          double density);

// A rectangular grid of nx × ny vertices (nx columns, ny rows) spanning `size` metres in
// the plane `plane` ("xy", "xz" or "yz") from `origin`; vertex id = row · nx + column.
ClothMesh make_grid_cloth(const Vec3& origin, double size_u, double size_v, int nx, int ny,
                          const char* plane, double density);

}  // namespace weft::physics
