#pragma once
// StVK plane-stress membrane. Per triangle, F (3×2) maps the rest triangle's 2D frame to
// its current 3D edges, G = ½(FᵀF − I) is the Green strain and
//   W = A · t · (μ tr(G²) + λ/2 tr(G)²),  λ = Eν/(1−ν²),  μ = E/(2(1+ν)),
// with A the rest area (m²), t the thickness (m) and E in Pa: W in joules. With the
// projection on, the element Hessian is made PSD by clamping the compressive eigenvalues
// of the stress S in its geometric term (see evaluate), exact in tension; with it off the
// Hessian is exact and add_hessian_correction supplies the difference.
#include <vector>

#include "physics/cloth_model.h"
#include "physics/energy.h"

namespace weft::physics {

class MembraneEnergy : public Energy {
 public:
  MembraneEnergy(const ClothMesh& mesh, const ClothMaterial& material);
  std::string name() const override { return "membrane"; }
  double evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g, SparseHessian* H) const override;
  void add_pattern(std::vector<std::array<int, 2>>& pairs) const override;
  // Adds the projected minus the exact Hessian: A·t·(β S₋ βᵀ) ⊗ I₃ per element, S₋ the
  // compressive part (−min(S, 0)) of the stress; PSD. Nothing when projecting already.
  bool add_hessian_correction(const Eigen::VectorXd& x, SparseHessian& c) const override;

 private:
  struct Element {
    std::array<int, 3> v;
    Eigen::Matrix<double, 3, 2> beta;  // F = Σ_v x_v β_vᵀ
    double weight;                     // rest area × thickness, m³
  };
  std::vector<Element> elements_;
  double lambda_, mu_;
};

}  // namespace weft::physics
