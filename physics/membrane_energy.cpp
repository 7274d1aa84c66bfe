#include "physics/membrane_energy.h"

#include <Eigen/Geometry>

#include <Eigen/Eigenvalues>

namespace weft::physics {

MembraneEnergy::MembraneEnergy(const ClothMesh& mesh, const ClothMaterial& m) {
  lambda_ = m.youngs_modulus * m.poisson_ratio / (1.0 - m.poisson_ratio * m.poisson_ratio);
  mu_ = m.youngs_modulus / (2.0 * (1.0 + m.poisson_ratio));
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

bool MembraneEnergy::add_hessian_correction(const Eigen::VectorXd& x, SparseHessian& c) const {
  if (project_hessian_) return false;
  using Mat32 = Eigen::Matrix<double, 3, 2>;
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  bool any = false;
  for (const auto& el : elements_) {
    Mat32 F = Mat32::Zero();
    for (int a = 0; a < 3; ++a) F += x.segment<3>(3 * el.v[a]) * el.beta.row(a);
    const Eigen::Matrix2d G = 0.5 * (F.transpose() * F - I);
    const Eigen::Matrix2d S = 2.0 * mu_ * G + lambda_ * G.trace() * I;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S);
    if (eig.eigenvalues()[0] >= 0) continue;  // in tension: the exact Hessian is PSD
    any = true;
    const Eigen::Matrix2d s_neg = eig.eigenvectors() *
                                  (-eig.eigenvalues().cwiseMin(0.0)).asDiagonal() *
                                  eig.eigenvectors().transpose();
    const Eigen::Matrix3d w = el.weight * el.beta * s_neg * el.beta.transpose();
    Eigen::Matrix<double, 9, 9> hx = Eigen::Matrix<double, 9, 9>::Zero();
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) hx.block<3, 3>(3 * a, 3 * b).diagonal().setConstant(w(a, b));
    c.add<3>(el.v, hx);
  }
  return any;
}

double MembraneEnergy::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* g,
                                SparseHessian* H) const {
  using Mat32 = Eigen::Matrix<double, 3, 2>;
  double energy = 0;
  const Eigen::Matrix2d I = Eigen::Matrix2d::Identity();
  for (const auto& el : elements_) {
    Mat32 F = Mat32::Zero();
    for (int a = 0; a < 3; ++a) F += x.segment<3>(3 * el.v[a]) * el.beta.row(a);
    const Eigen::Matrix2d G = 0.5 * (F.transpose() * F - I);
    const double trG = G.trace();
    energy += el.weight * (mu_ * (G * G).trace() + 0.5 * lambda_ * trG * trG);
    if (!g && !H) continue;
    const Eigen::Matrix2d S = 2.0 * mu_ * G + lambda_ * trG * I;  // second Piola-Kirchhoff
    if (g) {
      const Mat32 P = el.weight * F * S;
      for (int a = 0; a < 3; ++a) g->segment<3>(3 * el.v[a]) += P * el.beta.row(a).transpose();
    }
    if (H) {
      // d²ψ/dF²[dF] = dF S + F (2μ dG + λ tr(dG) I). Its second part is PSD for any F
      // (⟨dF, ·⟩ = 2μ‖dG‖² + λ tr(dG)²); only the geometric term dF S is indefinite, when
      // S has a compressive (negative) eigenvalue. The projection clamps those eigenvalues
      // of S, which makes the element Hessian PSD by construction and leaves it exact in
      // tension.
      Eigen::Matrix2d S_used = S;
      if (project_hessian_) {
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(S);
        S_used = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() *
                 eig.eigenvectors().transpose();
      }
      Eigen::Matrix<double, 6, 6> hf;
      for (int k = 0; k < 6; ++k) {
        Mat32 dF = Mat32::Zero();
        dF(k % 3, k / 3) = 1.0;
        const Eigen::Matrix2d FtdF = F.transpose() * dF;
        const Eigen::Matrix2d dG = 0.5 * (FtdF + FtdF.transpose());
        const Mat32 dP = dF * S_used + F * (2.0 * mu_ * dG + lambda_ * dG.trace() * I);
        hf.col(k) = Eigen::Map<const Eigen::Matrix<double, 6, 1>>(dP.data());
      }
      hf = 0.5 * (hf + hf.transpose()).eval();
      Eigen::Matrix<double, 9, 9> hx;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          Eigen::Matrix3d blk = Eigen::Matrix3d::Zero();
          for (int c = 0; c < 2; ++c)
            for (int d = 0; d < 2; ++d)
              blk += el.beta(a, c) * el.beta(b, d) * hf.block<3, 3>(3 * c, 3 * d);
          hx.block<3, 3>(3 * a, 3 * b) = el.weight * blk;
        }
      H->add<3>(el.v, hx);
    }
  }
  return energy;
}

}  // namespace weft::physics
