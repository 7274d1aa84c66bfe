#pragma once
// Collisions with obstacles (analytic spheres and body meshes) as a penalty on each cloth
// vertex's signed distance d to each obstacle, active within the collision thickness δ:
//   E = k/(6δ) · (δ − d)³  for d < δ, else 0;   k in N/m, δ in metres.
// A cubic onset: force and stiffness both grow from zero at the band's edge (E is C²),
// the stiffness reaches k at contact (d = 0), where the force is k·δ/2, and keeps growing
// with penetration. The quadratic penalty ½k(δ − d)² used before was only C¹: its
// stiffness jumped from 0 to k at d = δ, and since a resting vertex sits only
// m·g/k ≈ 1e-7 m inside the band, Newton kept switching vertices in and out of the
// active set and stalled on draping cloth.
// The per-vertex 3×3 Hessian E''∇d∇dᵀ + E'∇²d is projected to PSD.
#include <cmath>
#include <vector>

#include "physics/body_mesh.h"
#include "physics/energy.h"

namespace weft::physics {

struct SphereObstacle {
  Eigen::Vector3d center;
  double radius;          // metres
  double friction = 0.3;  // Coulomb coefficient μ against the cloth (FrictionEnergy); 0: none
};

// Signed distance of x to an obstacle with its gradient and Hessian.
struct DistanceSample {
  double distance = std::numeric_limits<double>::infinity();
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
};
DistanceSample signed_distance(const SphereObstacle& sphere, const Eigen::Vector3d& x);
DistanceSample signed_distance(const BodyMesh& body, const Eigen::Vector3d& x,
                               BodyMesh::Side known = BodyMesh::Side::unknown);
// The same from a closest point `c` of x already found on the body.
DistanceSample signed_distance(const ClosestPoint& c, const Eigen::Vector3d& x);

class CollisionEnergy : public Energy {
 public:
  CollisionEnergy(int num_vertices, double thickness, double stiffness);
  void set_spheres(std::vector<SphereObstacle> spheres) { spheres_ = std::move(spheres); }
  // Non-owning; the meshes must outlive the energy. Call again after moving a mesh.
  void set_bodies(std::vector<const BodyMesh*> bodies);
  const std::vector<SphereObstacle>& spheres() const { return spheres_; }
  const std::vector<const BodyMesh*>& bodies() const { return bodies_; }
  double thickness() const { return thickness_; }
  // Both sheets of a crease or a gap: a vertex within the band of a body's closest face
  // also feels the closest face whose normal differs from that face's by more than
  // `degrees` (the other side of the crease between thigh and belly, the other thigh),
  // if it too is within the band. With the closest face alone, a vertex pinched between
  // two sheets sits on their medial surface, where the closest face switches and the
  // penalty's gradient jumps: Newton then stalls at a kink instead of an equilibrium.
  // The sum is continuous across the switch. 0 turns it off (the closest face only).
  void set_second_sheet_angle(double degrees);
  double second_sheet_angle() const { return second_sheet_deg_; }
  // Smooth creases: a vertex outside a body mesh and within the band feels, instead of
  // its closest face alone, the penalty summed over every face, edge and vertex of the
  // mesh within the band, each on its own (unsigned) distance and weighted by
  // BodyMesh's inclusion–exclusion weights (face 1, edge 1 − m, vertex 1 + F − E):
  //   E_i = Σ_σ w_σ · k/(6δ)·(δ − d_σ(x_i))³.
  // Over a face, an edge or a vertex of a flat or convex surface the weights of the
  // features at the same distance sum to 1, so this is the closest-face penalty there;
  // in a concave crease the faces on both sides each hold a local closest point and both
  // push. Each term is C² in x_i away from its feature, so the sum is too: the medial
  // surface of a concave crease, where the closest face switches and its penalty's
  // gradient jumps, is no longer a kink Newton stalls on (traced: squat_jump, vertices
  // equidistant to 1 µm from two adjacent faces 7–28° apart, hundreds of iterations
  // with steps of 1e-14 m). Replaces the second sheet outside the body; a vertex inside
  // the body keeps the closest face (and the second sheet). Off by default.
  void set_smooth_creases(bool on) { smooth_creases_ = on; }
  bool smooth_creases() const { return smooth_creases_; }
  double stiffness() const { return k_; }
  // The penalty's force magnitude −dE/dd at signed distance d (N; 0 outside the band).
  double normal_force(double d) const {
    return d < thickness_ ? 0.5 * k_ / thickness_ * (thickness_ - d) * (thickness_ - d) : 0.0;
  }

  // Secant stiffness along the contact normal (off by default). Newton's quadratic model
  // of the cubic penalty (force c·gap², c = k/(2δ), tangent stiffness 2c·gap) is poor far
  // from the balance: from a vertex stopped deep in the band (the step filter's δ/2, where
  // the force is ~1e4 vertex weights) each iteration only halves the gap, and from a
  // vertex barely in the band it overshoots deep. With it, a vertex in the band gets, along
  // the direction n of its collision force f₀ = c·gap₀², instead of the tangent stiffness
  // the secant one to where its own penalty would balance the rest's push F toward the
  // obstacle (F = (g − g_collision)·n from the total gradient g):
  //   c·(gap₀ + gap*),  gap* = √(max(F, 0)/c),
  // so a decoupled vertex reaches its balance in one step, and at the balance (F = f₀) it
  // is the tangent stiffness again: Newton's local convergence is kept. Only the Hessian
  // (the direction) changes; the energy, the gradient and the line search do not.
  // Measured (issue 41, docs/notes/2026-12-06-contact-crawl-levers.md): with CG to 1e-2 it
  // saves a tenth of the 4k drape's CPU time but costs the 3k skirt 9 % more Newton
  // iterations and the 448-vertex windows 10 %, so it stays off.
  void set_secant_stiffness(bool on) { secant_stiffness_ = on; }
  bool secant_stiffness() const { return secant_stiffness_; }
  void adjust_hessian(const Eigen::VectorXd& x, const Eigen::VectorXd& g, SparseHessian& H) const override;

