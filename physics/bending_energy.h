#pragma once
// Discrete-shell bending (Grinspun et al. 2003): per interior edge e with dihedral angle θ
// (0 when flat) and rest angle θ̄,
//   W = ½ k_b · 3‖ē‖² / (Ā₁ + Ā₂) · (θ − θ̄)²,
// k_b the bending stiffness in N·m (J), ē the rest edge, Ā the rest areas of its two
// triangles. θ's gradient and Hessian come from a second-order jet on the 9 edge vectors
// (x1−x0, x2−x0, x3−x0). The Newton Hessian (projection on) is the Gauss-Newton term
// 2w ∇θ∇θᵀ, PSD by construction; with the projection off it is the exact one.
#include <vector>

#include "physics/cloth_model.h"
#include "physics/energy.h"

namespace weft::physics {

// Signed dihedral angle of hinge (x0, x1, x2, x3), radians in (−π, π]; 0 when flat.
double dihedral_angle(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3);

class BendingEnergy : public Energy {
 public:
  BendingEnergy(const ClothMesh& mesh, const ClothMaterial& material);
  std::string name() const override { return "bending"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;
  void add_pattern(std::vector<std::array<int, 2>>& pairs) const override;
  // The two vertices opposite across each hinge (they share no triangle).
  void add_weak_pairs(std::vector<std::array<int, 2>>& pairs) const override;

 private:
  struct Element {
    std::array<int, 4> v;
    double rest_angle;
    double weight;  // ½ k_b · 3‖ē‖²/(Ā₁+Ā₂), J
  };
  std::vector<Element> elements_;
};

}  // namespace weft::physics
