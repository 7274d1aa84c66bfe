// CholmodSolver: every ordering solves the system, the solver never changes the calling
// thread's OpenMP parallelism, and orderings computed on several threads at once equal
// one computed alone.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/Cholesky>
#include <thread>

#include "physics/cholmod_solver.h"
#include "physics/cloth_model.h"
#include "physics/membrane_energy.h"
#include "physics/vertex_energies.h"

namespace weft::physics {
namespace {

// A cloth Hessian (membrane, projected, plus the mass term of a 1/60 s step) of a
// stretched nx × nx grid: symmetric positive definite, with the simulator's pattern.
SparseHessian stretched_cloth_hessian(int nx) {
  const ClothMesh mesh = make_grid_cloth(Vec3(0, 0, 0), 1.0, 1.0, nx, nx, "xz", 0.2);
  MembraneEnergy membrane(mesh, ClothMaterial{});
  membrane.set_hessian_projection(true);
  InertiaEnergy inertia(mesh.mass, 1.0 / 60);
  inertia.set_prediction(mesh.rest);
  std::vector<std::array<int, 2>> pairs;
  membrane.add_pattern(pairs);
  SparseHessian h(mesh.num_vertices(), pairs);
  h.set_zero();
  Eigen::VectorXd x = 1.05 * mesh.rest;
  for (int i = 0; i < mesh.num_vertices(); ++i) x[3 * i + 1] += 0.01 * std::sin(0.7 * i);
  membrane.evaluate(x, nullptr, &h);
  inertia.evaluate(x, nullptr, &h);
  return h;
}

Eigen::VectorXd right_hand_side(int rows) {
  Eigen::VectorXd b(rows);
  for (int i = 0; i < rows; ++i) b[i] = std::cos(0.37 * i);
  return b;
}

TEST(CholmodSolver, EveryOrderingSolvesTheSystem) {
  const SparseHessian h = stretched_cloth_hessian(12);
  const Eigen::MatrixXd dense = Eigen::MatrixXd(h.to_full());
  const Eigen::VectorXd b = right_hand_side(h.rows());
  const Eigen::VectorXd expected = dense.llt().solve(b);
  for (CholeskyOrdering ordering :
       {CholeskyOrdering::amd, CholeskyOrdering::nested_dissection, CholeskyOrdering::metis}) {
    for (CholeskyKind kind : {CholeskyKind::simplicial, CholeskyKind::supernodal}) {
      CholmodSolver solver(h, kind, ordering);
      ASSERT_TRUE(solver.factorize(h));
      const Eigen::VectorXd x = solver.solve(b);
      EXPECT_LE((x - expected).lpNorm<Eigen::Infinity>(), 1e-9 * expected.lpNorm<Eigen::Infinity>())
          << "ordering " << static_cast<int>(ordering) << ", kind " << static_cast<int>(kind);
      EXPECT_GT(solver.factor_nonzeros(), h.nonzeros() / 2.0);
    }
  }
}

TEST(CholmodSolver, NestedDissectionNeedsFewerFlopsThanAmdOnALargeGrid) {
  const SparseHessian h = stretched_cloth_hessian(48);
  const CholmodSolver amd(h, CholeskyKind::supernodal, CholeskyOrdering::amd);
  const CholmodSolver metis(h, CholeskyKind::supernodal, CholeskyOrdering::metis);
  EXPECT_LT(metis.factor_flops(), amd.factor_flops());
}

TEST(CholmodSolver, LeavesTheCallersOpenMpParallelismAlone) {
  omp_set_max_active_levels(3);
  const SparseHessian h = stretched_cloth_hessian(16);
  CholmodSolver solver(h, CholeskyKind::supernodal);
  ASSERT_TRUE(solver.factorize(h));
  solver.solve(right_hand_side(h.rows()));
  EXPECT_EQ(omp_get_max_active_levels(), 3);
  int team = 0;
#pragma omp parallel num_threads(2)
  {
#pragma omp single
    team = omp_get_num_threads();
  }
  EXPECT_EQ(team, 2);
}

TEST(CholmodSolver, OrderingsOnSeveralThreadsEqualOneAlone) {
  const SparseHessian h = stretched_cloth_hessian(24);
  const Eigen::VectorXd b = right_hand_side(h.rows());
  auto solve = [&]() {
    CholmodSolver solver(h, CholeskyKind::supernodal, CholeskyOrdering::metis);
    EXPECT_TRUE(solver.factorize(h));
    return solver.solve(b);
  };
  const Eigen::VectorXd alone = solve();
  std::vector<Eigen::VectorXd> results(4);
  std::vector<std::thread> threads;
  for (size_t t = 0; t < results.size(); ++t)
    threads.emplace_back([&, t]() { results[t] = solve(); });
  for (auto& t : threads) t.join();
  for (const auto& r : results) EXPECT_EQ((r - alone).lpNorm<Eigen::Infinity>(), 0.0);
}

}  // namespace
}  // namespace weft::physics
