#pragma once
// Cloth-to-body attachment: each cloth anchor vertex (e.g. a skirt's waistband) is tied
// to the closest point of the undeformed body surface, stored as a triangle and its
// barycentric weights, so that the attachment loss can compare
//   V_cloth[anchor_i]  with  Σ_k barycentric(i,k) · V_body[body_faces(i,k)].
#include <Eigen/Core>
#include <vector>

#include "geometry/mesh.h"

namespace weft::capture {

struct Attachment {
  Eigen::VectorXi anchors;            // A cloth vertex indices
  Eigen::VectorXi triangles;          // A body face indices
  Faces body_vertices;                // A×3 body vertex indices (= body.F.row(triangles(i)))
  Vertices barycentric;               // A×3 weights, each row ≥ 0 and summing to 1
  Eigen::VectorXd rest_distance;      // A distances in the rest pose (character units)

  int size() const { return static_cast<int>(anchors.size()); }
  // Σ_k barycentric(i,k) · body_V(body_vertices(i,k)) for every anchor (A×3).
  Vertices targets(const Vertices& body_V) const;
};

// Attaches every anchor of `cloth` to the closest triangle of `body` (both undeformed).
Attachment attach_to_body(const TriangleMesh& body, const TriangleMesh& cloth,
                          const std::vector<int>& anchors);

}  // namespace weft::capture
