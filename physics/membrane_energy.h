#pragma once
// The plane-stress membrane. Per triangle, F (3×2) maps the rest triangle's 2D frame to
// its current 3D edges and G = ½(FᵀF − I) is the Green strain; the element energy is
// A·t·ψ(G), with A the rest area (m²), t the thickness (m) and ψ in J/m³ (Pa):
//
// - stvk: ψ = μ tr(G²) + λ/2 tr(G)², λ = Eν/(1−ν²), μ = E/(2(1+ν)), in tension and in
//   compression alike.
// - tension_field (the default): ψ = ψ_rel + ρ·(ψ_stvk − ψ_rel), ρ = compression_ratio.
//   ψ_rel is the tension-field relaxation of StVK: real fabric buckles on a length
//   sqrt(k_b/(E·t)) (0.1 mm for k_b = 1e-5 N·m, E·t = 500 N/m), far below a centimetre
//   mesh, and then carries no compressive stress. With g₁ ≥ g₂ the principal Green strains
//   and s₂ = 2μg₂ + λ(g₁+g₂) the smaller principal stress:
//     taut      (s₂ ≥ 0):        ψ_rel = ψ_stvk
//     wrinkled  (s₂ < 0 < g₁):   ψ_rel = k·g₁², k = 2μ(μ+λ)/(2μ+λ) (uniaxial tension,
//                                 the compressed direction contracting freely)
//     slack     (g₁ ≤ 0):        ψ_rel = 0.
//   ψ_rel = min over g₂' ≥ g₂ of ψ_stvk(g₁, g₂'), so it is C¹ across the region borders
//   (its Hessian jumps). Its stress S_rel is positive semi-definite and its tangent in G is
//   PSD, so its element Hessian is PSD without projection; only ρ·ψ_stvk adds an
//   indefinite geometric term, which the projection clamps as for StVK.
//   Free compression lets an element collapse to a line, where the bending energy's
//   gradient (∝ 1/height) blows up and Newton stalls (measured: the 1k drape with ρ ≤ 1e-3
//   lost frames at a residual of 1e9 of a vertex's weight). So below an area ratio
//   J = A/Ā of min_area_ratio, a barrier ψ_b = −μ (D − D₀)² ln(D/D₀), D = J², D₀ = J_min²,
//   resists further collapse: zero and C² at J_min, +∞ at J = 0. Its geometric term and
//   tangent are clamped by the projection.
//
// With the projection on, the element Hessian is made PSD by clamping the compressive
// eigenvalues of the stress S in its geometric term (exact wherever S ⪰ 0); with it off
// the Hessian is exact and add_hessian_correction supplies the difference.
#include <Eigen/Core>
#include <vector>

#include "physics/cloth_model.h"
#include "physics/energy.h"

namespace weft::physics {

// The membrane's response to a Green strain G: energy density ψ (J/m³), stress
// S = ∂ψ/∂G (Pa, symmetric) and tangent ∂²ψ/∂γ² in γ = (G₀₀, G₁₁, G₀₁) (Pa).
struct MembraneResponse {
  double psi = 0;
  Eigen::Matrix2d stress = Eigen::Matrix2d::Zero();
  Eigen::Matrix3d tangent = Eigen::Matrix3d::Zero();
  bool tangent_indefinite = false;  // true where the area barrier acts (the tangent may be indefinite)
};
MembraneResponse membrane_response(const Eigen::Matrix2d& G, const ClothMaterial& material,
                                   bool derivatives = true);

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
  Eigen::Matrix<double, 3, 2> deformation_gradient(const Element& el, const Eigen::VectorXd& x) const;
  // The 9×9 element Hessian for stress S and tangent C (exact for the response's own).
  Eigen::Matrix<double, 9, 9> element_hessian(const Element& el, const Eigen::Matrix<double, 3, 2>& F,
                                              const Eigen::Matrix2d& S, const Eigen::Matrix3d& tangent) const;
  std::vector<Element> elements_;
  ClothMaterial material_;
};

}  // namespace weft::physics
