#pragma once
// Shared helpers of the physics tests: finite-difference checks and small meshes.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <random>

#include "physics/body_mesh.h"
#include "physics/cloth_simulator.h"
#include "physics/energy.h"

namespace weft::physics::testing {

// The simulation tests' cloth: 0.2 kg/m², E = 5e5 Pa, ν = 0.3, k_b = 1e-5 N·m, 1 mm thick;
// Newton to 1e-4 of each vertex's weight, at most 50 iterations per step.
inline SimulationSettings simulation_settings(double time_step) {
  SimulationSettings s;
  s.time_step = time_step;
  s.material.density = 0.2;
  s.material.youngs_modulus = 5e5;
  s.material.poisson_ratio = 0.3;
  s.material.bending_stiffness = 1e-5;
  s.material.thickness = 1e-3;
  s.newton.max_iterations = 50;
  s.newton.tolerance = 1e-4;
  return s;
}

// Central differences of an energy's value and gradient; the Hessian is checked with its
// PSD projection off (the exact Hessian), as PyTorch checks gradients: float64, eps 1e-6.
// The step begins at x_start (default x itself), for energies lagged at the step's start.
inline void expect_derivatives_match(Energy& e, const Eigen::VectorXd& x, double rtol = 1e-4,
                                     const Eigen::VectorXd* x_start = nullptr) {
  const int n3 = static_cast<int>(x.size());
  e.begin_step(x_start ? *x_start : x);
  e.set_hessian_projection(false);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n3);
  e.evaluate(x, &g, nullptr);
  std::vector<std::array<int, 2>> pairs;
  e.add_pattern(pairs);
  SparseHessian h(n3 / 3, pairs);
  h.set_zero();
  e.evaluate(x, nullptr, &h);
  const Eigen::MatrixXd hd = Eigen::MatrixXd(h.to_full());
  const double eps = 1e-6;
  Eigen::VectorXd g_fd(n3);
  Eigen::MatrixXd h_fd(n3, n3);
  for (int i = 0; i < n3; ++i) {
    Eigen::VectorXd xp = x, xm = x;
    xp[i] += eps;
    xm[i] -= eps;
    g_fd[i] = (e.evaluate(xp, nullptr, nullptr) - e.evaluate(xm, nullptr, nullptr)) / (2 * eps);
    Eigen::VectorXd gp = Eigen::VectorXd::Zero(n3), gm = Eigen::VectorXd::Zero(n3);
    e.evaluate(xp, &gp, nullptr);
    e.evaluate(xm, &gm, nullptr);
    h_fd.col(i) = (gp - gm) / (2 * eps);
  }
  const double gscale = std::max(g.lpNorm<Eigen::Infinity>(), 1e-12);
  const double hscale = std::max(hd.lpNorm<Eigen::Infinity>(), 1e-12);
  EXPECT_GT(g.lpNorm<Eigen::Infinity>(), 0.0) << e.name() << ": test state has zero gradient";
  EXPECT_LE((g - g_fd).lpNorm<Eigen::Infinity>(), rtol * gscale) << e.name() << " gradient";
  EXPECT_LE((hd - h_fd).lpNorm<Eigen::Infinity>(), rtol * hscale) << e.name() << " Hessian";
  // The projected Hessian is positive semi-definite.
  e.set_hessian_projection(true);
  h.set_zero();
  e.evaluate(x, nullptr, &h);
  const Eigen::MatrixXd hp = Eigen::MatrixXd(h.to_full());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(hp);
  EXPECT_GE(eig.eigenvalues().minCoeff(), -1e-9 * std::max(hp.lpNorm<Eigen::Infinity>(), 1.0))
      << e.name() << ": projected Hessian is not PSD";
}

// A closed UV sphere of radius r around c, outward-facing triangles.
inline BodyMesh uv_sphere(const Eigen::Vector3d& c, double r, int rings = 12, int segments = 24) {
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<int, 3>> f;
  v.push_back(c + Eigen::Vector3d(0, r, 0));
  for (int i = 1; i < rings; ++i) {
    const double th = M_PI * i / rings;
    for (int j = 0; j < segments; ++j) {
      const double ph = 2 * M_PI * j / segments;
      v.push_back(c + r * Eigen::Vector3d(std::sin(th) * std::cos(ph), std::cos(th),
                                          std::sin(th) * std::sin(ph)));
    }
  }
  v.push_back(c - Eigen::Vector3d(0, r, 0));
  const int bottom = static_cast<int>(v.size()) - 1;
  auto ring = [&](int i, int j) { return 1 + (i - 1) * segments + (j % segments); };
  for (int j = 0; j < segments; ++j) f.push_back({0, ring(1, j + 1), ring(1, j)});
  for (int i = 1; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      f.push_back({ring(i, j), ring(i, j + 1), ring(i + 1, j + 1)});
      f.push_back({ring(i, j), ring(i + 1, j + 1), ring(i + 1, j)});
    }
  for (int j = 0; j < segments; ++j) f.push_back({bottom, ring(rings - 1, j), ring(rings - 1, j + 1)});
  Eigen::MatrixX3d vm(v.size(), 3);
  for (size_t k = 0; k < v.size(); ++k) vm.row(k) = v[k].transpose();
  return BodyMesh(vm, f);
}

// An axis-aligned cube [−h, h]³ around c, 12 outward-facing triangles.
inline BodyMesh cube(const Eigen::Vector3d& c, double h) {
  Eigen::MatrixX3d v(8, 3);
  for (int k = 0; k < 8; ++k)
    v.row(k) = (c + h * Eigen::Vector3d(k & 1 ? 1 : -1, k & 2 ? 1 : -1, k & 4 ? 1 : -1)).transpose();
  std::vector<std::array<int, 3>> f = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},
                                       {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                       {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return BodyMesh(v, f);
}

}  // namespace weft::physics::testing
