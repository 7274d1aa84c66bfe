#pragma once
// A triangle mesh obstacle (the body) with an AABB tree for closest-point queries and
// signed distances. The sign comes from the closest feature's pseudo-normal: the face
// normal inside a face, the angle-weighted vertex normal at a vertex, the sum of the two
// face normals on an edge (Bærentzen & Aanæs 2005), so it is exact for closed meshes.
// Faces marked inactive are left out of the tree entirely (not collided with).
#include <Eigen/Core>
#include <array>
#include <vector>

#include "geometry/closest_point.h"

namespace weft::physics {

struct ClosestPoint {
  double distance = 0;       // signed, metres; > 0 outside
  Eigen::Vector3d point;     // closest point on the surface
  Eigen::Vector3d normal;    // pseudo-normal of the closest feature (unit)
  int face = -1;             // closest face, -1 when the mesh has no active face
  bool face_interior = false;  // true when the closest point is inside the face
  bool on_edge = false;        // true when it is inside an edge (not at a vertex)
  Eigen::Vector3d edge_direction = Eigen::Vector3d::Zero();  // unit, when on_edge
};

class BodyMesh {
 public:
  BodyMesh() = default;
  // vertices: n × 3 positions in metres; inactive: faces left out of collisions.
  BodyMesh(Eigen::MatrixX3d vertices, std::vector<std::array<int, 3>> faces,
           std::vector<int> inactive_faces = {});

  // Moves the vertices (same count) and refits the tree; normals are recomputed. The
  // positions before the call become previous_vertices() (the body's motion over the
  // step, which friction drags the cloth along with).
  void set_vertices(const Eigen::MatrixX3d& vertices);
  // The same, with the positions the motion starts from given explicitly (e.g. the first
  // sub-step of a frame whose start the mesh never was at).
  void set_vertices(const Eigen::MatrixX3d& vertices, const Eigen::MatrixX3d& previous);

  const Eigen::MatrixX3d& vertices() const { return vertices_; }
  // Positions before the last set_vertices (metres); equal to vertices() until then.
  const Eigen::MatrixX3d& previous_vertices() const { return previous_vertices_; }
  const std::vector<std::array<int, 3>>& faces() const { return faces_; }
  int num_active_faces() const { return static_cast<int>(active_.size()); }

  // Which side of the surface a query point is known to lie on, when the caller knows it
  // without asking: a point that moved less than |d| from where the signed distance was d
  // has not crossed the surface (distance is 1-Lipschitz), so it is on the same side.
  // Where the pseudo-normal's sign is doubted (a folded vertex) a known side replaces the
  // O(faces) winding number.
  enum class Side { unknown, outside, inside };
  // Closest point on the active surface; nodes farther than `max_distance` are pruned (the
  // result then has face = -1 if nothing is that close).
  ClosestPoint closest_point(const Eigen::Vector3d& x,
                             double max_distance = std::numeric_limits<double>::infinity(),
                             Side known = Side::unknown) const;
  // The same over the active faces whose unit normal n has n·facing < max_cos only: the
  // closest point on another sheet of the surface than the one `facing` belongs to (the
  // other side of a crease or of a gap between two limbs).
  ClosestPoint closest_point_facing_away(const Eigen::Vector3d& x, double max_distance,
                                         const Eigen::Vector3d& facing, double max_cos) const;
  // Unit normal of face f.
  const Eigen::Vector3d& face_normal(int f) const { return face_normals_[f]; }
  // The generalized winding number of the whole surface (every face, active or not) at x:
  // the faces' signed solid angles seen from x over 4π (van Oosterom & Strackee's formula);
  // 1 inside a closed outward-oriented mesh, 0 outside, ½ on it. O(faces).
  double winding_number(const Eigen::Vector3d& x) const;
  // Whether vertex v's surface is folded over: an active face at v faces against v's
  // pseudo-normal, or the unit normals of its active faces average to shorter than ½
  // (updated with the vertices).
  bool folded(int v) const { return folded_[v] != 0; }
  // One active face near a point: the face's closest point to it, the feature of the face
  // that point lies on, and the squared distance (m²).
  struct FaceNear {
    int face = -1;
    Eigen::Vector3d point = Eigen::Vector3d::Zero();
    TriangleFeature feature = TriangleFeature::face;
    double distance2 = 0;
  };
  // closest_point(x) and, in `faces` (cleared first, in no order), every active face closer
  // to x than `band` (m) with its own closest point: one traversal of the tree.
  ClosestPoint closest_point_and_faces_within(const Eigen::Vector3d& x, double band,
                                              std::vector<FaceNear>& faces, Side known = Side::unknown) const;
  // The mesh as a cell complex of its active faces, for sums over its features:
  // the ids of face f's edges (k, k+1), an edge's two vertices, and the inclusion–exclusion
  // weights that make Σ_faces − … count each feature's neighbourhood once: an edge shared
  // by m active faces weighs 1 − m (−1 inside the surface, 0 on a boundary), a vertex with
  // F active faces and E edges weighs 1 + F − E (1 inside, 0 on a boundary). A point whose
  // closest feature is σ then finds weights summing to 1 over σ and the features
  // containing it (CollisionEnergy's smooth creases).
  const std::array<int, 3>& face_edges(int f) const { return face_edges_[f]; }
  const std::array<int, 2>& edge_vertices(int e) const { return edge_vertices_[e]; }
  int edge_weight(int e) const { return edge_weights_[e]; }
  int vertex_weight(int v) const { return vertex_weights_[v]; }

 private:
  struct Node {
    Eigen::Vector3d lo, hi;
    int left = -1, right = -1;  // children, or -1 for a leaf
    int begin = 0, end = 0;     // leaf range in active_
  };
  int build(int begin, int end);
  // The closest point over the active faces `accept(face)` admits.
  template <class Accept>
  ClosestPoint closest_point_where(const Eigen::Vector3d& x, double max_distance, const Accept& accept,
                                   Side known) const;
  // The one tree walk of every query: visit(face) for each active face in a leaf whose box
  // is closer to x than √bound2(), nearer children first; bound2() may shrink as faces are
  // visited (a closest-point search) or stay fixed (all faces within a band).
  template <class Bound, class Visit>
  void traverse(const Eigen::Vector3d& x, const Bound& bound2, const Visit& visit) const;
  FaceNear near_face(const Eigen::Vector3d& x, int face) const;
  // The signed closest point of the nearest face found (face −1: none).
  ClosestPoint signed_closest_point(const Eigen::Vector3d& x, const FaceNear& nearest, Side known) const;
  void refit(int node);
  void compute_normals();

  Eigen::MatrixX3d vertices_, previous_vertices_;
  std::vector<std::array<int, 3>> faces_;
  std::vector<int> active_;          // active face ids, reordered by the tree
  std::vector<Node> nodes_;
  std::vector<Eigen::Vector3d> face_normals_, vertex_normals_;
  std::vector<char> folded_;  // per vertex, see folded()
  std::vector<std::array<Eigen::Vector3d, 3>> edge_normals_;  // per face, edge (k, k+1)
  std::vector<std::array<int, 3>> face_edges_;  // per active face, the id of edge (k, k+1)
  int num_edges_ = 0;
  std::vector<std::array<int, 2>> edge_vertices_;  // per edge id
  std::vector<int> edge_weights_, vertex_weights_;  // see face_edges()
};

}  // namespace weft::physics
