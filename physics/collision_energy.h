#pragma once
// Collisions with obstacles (analytic spheres and body meshes) as a penalty on each cloth
// vertex's signed distance d to each obstacle, active within the collision thickness δ:
//   E = ½ k (δ − d)²  for d < δ, else 0;   k in N/m, δ in metres.
// The per-vertex 3×3 Hessian k ∇d∇dᵀ − k (δ − d) ∇²d is projected to PSD.
#include <vector>

#include "physics/body_mesh.h"
#include "physics/energy.h"

namespace weft::physics {

struct SphereObstacle {
  Eigen::Vector3d center;
  double radius;  // metres
};

// Signed distance of x to an obstacle with its gradient and Hessian.
struct DistanceSample {
  double distance = std::numeric_limits<double>::infinity();
  Eigen::Vector3d gradient = Eigen::Vector3d::Zero();
  Eigen::Matrix3d hessian = Eigen::Matrix3d::Zero();
};
DistanceSample signed_distance(const SphereObstacle& sphere, const Eigen::Vector3d& x);
DistanceSample signed_distance(const BodyMesh& body, const Eigen::Vector3d& x);

class CollisionEnergy : public Energy {
 public:
  CollisionEnergy(int num_vertices, double thickness, double stiffness);
  void set_spheres(std::vector<SphereObstacle> spheres) { spheres_ = std::move(spheres); }
  // Non-owning; the meshes must outlive the energy. Call again after moving a mesh.
  void set_bodies(std::vector<const BodyMesh*> bodies);
  const std::vector<SphereObstacle>& spheres() const { return spheres_; }
  const std::vector<const BodyMesh*>& bodies() const { return bodies_; }
  double thickness() const { return thickness_; }

  std::string name() const override { return "collision"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;
  void begin_step(const Eigen::VectorXd&) override { invalidate_cache(); }

  // Smallest signed distance of vertex i to any obstacle (metres; +inf without obstacles).
  double min_signed_distance(const Eigen::Vector3d& x) const;

 private:
  void invalidate_cache();
  // Adds vertex i's penalty against one sample; returns its energy.
  double add_penalty(int i, const DistanceSample& s, Eigen::VectorXd* g, SparseHessian* H) const;

  int n_;
  double thickness_, k_;
  std::vector<SphereObstacle> spheres_;
  std::vector<const BodyMesh*> bodies_;
  // Per body and vertex: where the distance was last queried and its value. Distance is
  // 1-Lipschitz, so a vertex that moved less than (d_ref − δ) is still outside the band.
  struct CacheEntry {
    Eigen::Vector3d x_ref;
    double d_ref = -std::numeric_limits<double>::infinity();
  };
  mutable std::vector<std::vector<CacheEntry>> cache_;
};

}  // namespace weft::physics
