#include "physics/membrane_energy.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>

namespace weft::physics {

namespace {

using Mat32 = Eigen::Matrix<double, 3, 2>;

struct Lame {
  double lambda, mu;
};
Lame lame(const ClothMaterial& m) {
  return {m.youngs_modulus * m.poisson_ratio / (1.0 - m.poisson_ratio * m.poisson_ratio),
          m.youngs_modulus / (2.0 * (1.0 + m.poisson_ratio))};
}

// StVK: ψ = μ tr(G²) + λ/2 tr(G)²; in γ = (G₀₀, G₁₁, G₀₁), tr(G²) = γ₀² + γ₁² + 2γ₂².
MembraneResponse stvk(const Eigen::Matrix2d& G, Lame l, bool derivatives) {
  MembraneResponse r;
  const double tr = G.trace();
  r.psi = l.mu * (G * G).trace() + 0.5 * l.lambda * tr * tr;
  if (!derivatives) return r;
  r.stress = 2.0 * l.mu * G + l.lambda * tr * Eigen::Matrix2d::Identity();
  r.tangent << 2.0 * l.mu + l.lambda, l.lambda, 0.0,  //
      l.lambda, 2.0 * l.mu + l.lambda, 0.0,           //
      0.0, 0.0, 4.0 * l.mu;
  return r;
}

// The tension-field relaxation of StVK (see the header): StVK where taut, k·g₁² where
// wrinkled, zero where slack.
MembraneResponse relaxed(const Eigen::Matrix2d& G, Lame l, bool derivatives) {
  // Principal strains g₁,₂ = m ± r with m = (G₀₀+G₁₁)/2, r = sqrt(u² + v²),
  // u = (G₀₀−G₁₁)/2, v = G₀₁.
  const double m = 0.5 * (G(0, 0) + G(1, 1));
  const double u = 0.5 * (G(0, 0) - G(1, 1)), v = 0.5 * (G(0, 1) + G(1, 0));
  const double r = std::sqrt(u * u + v * v);
  const double g1 = m + r, g2 = m - r;
  if (!(g1 > 0)) return {};  // slack: both directions compressed
  const double s2 = 2.0 * l.mu * g2 + l.lambda * (g1 + g2);
  if (s2 >= 0) return stvk(G, l, derivatives);  // taut
  // Wrinkled: r > 0 here, since s₂ < 0 < g₁ needs g₂ < −λg₁/(2μ+λ) < g₁.
  const double k = 2.0 * l.mu * (l.mu + l.lambda) / (2.0 * l.mu + l.lambda);
  MembraneResponse out;
  out.psi = k * g1 * g1;
  if (!derivatives) return out;
  // ∂g₁/∂γ and ∂²g₁/∂γ² (= ∂²r/∂γ², PSD); S = 2k·g₁·e₁e₁ᵀ ⪰ 0.
  const Eigen::Vector3d dg1(0.5 + 0.5 * u / r, 0.5 - 0.5 * u / r, v / r);
  Eigen::Matrix<double, 2, 3> J;
  J << 0.5, -0.5, 0.0, 0.0, 0.0, 1.0;  // ∂(u, v)/∂γ
  Eigen::Matrix2d d2r;
  d2r << v * v, -u * v, -u * v, u * u;
  d2r /= r * r * r;
  const Eigen::Vector3d dpsi = 2.0 * k * g1 * dg1;
  out.stress << dpsi[0], 0.5 * dpsi[2], 0.5 * dpsi[2], dpsi[1];
  out.tangent = 2.0 * k * (dg1 * dg1.transpose() + g1 * J.transpose() * d2r * J);
  return out;
}

// The area barrier of tension_field: ψ_b = −κ (D − D₀)² ln(D/D₀) for D < D₀, with
// D = det(FᵀF) = J² (J the area ratio, current / rest) and D₀ = J_min², zero above; C²
// at D₀ and +∞ at a collapsed element. In γ, D = (1+2γ₀)(1+2γ₁) − 4γ₂².
void add_area_barrier(const Eigen::Matrix2d& G, double kappa, double min_area_ratio, bool derivatives,
                      MembraneResponse& r) {
  const double d0 = min_area_ratio * min_area_ratio;
  const double gamma2 = 0.5 * (G(0, 1) + G(1, 0));
  const double D_exact = (1.0 + 2.0 * G(0, 0)) * (1.0 + 2.0 * G(1, 1)) - 4.0 * gamma2 * gamma2;
  if (!(D_exact < d0)) return;
  // A collapsed element (D = 0, only in a given start state) gets a large finite energy.
  const double D = std::max(D_exact, 1e-9 * d0);
  const double q = D - d0, l = std::log(D / d0);
  r.psi += -kappa * q * q * l;
  if (!derivatives) return;
  const double b1 = -kappa * (2.0 * q * l + q * q / D);
  const double b2 = -kappa * (2.0 * l + 4.0 * q / D - q * q / (D * D));
  const Eigen::Vector3d dD(2.0 * (1.0 + 2.0 * G(1, 1)), 2.0 * (1.0 + 2.0 * G(0, 0)), -8.0 * gamma2);
  Eigen::Matrix3d d2D;
  d2D << 0, 4, 0, 4, 0, 0, 0, 0, -8;
  const Eigen::Vector3d dpsi = b1 * dD;
  Eigen::Matrix2d S;
  S << dpsi[0], 0.5 * dpsi[2], 0.5 * dpsi[2], dpsi[1];
  r.stress += S;
  r.tangent += b2 * dD * dD.transpose() + b1 * d2D;
  r.tangent_indefinite = true;  // b₁ ∇²D has both signs
}

// The compressive part −min(S, 0) of a symmetric 2×2 stress (zero when S ⪰ 0).
Eigen::Matrix2d compressive_part(const Eigen::Matrix2d& S) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S);
  // The relaxed stress of a wrinkled element is rank one (2k·g₁·e₁e₁ᵀ): its second
  // eigenvalue is zero up to rounding, and is no compression.
  if (eig.eigenvalues()[0] >= -1e-12 * std::abs(eig.eigenvalues()[1])) return Eigen::Matrix2d::Zero();
  return eig.eigenvectors() * (-eig.eigenvalues().cwiseMin(0.0)).asDiagonal() *
         eig.eigenvectors().transpose();
}

}  // namespace

