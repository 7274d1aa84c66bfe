#include "capture/inference/root_placement.h"

#include <Eigen/Dense>
#include <cmath>

#include "graph/error.h"

namespace weft::capture {

RootPlacement::RootPlacement(const Character& character)
    : character_(character), param_(pose_parametrisation(character)) {
  for (int j = param_.pivot_joint; j >= 0; j = character.skeleton.joints[size_t(j)].parent) chain_.insert(chain_.begin(), j);
  rest_pivot_ = pivot_transform(character.rest_dofs);
  length_ = 1.0 / character.metres_per_unit;
}

Eigen::Isometry3d RootPlacement::pivot_transform(const Eigen::VectorXd& dofs) const {
  const Skeleton& s = character_.skeleton;
  Eigen::VectorXd p = Eigen::VectorXd::Zero(s.num_joints());
  for (int d : param_.root_dofs)
    for (const DofInfluence& inf : s.dofs[size_t(d)].joints) p(inf.joint) += inf.weight * dofs(d);
  Eigen::Isometry3d G = Eigen::Isometry3d::Identity();
  for (int j : chain_) G = G * joint_local_transform(s.joints[size_t(j)], p(j));
  return G;
}

Eigen::VectorXd RootPlacement::solve(Eigen::VectorXd dofs, const Eigen::Isometry3d& target, double* residual) const {
  const int n = int(param_.root_dofs.size());
  auto residuals = [&](const Eigen::VectorXd& x) {
    const Eigen::Isometry3d G = pivot_transform(x);
    Eigen::Matrix<double, 12, 1> r;
    r.head<3>() = (G.translation() - target.translation()) / length_;
    const Eigen::Matrix3d dR = G.linear() - target.linear();
    for (int k = 0; k < 9; ++k) r(3 + k) = dR(k);
    return r;
  };
  Eigen::Matrix<double, 12, 1> r = residuals(dofs);
  double lambda = 1e-3;
  for (int it = 0; it < 100 && r.norm() > 1e-12; ++it) {
    Eigen::MatrixXd Jm(12, n);
    for (int k = 0; k < n; ++k) {
      Eigen::VectorXd x = dofs;
      const double h = 1e-7 * std::max(1.0, std::abs(x(param_.root_dofs[size_t(k)])));
      x(param_.root_dofs[size_t(k)]) += h;
      Jm.col(k) = (residuals(x) - r) / h;
    }
    const Eigen::MatrixXd A = Jm.transpose() * Jm;
    const Eigen::VectorXd g = Jm.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 10 && !improved; ++tries) {
      Eigen::MatrixXd D = A;
      D.diagonal().array() += lambda * (1.0 + A.diagonal().array());
      const Eigen::VectorXd step = D.ldlt().solve(-g);
      Eigen::VectorXd x = dofs;
      for (int k = 0; k < n; ++k) x(param_.root_dofs[size_t(k)]) += step(k);
      const Eigen::Matrix<double, 12, 1> rx = residuals(x);
      if (rx.norm() < r.norm()) {
        dofs = x, r = rx, improved = true;
        lambda = std::max(1e-9, lambda / 10);
      } else {
        lambda *= 10;
      }
    }
    if (!improved) break;
  }
  if (residual) *residual = r.norm();
  return dofs;
}

Eigen::VectorXd RootPlacement::place(const Eigen::VectorXd& dofs, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
                                     const Eigen::VectorXd* previous, double* residual) const {
  WEFT_CHECK(dofs.size() == character_.skeleton.num_dofs(), "RootPlacement: ", dofs.size(), " dofs, expected ",
             character_.skeleton.num_dofs());
  WEFT_CHECK(R.allFinite() && t.allFinite(), "RootPlacement: non-finite rotation or translation");
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.linear() = R * rest_pivot_.linear();
  target.translation() = R * (rest_pivot_.translation() - param_.pivot) + t;
  constexpr double kConverged = 1e-8;
  double best_residual = INFINITY;
  Eigen::VectorXd best = dofs;
  auto attempt = [&](Eigen::VectorXd start) {
    double res = 0;
    Eigen::VectorXd x = solve(std::move(start), target, &res);
    if (res < best_residual) best_residual = res, best = x;
  };
  if (previous) {
    Eigen::VectorXd start = dofs;
    for (int d : param_.root_dofs) start(d) = (*previous)(d);
    attempt(start);
  }
  if (!(best_residual < kConverged)) {
    // Starts: the rest pose, and each revolute root dof turned by π (Euler chains have two
    // solutions, and damped Gauss–Newton may stall near a gimbal lock from a poor start).
    const Skeleton& s = character_.skeleton;
    std::vector<int> revolute;
    for (int d : param_.root_dofs) {
      bool rotates = false;
      for (const DofInfluence& inf : s.dofs[size_t(d)].joints)
        rotates |= s.joints[size_t(inf.joint)].type == JointType::revolute;
      if (rotates) revolute.push_back(d);
    }
    const int combos = 1 << std::min<int>(int(revolute.size()), 3);
    for (int c = 0; c < combos && !(best_residual < kConverged); ++c) {
      Eigen::VectorXd start = dofs;
      for (size_t k = 0; k < revolute.size() && k < 3; ++k)
        if (c & (1 << k)) {
          double w = 1;
          for (const DofInfluence& inf : s.dofs[size_t(revolute[k])].joints) w = inf.weight;
          start(revolute[k]) += 3.14159265358979323846 / w;
        }
      attempt(start);
    }
  }
  if (residual) *residual = best_residual;
  return best;
}

}  // namespace weft::capture