  std::string name() const override { return "collision"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;
  void begin_step(const Eigen::VectorXd&) override { invalidate_cache(); }
  // Step filter: a vertex outside the band may, to first order in the step, not come
  // closer than half the thickness: d + α ∇d·dx ≥ δ/2 for d ≥ δ. Without it the first
  // Newton step of a contact frame, blind to vertices still outside the band, sent them
  // centimetres deep into the obstacle, and Newton spent many iterations pushing them
  // out. Vertices in the band are left to the penalty's Hessian. (For a convex obstacle
  // d is convex outside it and the first-order bound is conservative.)
  void limit_vertex_steps(const Eigen::VectorXd& x, const Eigen::VectorXd& dx,
                          Eigen::VectorXd& limits) const override;
  // The per-vertex filter as a bound along the contact normal only (on by default;
  // set_planar_step_bounds): a vertex outside the band keeps its move's component along
  // the plane through its closest obstacle point and loses only the part of its approach
  // to that plane beyond d − δ/2, recomputed from x at every Newton iteration. Scaling the
  // whole move instead, as limit_vertex_steps does, also held back the vertex's slide
  // along the body, so cloth sliding onto a body crawled at a fraction of its Newton move
  // per iteration. Against tunnelling, a clipped vertex moves at most
  // max(d − δ/2, 2δ): within d − δ/2 no other obstacle point is reached (distance is
  // 1-Lipschitz), and a slide of s along the tangent plane of a concave surface of radius
  // R sinks by s²/(2R), under δ/2 for s = 2δ and R ≥ 4δ (2 cm at δ = 5 mm; the body's
  // colliding parts are rounder than that). The line search still judges the result.
  // When a vertex's planes disagree (a crease), the clipped move is scaled until it meets
  // them all.
  void clip_vertex_steps(const Eigen::VectorXd& x, Eigen::VectorXd& dx) const override;
  // Off: clip_vertex_steps scales the whole move (limit_vertex_steps), as before.
  void set_planar_step_bounds(bool on) { planar_step_bounds_ = on; }
  bool planar_step_bounds() const { return planar_step_bounds_; }

  // The closest body face of vertex i, where on it (interior, edge, vertex), the signed
  // distance, and the nearest other faces in the band turned more than 5°, 20° and
  // the second-sheet angle from it: whether the vertex sits in a crease.
  std::string describe_vertex(const Eigen::VectorXd& x, int i) const override;

  // Smallest signed distance of vertex i to any obstacle (metres; +inf without obstacles).
  double min_signed_distance(const Eigen::Vector3d& x) const;

 private:
  void invalidate_cache();
  // evaluate's sum over the vertices and obstacles.
  double evaluate_terms(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const;
  // The distance samples (closest obstacle points with their normals) that bound vertex i's
  // move of length `reach` (m) from xi: every obstacle it might come within δ/2 of.
  // Refreshes the body distance cache.
  void step_bound_samples(int i, const Eigen::Vector3d& xi, double reach,
                          std::vector<DistanceSample>& out) const;
  // Adds vertex i's penalty against one sample; returns its energy.
  double add_penalty(int i, const DistanceSample& s, Eigen::VectorXd* g, SparseHessian* H) const;
  // w times the penalty of sample s, added to a vertex's energy, gradient and Hessian block.
  void accumulate_penalty(double w, const DistanceSample& s, double& e, Eigen::Vector3d& g,
                          Eigen::Matrix3d& h) const;
  // Vertex i's smooth-crease penalty against body (see set_smooth_creases) from the faces
  // within the band and their closest points (BodyMesh::closest_point_and_faces_within);
  // returns it.
  double add_feature_sum(int i, const Eigen::Vector3d& x, const BodyMesh& body,
                         const std::vector<BodyMesh::FaceNear>& faces, Eigen::VectorXd* g, SparseHessian* H) const;

  int n_;
  double thickness_, k_;
  double second_sheet_deg_ = 0, second_sheet_cos_ = 2;  // off: no normal is that far
  bool smooth_creases_ = false;
  bool planar_step_bounds_ = true;
  bool secant_stiffness_ = false;
  std::vector<SphereObstacle> spheres_;
  std::vector<const BodyMesh*> bodies_;
  // Per body and vertex: where the distance was last queried and its value. Distance is
  // 1-Lipschitz, so a vertex that moved less than (d_ref − δ) is still outside the band.
  struct CacheEntry {
    Eigen::Vector3d x_ref;
    double d_ref = -std::numeric_limits<double>::infinity();
    // The side of the body x is on, known from the last query without a winding number
    // when x is within |d_ref| of x_ref (see BodyMesh::Side).
    BodyMesh::Side side(const Eigen::Vector3d& x) const {
      if (!std::isfinite(d_ref) || !((x - x_ref).norm() < std::abs(d_ref))) return BodyMesh::Side::unknown;
      return d_ref > 0 ? BodyMesh::Side::outside : BodyMesh::Side::inside;
    }
  };
  mutable std::vector<std::vector<CacheEntry>> cache_;
  // The x of the last Hessian evaluation and this energy's own gradient there (for
  // adjust_hessian; kept only with the secant stiffness).
  mutable Eigen::VectorXd hessian_x_, hessian_gradient_;
};

}  // namespace weft::physics