MembraneResponse membrane_response(const Eigen::Matrix2d& G, const ClothMaterial& material,
                                   bool derivatives) {
  const Lame l = lame(material);
  if (material.membrane == MembraneModel::stvk) return stvk(G, l, derivatives);
  MembraneResponse rel = relaxed(G, l, derivatives);
  const double rho = material.compression_ratio;
  if (rho != 0) {
    const MembraneResponse full = stvk(G, l, derivatives);
    // ψ_rel ≤ ψ_stvk, equal where taut: the blend changes only the compressed response.
    rel.psi += rho * (full.psi - rel.psi);
    rel.stress += rho * (full.stress - rel.stress);
    rel.tangent += rho * (full.tangent - rel.tangent);
  }
  if (material.min_area_ratio > 0) add_area_barrier(G, l.mu, material.min_area_ratio, derivatives, rel);
  return rel;
}

MembraneEnergy::MembraneEnergy(const ClothMesh& mesh, const ClothMaterial& m) : material_(m) {
  elements_.reserve(mesh.triangles.size());
  for (const auto& f : mesh.triangles) {
    const Vec3 x0 = mesh.rest_vertex(f[0]);
    const Vec3 e1 = mesh.rest_vertex(f[1]) - x0, e2 = mesh.rest_vertex(f[2]) - x0;
    const Vec3 n = e1.cross(e2);
    const Vec3 u = e1.normalized(), w = n.normalized().cross(u);
    Eigen::Matrix2d dm;
    dm << e1.norm(), e2.dot(u), 0.0, e2.dot(w);
    const Eigen::Matrix2d dinv = dm.inverse();
    Element el;
    el.v = f;
    el.beta.row(0) = -(dinv.row(0) + dinv.row(1));
    el.beta.row(1) = dinv.row(0);
    el.beta.row(2) = dinv.row(1);
    el.weight = 0.5 * n.norm() * m.thickness;
    elements_.push_back(el);
  }
}

void MembraneEnergy::add_pattern(std::vector<std::array<int, 2>>& pairs) const {
  for (const auto& el : elements_)
    for (int a = 0; a < 3; ++a) pairs.push_back({el.v[a], el.v[(a + 1) % 3]});
}

Mat32 MembraneEnergy::deformation_gradient(const Element& el, const Eigen::VectorXd& x) const {
  Mat32 F = Mat32::Zero();
  for (int a = 0; a < 3; ++a) F += x.segment<3>(3 * el.v[a]) * el.beta.row(a);
  return F;
}

