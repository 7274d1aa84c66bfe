#pragma once
// Closest points on triangle meshes: the point–triangle primitive and a query structure
// for many points against one mesh (used by attachment, weight transfer and the
// penetration measures). physics::BodyMesh keeps its own AABB tree with signed distances
// and refits (the simulator's obstacle query) on the same point–triangle primitive.
#include <Eigen/Core>
#include <vector>

#include "geometry/mesh.h"

namespace weft {

// The feature of a triangle (a, b, c) a closest point lies on: its interior, an edge
// (edge01 joins a and b) or a vertex.
enum class TriangleFeature { face, edge01, edge12, edge20, vertex0, vertex1, vertex2 };

// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection,
// §5.1.5), with its barycentric weights (sum 1, all ≥ 0) and, when asked, the feature it
// lies on. A zero-area triangle gives its first vertex. The one point–triangle primitive
// of weft: the closest-point queries here and the simulator's body obstacle
// (physics::BodyMesh) both use it.
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                                          Eigen::Vector3d& barycentric, TriangleFeature* feature = nullptr);

struct ClosestPoint {
  int face = -1;
  Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();  // weights of F(face, 0..2)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  double distance = 0;  // character units
};

// Exact closest-triangle queries against a fixed mesh. Each query first bounds every
// triangle by its enclosing sphere (cheap) and only runs the exact test where that bound
// can beat the best distance so far; ties go to the lowest face index (deterministic).
class ClosestTriangleQuery {
 public:
  ClosestTriangleQuery(const Vertices& V, const Faces& F);
  ClosestPoint closest(const Eigen::Vector3d& p) const;

 private:
  Vertices V_;
  Faces F_;
  Vertices centers_;
  Eigen::VectorXd radii_;
};

}  // namespace weft