Eigen::Matrix<double, 9, 9> MembraneEnergy::element_hessian(const Element& el, const Mat32& F,
                                                             const Eigen::Matrix2d& S,
                                                             const Eigen::Matrix3d& tangent) const {
  // d²ψ/dF²[dF] = dF S + F dS, dS = C[dG]: over vec(F) = (f₀, f₁) (F's columns),
  //   H_F = S ⊗ I₃ + Lᵀ C L,  L = [f₀ᵀ 0; 0 f₁ᵀ; ½f₁ᵀ ½f₀ᵀ]  (dγ = L vec(dF), γ = (G₀₀, G₁₁, G₀₁)).
  // The second part is PSD whenever the tangent C is; the geometric term S ⊗ I₃ is
  // indefinite where S has a compressive (negative) eigenvalue. Linear in (S, C). With
  // F = Σ_v x_v β_vᵀ, the vertex Hessian is w (β ⊗ I₃) H_F (β ⊗ I₃)ᵀ.
  Eigen::Matrix<double, 3, 6> L = Eigen::Matrix<double, 3, 6>::Zero();
  L.block<1, 3>(0, 0) = F.col(0).transpose();
  L.block<1, 3>(1, 3) = F.col(1).transpose();
  L.block<1, 3>(2, 0) = 0.5 * F.col(1).transpose();
  L.block<1, 3>(2, 3) = 0.5 * F.col(0).transpose();
  const Eigen::Matrix3d C = 0.5 * (tangent + tangent.transpose());
  const Eigen::Matrix<double, 3, 6> CL = C.lazyProduct(L);
  Eigen::Matrix<double, 6, 6> hf = L.transpose().lazyProduct(CL);
  const double s01 = 0.5 * (S(0, 1) + S(1, 0));
  for (int i = 0; i < 3; ++i) {
    hf(i, i) += S(0, 0);
    hf(3 + i, 3 + i) += S(1, 1);
    hf(i, 3 + i) += s01;
    hf(3 + i, i) += s01;
  }
  // Block (a, b) = w Σ_cd β_ac β_bd H_F,cd, in two passes over 3×3 blocks: T_cb = Σ_d β_bd H_F,cd.
  Eigen::Matrix3d T[2][3];
  for (int c = 0; c < 2; ++c)
    for (int b = 0; b < 3; ++b)
      T[c][b] = el.beta(b, 0) * hf.block<3, 3>(3 * c, 0) + el.beta(b, 1) * hf.block<3, 3>(3 * c, 3);
  Eigen::Matrix<double, 9, 9> hx;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      hx.block<3, 3>(3 * a, 3 * b) = el.weight * (el.beta(a, 0) * T[0][b] + el.beta(a, 1) * T[1][b]);
  return hx;
}

namespace {
// The PSD part of a symmetric 3×3 tangent (eigenvalues clamped at zero).
Eigen::Matrix3d psd_part(const Eigen::Matrix3d& C) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(C);
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
}
}  // namespace

bool MembraneEnergy::add_hessian_correction(const Eigen::VectorXd& x, SparseHessian& c) const {
  if (project_hessian_) return false;
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  bool any = false;
  for (const auto& el : elements_) {
    const Mat32 F = deformation_gradient(el, x);
    const Eigen::Matrix2d G = 0.5 * (F.transpose() * F - I);
    const MembraneResponse resp = membrane_response(G, material_);
    const Eigen::Matrix2d s_neg = compressive_part(resp.stress);
    const Eigen::Matrix3d c_fix = resp.tangent_indefinite ? Eigen::Matrix3d(psd_part(resp.tangent) - resp.tangent)
                                                          : Eigen::Matrix3d::Zero();
    if (s_neg.isZero(0.0) && c_fix.isZero(0.0)) continue;  // the exact element Hessian is PSD
    any = true;
    // Projected minus exact: the Hessian is linear in (S, C).
    c.add<3>(el.v, element_hessian(el, F, s_neg, c_fix));
  }
  return any;
}

double MembraneEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                                SparseHessian* H) const {
  double energy = 0;
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  const bool derivatives = g || H;
  for (const auto& el : elements_) {
    const Mat32 F = deformation_gradient(el, x);
    const Eigen::Matrix2d G = 0.5 * (F.transpose() * F - I);
    const MembraneResponse resp = membrane_response(G, material_, derivatives);
    energy += el.weight * resp.psi;
    if (!derivatives) continue;
    const Eigen::Matrix2d& S = resp.stress;  // second Piola-Kirchhoff
    if (g) {
      const Mat32 P = el.weight * F * S;
      for (int a = 0; a < 3; ++a) g->segment<3>(3 * el.v[a]) += P * el.beta.row(a).transpose();
    }
    if (H) {
      // The projection clamps the compressive eigenvalues of S (and, where the area
      // barrier acts, the tangent's negative ones), which makes the element Hessian PSD by
      // construction and leaves it exact where S ⪰ 0 and C ⪰ 0.
      if (project_hessian_)
        H->add<3>(el.v, element_hessian(el, F, S + compressive_part(S),
                                        resp.tangent_indefinite ? psd_part(resp.tangent) : resp.tangent));
      else
        H->add<3>(el.v, element_hessian(el, F, S, resp.tangent));
    }
  }
  return energy;
}

}  // namespace weft::physics
