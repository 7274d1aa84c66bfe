// Finite-difference checks of every energy's gradient and Hessian and PSD projection (one
// table, energy_cases(), with a coverage test over the simulator's energies), the laws of
// the tension-field membrane, the collision band and its second sheet, and the invariance
// of the internal energies under rigid motions.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <string>

#include "graph/error.h"
#include "physics/bending_energy.h"
#include "physics/cloth_simulator.h"
#include "physics/friction_energy.h"
#include "physics/cloth_model.h"
#include "physics/collision_energy.h"
#include "physics/membrane_energy.h"
#include "physics/vertex_energies.h"
#include "tests/physics/physics_test_util.h"

namespace weft::physics {
namespace {

ClothMesh small_grid(int n = 4) {
  return make_grid_cloth(Vec3(0, 0, 0), 0.3, 0.3, n, n, "xz", 0.2);
}

Eigen::VectorXd perturbed(const Eigen::VectorXd& x, double scale, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> nd(0.0, noise);
  Eigen::VectorXd y = scale * x;
  for (int i = 0; i < y.size(); ++i) y[i] += nd(rng);
  return y;
}

ClothMaterial material() {
  ClothMaterial m;
  m.youngs_modulus = 5e5;
  m.poisson_ratio = 0.3;
  m.bending_stiffness = 1e-3;
  m.thickness = 1e-3;
  return m;
}

// The tension-field regime of a Green strain: 0 slack, 1 wrinkled, 2 taut.
int regime(const Eigen::Matrix2d& G, const ClothMaterial& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(G);
  const double g2 = eig.eigenvalues()[0], g1 = eig.eigenvalues()[1];
  const double lambda = m.youngs_modulus * m.poisson_ratio / (1 - m.poisson_ratio * m.poisson_ratio);
  const double mu = m.youngs_modulus / (2 * (1 + m.poisson_ratio));
  if (g1 <= 0) return 0;
  return 2 * mu * g2 + lambda * (g1 + g2) < 0 ? 1 : 2;
}

// One right triangle (legs 0.1 m along x and z) deformed by the 2×2 map A of its plane
// (x, z), lifted off the plane by `lift` at its third vertex.
Positions deformed_triangle(const Eigen::Matrix2d& A, double lift = 0) {
  Positions x(9);
  const Eigen::Vector2d p[3] = {{0, 0}, {0.1, 0}, {0, 0.1}};
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector2d q = A * p[k];
    x.segment<3>(3 * k) << q[0], k == 2 ? lift : 0.0, q[1];
  }
  return x;
}
ClothMesh one_triangle() { return make_cloth_mesh(deformed_triangle(Eigen::Matrix2d::Identity()), {{0, 2, 1}}, 0.2); }

TEST(Energies, TensionFieldMembraneMatchesFiniteDifferencesInEveryRegime) {
  // Single elements well inside each regime (slack, wrinkled, taut), with and without the
  // StVK share, then the PSD projection: value, gradient and exact Hessian agree with
  // central differences.
  const ClothMesh mesh = one_triangle();
  struct Case {
    Eigen::Matrix2d A;
    int regime;
  };
  std::vector<Case> cases;
  auto map = [](double a, double b, double c, double d) { return (Eigen::Matrix2d() << a, b, c, d).finished(); };
  cases.push_back({map(0.9, 0.02, -0.01, 0.85), 0});   // compressed both ways
  cases.push_back({map(1.1, 0.03, 0.01, 0.9), 1});     // stretched along x, compressed along z
  cases.push_back({map(0.8, 0.1, 0.05, 1.15), 1});     // sheared, one direction stretched
  cases.push_back({map(1.1, 0.02, -0.03, 1.05), 2});   // stretched both ways
  for (double rho : {0.0, 1e-2}) {
    ClothMaterial m = material();
    m.membrane = MembraneModel::tension_field;
    m.compression_ratio = rho;
    for (const Case& c : cases) {
      SCOPED_TRACE("rho " + std::to_string(rho) + " regime " + std::to_string(c.regime));
      const Positions x = deformed_triangle(c.A, 0.01);
      // The Green strain of the element, to check the case is in the regime it claims.
      MembraneEnergy e(mesh, m);
      // FᵀF from the deformed unit edges (the lift changes it a little from AᵀA).
      const Eigen::Vector3d ex = (x.segment<3>(3 * 1) - x.segment<3>(0)) / 0.1;
      const Eigen::Vector3d ez = (x.segment<3>(3 * 2) - x.segment<3>(0)) / 0.1;
      Eigen::Matrix2d FtF;
      FtF << ex.dot(ex), ex.dot(ez), ex.dot(ez), ez.dot(ez);
      const Eigen::Matrix2d G = 0.5 * (FtF - Eigen::Matrix2d::Identity());
      ASSERT_EQ(regime(G, m), c.regime);
      if (c.regime == 0 && rho == 0) {
        Eigen::VectorXd g = Eigen::VectorXd::Zero(9);
        EXPECT_EQ(e.evaluate(x, &g, nullptr), 0.0);
        EXPECT_EQ(g.lpNorm<Eigen::Infinity>(), 0.0);
        continue;
      }
      testing::expect_derivatives_match(e, x, 1e-5);
    }
  }
}

TEST(Energies, TensionFieldCompressionCostsOnlyTheRatioOfStvk) {
  // Pure compression (slack): energy and force are compression_ratio × StVK's, and zero
  // with a zero ratio. Pure tension: identical to StVK.
  const ClothMesh mesh = one_triangle();
  ClothMaterial stvk = material(), tf = material();
  stvk.membrane = MembraneModel::stvk;
  tf.membrane = MembraneModel::tension_field;
  tf.compression_ratio = 1e-3;
  MembraneEnergy e_stvk(mesh, stvk), e_tf(mesh, tf);
  const Positions squeezed = deformed_triangle(0.9 * Eigen::Matrix2d::Identity());
  Eigen::VectorXd g_stvk = Eigen::VectorXd::Zero(9), g_tf = Eigen::VectorXd::Zero(9);
  const double w_stvk = e_stvk.evaluate(squeezed, &g_stvk, nullptr);
  const double w_tf = e_tf.evaluate(squeezed, &g_tf, nullptr);
  EXPECT_GT(w_stvk, 0);
  EXPECT_NEAR(w_tf, 1e-3 * w_stvk, 1e-12 * w_stvk);
  EXPECT_LE((g_tf - 1e-3 * g_stvk).norm(), 1e-12 * g_stvk.norm());
  tf.compression_ratio = 0;
  MembraneEnergy e_free(mesh, tf);
  Eigen::VectorXd g_free = Eigen::VectorXd::Zero(9);
  EXPECT_EQ(e_free.evaluate(squeezed, &g_free, nullptr), 0.0);
  EXPECT_EQ(g_free.norm(), 0.0);
  const Positions stretched = deformed_triangle((Eigen::Matrix2d() << 1.1, 0.02, 0.0, 1.05).finished());
  g_stvk.setZero();
  g_tf.setZero();
  EXPECT_DOUBLE_EQ(e_free.evaluate(stretched, &g_tf, nullptr), e_stvk.evaluate(stretched, &g_stvk, nullptr));
  EXPECT_LE((g_tf - g_stvk).norm(), 1e-12 * g_stvk.norm());
}

TEST(Energies, TensionFieldAreaBarrierResistsCollapse) {
  // Below min_area_ratio the element meets a barrier: none at 0.55 of the area, a rising
  // energy and an outward force as the area shrinks to 0.45, 0.3, 0.1, a large finite one
  // at full collapse; its derivatives match finite differences, its projection is PSD.
  const ClothMesh mesh = one_triangle();
  ClothMaterial m = material();
  m.membrane = MembraneModel::tension_field;
  m.compression_ratio = 0;
  m.min_area_ratio = 0.5;
  MembraneEnergy e(mesh, m);
  EXPECT_EQ(e.evaluate(deformed_triangle((Eigen::Matrix2d() << 1.0, 0, 0, 0.55).finished()), nullptr, nullptr), 0.0);
  double last = 0;
  for (double area : {0.45, 0.3, 0.1, 0.01}) {
    SCOPED_TRACE("area ratio " + std::to_string(area));
    const Positions x = deformed_triangle((Eigen::Matrix2d() << 1.0, 0.05, 0, area).finished());
    Eigen::VectorXd g = Eigen::VectorXd::Zero(9);
    const double w = e.evaluate(x, &g, nullptr);
    EXPECT_GT(w, last);
    last = w;
    // The force −g on the vertex across the squeezed (z) leg pushes it outward (+z).
    EXPECT_GT(-g[3 * 2 + 2], 0.0);
    if (area >= 0.1) testing::expect_derivatives_match(e, deformed_triangle((Eigen::Matrix2d() << 1.0, 0.05, 0, area).finished(), 0.002), 1e-5);
  }
  const Positions collapsed = deformed_triangle((Eigen::Matrix2d() << 1.0, 1.0, 0, 0).finished());
  Eigen::VectorXd g = Eigen::VectorXd::Zero(9);
  EXPECT_TRUE(std::isfinite(e.evaluate(collapsed, &g, nullptr)));
  EXPECT_TRUE(g.allFinite());
}

TEST(Energies, TensionFieldUniaxialTensionContractsFreely) {
  // Stretched by s along x and held at any width below the free Poisson contraction
  // (g_z < −ν g_x; 0.968 of the width at s = 1.1): the
  // relaxed energy is the uniaxial one, A·t·k·g², k = 2μ(μ+λ)/(2μ+λ) = E/2 in plane
  // stress (the same as ψ_stvk with the free contraction g_z = −ν g_x).
  const ClothMesh mesh = one_triangle();
  ClothMaterial m = material();
  m.membrane = MembraneModel::tension_field;
  m.compression_ratio = 0;
  MembraneEnergy e(mesh, m);
  const double s = 1.1, gx = 0.5 * (s * s - 1);
  const double area_t = 0.5 * 0.1 * 0.1 * m.thickness;
  for (double width : {0.95, 0.9, 0.7}) {
    const Positions x = deformed_triangle((Eigen::Matrix2d() << s, 0, 0, width).finished());
    EXPECT_NEAR(e.evaluate(x, nullptr, nullptr), area_t * 0.5 * m.youngs_modulus * gx * gx,
                1e-12 * area_t * m.youngs_modulus) << "width " << width;
  }
}

TEST(Energies, TensionFieldStressIsContinuousAcrossTheWrinklingBoundary) {
  // C¹: the stress just inside the taut regime equals the stress just inside the
  // wrinkled one, for the blended model too.
  ClothMaterial m = material();
  m.membrane = MembraneModel::tension_field;
  const double lambda = m.youngs_modulus * m.poisson_ratio / (1 - m.poisson_ratio * m.poisson_ratio);
  const double mu = m.youngs_modulus / (2 * (1 + m.poisson_ratio));
  const double g1 = 0.05, g2_star = -lambda * g1 / (2 * mu + lambda);  // s₂ = 0 here
  const Eigen::Matrix2d R = Eigen::Rotation2Dd(0.4).toRotationMatrix();
  for (double rho : {0.0, 1e-3}) {
    m.compression_ratio = rho;
    auto at = [&](double g2) {
      return membrane_response(R * Eigen::Vector2d(g1, g2).asDiagonal() * R.transpose(), m);
    };
    const MembraneResponse taut = at(g2_star + 1e-9), wrinkled = at(g2_star - 1e-9);
    ASSERT_EQ(regime(R * Eigen::Vector2d(g1, g2_star + 1e-9).asDiagonal() * R.transpose(), m), 2);
    ASSERT_EQ(regime(R * Eigen::Vector2d(g1, g2_star - 1e-9).asDiagonal() * R.transpose(), m), 1);
    EXPECT_NEAR(taut.psi, wrinkled.psi, 1e-6 * taut.psi);
    EXPECT_LE((taut.stress - wrinkled.stress).norm(), 1e-5 * taut.stress.norm()) << "rho " << rho;
  }
}

TEST(Energies, MembraneMatchesUniaxialStretchFormula) {
  // Stretch a single right triangle by s along x: G = diag((s²−1)/2, 0), so
  // W = A t (μ + λ/2) ((s²−1)/2)².
  const Positions rest = (Eigen::VectorXd(9) << 0, 0, 0, 1, 0, 0, 0, 0, 1).finished();
  const ClothMesh mesh = make_cloth_mesh(rest, {{0, 2, 1}}, 0.2);
  const ClothMaterial m = material();
  MembraneEnergy e(mesh, m);
  const double s = 1.1;
  Positions x = rest;
  x[3] = s;
  const double lambda = m.youngs_modulus * m.poisson_ratio / (1 - m.poisson_ratio * m.poisson_ratio);
  const double mu = m.youngs_modulus / (2 * (1 + m.poisson_ratio));
  const double gxx = 0.5 * (s * s - 1);
  EXPECT_NEAR(e.evaluate(x, nullptr, nullptr), 0.5 * m.thickness * (mu + 0.5 * lambda) * gxx * gxx,
              1e-12);
}

TEST(Energies, DihedralAngleOfAFoldIsSigned) {
  const Vec3 x0(0, 0, 0), x1(1, 0, 0), x2(0.5, 0, -1);
  const double a = 0.7;  // fold the second triangle by `a` radians about the x axis
  const Vec3 x3(0.5, std::sin(a), std::cos(a));
  const Vec3 x3m(0.5, -std::sin(a), std::cos(a));
  EXPECT_NEAR(std::abs(dihedral_angle(x0, x1, x2, x3)), a, 1e-12);
  EXPECT_NEAR(dihedral_angle(x0, x1, x2, x3), -dihedral_angle(x0, x1, x2, x3m), 1e-12);
  EXPECT_NEAR(dihedral_angle(x0, x1, x2, Vec3(0.5, 0, 1)), 0.0, 1e-12);
}

TEST(Energies, RayConstraintIsZeroOnTheRay) {
  RayConstraintEnergy rays({{0, Vec3(0, 1, 0), Vec3(0, -2, 0)}}, 30.0);
  EXPECT_NEAR(rays.evaluate(Eigen::Vector3d(0, -3, 0), nullptr, nullptr), 0.0, 1e-15);
  EXPECT_NEAR(rays.evaluate(Eigen::Vector3d(0.1, -3, 0), nullptr, nullptr), 0.5 * 30 * 0.01, 1e-12);
}

TEST(Energies, CollisionPenaltyIsSmoothAtTheBandEdge) {
  // E = k/(6δ)(δ − d)³: force and stiffness vanish as d → δ from inside (C²), the
  // stiffness along the normal is k at contact (d = 0) and the force there k·δ/2.
  const double k = 1e4, delta = 0.01, r = 0.5;
  CollisionEnergy e(1, delta, k);
  e.set_spheres({{Vec3(0, 0, 0), r}});
  std::vector<std::array<int, 2>> pairs;
  SparseHessian h(1, pairs);
  auto probe = [&](double d, double& force, double& stiffness) {
    const Eigen::VectorXd x = Eigen::Vector3d(0, r + d, 0);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3);
    h.set_zero();
    e.evaluate(x, &g, &h);
    force = -g[1];
    stiffness = h.to_full().coeff(1, 1);
  };
  double f, s;
  probe(delta * (1 - 1e-6), f, s);
  EXPECT_LT(f, 1e-9 * k * delta);
  EXPECT_LT(s, 1e-5 * k);
  probe(delta * 1.001, f, s);
  EXPECT_EQ(f, 0.0);
  EXPECT_EQ(s, 0.0);
  probe(0.0, f, s);
  EXPECT_NEAR(f, 0.5 * k * delta, 1e-9 * k * delta);
  EXPECT_NEAR(s, k, 1e-9 * k);
}

// Two boxes 6 mm apart in one body mesh (two thighs): a vertex in the gap is within the
// 4 mm band of both. With the closest face alone the penalty's force jumps from one wall's
// push to the other's as the vertex crosses the medial plane, so no point of the gap is
// an equilibrium Newton can reach; with the second sheet on, the force is continuous, zero
// on the medial plane, and derivatives match finite differences on either side.
TEST(Energies, AVertexBetweenTwoSheetsFeelsBothWhenTheSecondSheetIsOn) {
  const BodyMesh left = testing::cube(Vec3(-0.503, 0, 0), 0.5), right = testing::cube(Vec3(0.503, 0, 0), 0.5);
  Eigen::MatrixX3d v(16, 3);
  v << left.vertices(), right.vertices();
  std::vector<std::array<int, 3>> f = left.faces();
  for (auto t : right.faces()) f.push_back({t[0] + 8, t[1] + 8, t[2] + 8});
  const BodyMesh gap(v, f);  // walls at x = ±3 mm
  auto force_x = [&](const CollisionEnergy& e, double x) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3);
    e.evaluate(Eigen::Vector3d(x, 0.1, 0.2), &g, nullptr);
    return -g[0];
  };
  CollisionEnergy closest_only(1, 0.004, 1e4);
  closest_only.set_bodies({&gap});
  CollisionEnergy both(1, 0.004, 1e4);
  both.set_bodies({&gap});
  both.set_second_sheet_angle(45);
  const double h = 1e-7;
  // Closest face only: pushed right just left of the middle, left just right of it.
  EXPECT_GT(force_x(closest_only, -h), 1.0);
  EXPECT_LT(force_x(closest_only, h), -1.0);
  // Both sheets: continuous, zero in the middle, restoring on either side.
  EXPECT_NEAR(force_x(both, -h), force_x(both, h), 1e-3);
  EXPECT_NEAR(force_x(both, 0.0), 0.0, 1e-9);
  EXPECT_GT(force_x(both, -0.0005), 0.0);
  EXPECT_LT(force_x(both, 0.0005), 0.0);
  // A vertex near one wall only (the other beyond the band) feels that wall alone.
  EXPECT_EQ(force_x(both, -0.0025), force_x(closest_only, -0.0025));
  Eigen::VectorXd x(6);
  x << -0.0005, 0.1, 0.2, 0.0007, -0.2, 0.1;  // within the band of both walls
  CollisionEnergy both2(2, 0.004, 1e4);
  both2.set_bodies({&gap});
  both2.set_second_sheet_angle(45);
  testing::expect_derivatives_match(both2, x);
  EXPECT_THROW(both.set_second_sheet_angle(180), weft::Error);
  EXPECT_THROW(both.set_second_sheet_angle(-1), weft::Error);
}

// A folded sheet y = |x|·tan(half_angle) over [−0.2, 0.2]² (normals up), 8 × 8 cells, the
// fold along the z axis: a concave crease whose faces turn 2·half_angle; flat at 0.
BodyMesh folded_sheet(double half_angle_deg) {
  const int n = 8;
  const double t = std::tan(half_angle_deg * M_PI / 180);
  Eigen::MatrixX3d v((n + 1) * (n + 1), 3);
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) {
      const double x = -0.2 + 0.4 * i / n, z = -0.2 + 0.4 * j / n;
      v.row(i * (n + 1) + j) << x, std::abs(x) * t, z;
    }
  std::vector<std::array<int, 3>> f;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = i * (n + 1) + j, b = a + n + 1;
      f.push_back({a, a + 1, b});  // (x, z) counter-clockwise seen from +y
      f.push_back({b, a + 1, b + 1});
    }
  return BodyMesh(v, f);
}

// Smooth creases (the penalty summed over the faces, edges and vertices in the band with
// inclusion–exclusion weights) on a flat sheet and on a cube: above a face, an edge (shared
// by two faces) or a vertex (shared by four or six), and beside a cube's convex edges and
// corners, it is the closest-face penalty: each neighbourhood counted once.
TEST(Energies, SmoothCreasesAreTheClosestFacePenaltyOnFlatAndConvexSurfaces) {
  const BodyMesh flat = folded_sheet(0), box = testing::cube(Vec3(0, 0, 0), 0.1);
  auto compare = [](const BodyMesh& body, const Vec3& p) {
    CollisionEnergy closest(1, 0.004, 1e4), smooth(1, 0.004, 1e4);
    closest.set_bodies({&body});
    smooth.set_bodies({&body});
    smooth.set_smooth_creases(true);
    Eigen::VectorXd g1 = Eigen::VectorXd::Zero(3), g2 = Eigen::VectorXd::Zero(3);
    const double e1 = closest.evaluate(p, &g1, nullptr), e2 = smooth.evaluate(p, &g2, nullptr);
    EXPECT_GT(e1, 0.0) << p.transpose();
    EXPECT_NEAR(e2, e1, 1e-12 * e1) << p.transpose();
    EXPECT_LE((g2 - g1).norm(), 1e-9 * g1.norm()) << p.transpose();
  };
  compare(flat, Vec3(0.01, 0.002, 0.013));   // over a face
  compare(flat, Vec3(0.05, 0.003, 0.02));    // over an edge along z
  compare(flat, Vec3(0.0, 0.001, 0.05));     // over a vertex
  compare(flat, Vec3(0.025, 0.0035, 0.025)); // over a diagonal edge's midpoint
  compare(box, Vec3(0.03, 0.102, -0.01));    // over a face of the cube
  compare(box, Vec3(0.0, 0.102, 0.0));       // over the diagonal of the top face
  compare(box, Vec3(0.101, 0.102, 0.02));    // beside a convex edge
  compare(box, Vec3(0.101, 0.102, 0.1025));  // beside a corner
}

// In a concave crease whose faces turn 24° (traced in the squat: a vertex equidistant to
// 1 µm from two such faces, Newton stalled for 200 iterations), the closest face's
// penalty pushes toward the other side on either side of the medial plane, so its force
// jumps there; with smooth creases both faces push, the force is continuous and has no
// component across the medial plane on it, and derivatives match finite differences.
TEST(Energies, SmoothCreasesMakeTheForceContinuousAcrossAConcaveCrease) {
  const BodyMesh crease = folded_sheet(12);
  CollisionEnergy closest(1, 0.004, 1e4), smooth(1, 0.004, 1e4);
  closest.set_bodies({&crease});
  smooth.set_bodies({&crease});
  smooth.set_smooth_creases(true);
  auto force = [&](const CollisionEnergy& e, double x) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(3);
    e.evaluate(Eigen::Vector3d(x, 0.003, 0.013), &g, nullptr);
    return Vec3(-g);
  };
  const double h = 1e-7;
  EXPECT_GT(force(closest, -h).x(), 0.1);
  EXPECT_LT(force(closest, h).x(), -0.1);
  EXPECT_LT((force(smooth, -h) - force(smooth, h)).norm(), 1e-4 * force(smooth, 0).norm());
  EXPECT_NEAR(force(smooth, 0).x(), 0.0, 1e-9);
  EXPECT_GT(force(smooth, 0).y(), force(closest, 0).y());  // both faces push
  Eigen::VectorXd x(9);
  x << 0.0, 0.003, 0.013,  0.0004, 0.0025, -0.05,  -0.03, 0.0075, 0.1;  // the ridge, by it, a wing
  CollisionEnergy e(3, 0.004, 1e4);
  e.set_bodies({&crease});
  e.set_smooth_creases(true);
  testing::expect_derivatives_match(e, x);
}

TEST(Energies, BodyMeshSignedDistance) {
  const BodyMesh sphere = testing::uv_sphere(Vec3(0, 1, 0), 0.3);
  EXPECT_LT(sphere.closest_point(Vec3(0, 1, 0)).distance, -0.28);
  EXPECT_NEAR(sphere.closest_point(Vec3(0.7, 1, 0)).distance, 0.4, 0.01);
  EXPECT_NEAR(sphere.closest_point(Vec3(0, 1.5, 0)).distance, 0.2, 1e-9);  // a pole vertex
  // The tree gives the same answer as brute force over every face.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (int k = 0; k < 200; ++k) {
    const Vec3 p(u(rng), 1 + u(rng), u(rng));
    double best = 1e300;
    for (const auto& f : sphere.faces()) {
      // Brute force on a fine sampling is not exact; compare with each face's own query.
      Eigen::MatrixX3d v(3, 3);
      for (int a = 0; a < 3; ++a) v.row(a) = sphere.vertices().row(f[a]);
      BodyMesh one(v, {{0, 1, 2}});
      best = std::min(best, std::abs(one.closest_point(p).distance));
    }
    EXPECT_NEAR(std::abs(sphere.closest_point(p).distance), best, 1e-12);
  }
}

// The generalized winding number tells inside from outside, and the signed distance agrees
// with it where the surface folds over (a skinned body at a far-bent joint): a sphere with one
// vertex of its top ring pulled down through it and out of its bottom, a spike whose faces
// face opposite ways. There the closest vertex's pseudo-normal said "inside" for points around
// the spike's tip that lie outside the body.
TEST(Energies, BodyMeshSignAgreesWithTheWindingNumberWhereTheSurfaceFolds) {
  const BodyMesh sphere = testing::uv_sphere(Vec3(0, 1, 0), 0.3);
  EXPECT_NEAR(sphere.winding_number(Vec3(0, 1, 0)), 1.0, 1e-9);
  EXPECT_NEAR(sphere.winding_number(Vec3(0.1, 1.2, -0.05)), 1.0, 1e-9);
  EXPECT_NEAR(sphere.winding_number(Vec3(0.5, 1, 0)), 0.0, 1e-9);
  EXPECT_NEAR(sphere.winding_number(Vec3(0, 0.5, 0.2)), 0.0, 1e-9);

  Eigen::MatrixX3d v = sphere.vertices();
  const int spike = 1;  // a vertex of the first ring below the north pole
  const Vec3 tip(0.02, 0.55, 0.01);  // 15 cm below the sphere's bottom
  v.row(spike) = tip.transpose();
  const BodyMesh folded(v, sphere.faces());
  int folded_vertices = 0;
  for (int k = 0; k < v.rows(); ++k) {
    folded_vertices += folded.folded(k);
    EXPECT_FALSE(sphere.folded(k)) << k;
  }
  EXPECT_TRUE(folded.folded(spike));
  EXPECT_LE(folded_vertices, 8) << "the spike and its neighbours only";
  // The tip's angle-weighted pseudo-normal, as the sign was taken before.
  Vec3 pseudo = Vec3::Zero();
  for (const auto& f : folded.faces())
    for (int k = 0; k < 3; ++k)
      if (f[k] == spike) {
        const Vec3 a = v.row(f[k]).transpose(), b = v.row(f[(k + 1) % 3]).transpose(),
                   c = v.row(f[(k + 2) % 3]).transpose();
        const Vec3 n = (b - a).cross(c - a).normalized();
        pseudo += std::acos(std::clamp((b - a).normalized().dot((c - a).normalized()), -1.0, 1.0)) * n;
      }
  pseudo.normalize();
  int outside_but_pseudo_inside = 0, checked = 0;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 24; ++j) {
      const double th = M_PI * (i + 0.5) / 12, ph = 2 * M_PI * j / 24;
      const Vec3 x = tip + 0.02 * Vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
      const ClosestPoint c = folded.closest_point(x);
      const bool inside = folded.winding_number(x) >= 0.5;
      EXPECT_EQ(c.distance < 0, inside) << "x = " << x.transpose() << ", winding " << folded.winding_number(x);
      EXPECT_NEAR(std::abs(c.distance), (x - c.point).norm(), 1e-12);
      ++checked;
      if ((c.point - tip).norm() < 1e-12 && !inside && (x - tip).dot(pseudo) < 0) ++outside_but_pseudo_inside;
    }
  EXPECT_GT(outside_but_pseudo_inside, 0) << "the case the winding number decides: outside, behind the tip's pseudo-normal";
  EXPECT_EQ(checked, 288);
}

// A side of the body known from an earlier query (a point that moved less than its distance
// has not crossed the surface) replaces the winding number where the surface folds, and the
// collision energy that uses it, asked again and again as its vertices move, gives exactly
// what a fresh energy gives at each position: the shortcut changes time, not results.
TEST(Energies, BodyMeshKnownSideReplacesTheWindingNumberAndChangesNoResult) {
  const BodyMesh sphere = testing::uv_sphere(Vec3(0, 1, 0), 0.3);
  Eigen::MatrixX3d v = sphere.vertices();
  const Vec3 tip(0.02, 0.55, 0.01);
  v.row(1) = tip.transpose();  // the spike of the test above
  const BodyMesh folded(v, sphere.faces());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<Vec3> points;
  int decided_by_side = 0;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 24; ++j) {
      const double th = M_PI * (i + 0.5) / 12, ph = 2 * M_PI * j / 24;
      const Vec3 x = tip + 0.02 * Vec3(std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
      points.push_back(x);
      const ClosestPoint unknown = folded.closest_point(x);
      const ClosestPoint out = folded.closest_point(x, inf, BodyMesh::Side::outside);
      const ClosestPoint in = folded.closest_point(x, inf, BodyMesh::Side::inside);
      const bool inside = folded.winding_number(x) >= 0.5;
      EXPECT_EQ((inside ? in : out).distance, unknown.distance) << "the true side gives the winding number's answer";
      EXPECT_EQ(std::abs(out.distance), std::abs(unknown.distance));
      if (out.distance > 0 && in.distance < 0) ++decided_by_side;
    }
  EXPECT_GT(decided_by_side, 0) << "points where the pseudo-normal is doubted and the side decides";

  const int n = static_cast<int>(points.size());
  Eigen::VectorXd x(3 * n);
  for (int i = 0; i < n; ++i) x.segment<3>(3 * i) = points[i];
  for (const bool smooth : {false, true}) {
    CollisionEnergy reused(n, 0.03, 1e4);  // a band wide enough to hold every point
    reused.set_smooth_creases(smooth);
    reused.set_bodies({&folded});
    std::mt19937 rng(7);
    std::normal_distribution<double> step(0.0, 1e-3);  // m
    Eigen::VectorXd y = x;
    for (int round = 0; round < 6; ++round) {
      CollisionEnergy fresh(n, 0.03, 1e4);
      fresh.set_smooth_creases(smooth);
      fresh.set_bodies({&folded});
      Eigen::VectorXd g_reused = Eigen::VectorXd::Zero(3 * n), g_fresh = Eigen::VectorXd::Zero(3 * n);
      const double e_reused = reused.evaluate(y, &g_reused, nullptr);
      const double e_fresh = fresh.evaluate(y, &g_fresh, nullptr);
      EXPECT_GT(e_fresh, 0);
      EXPECT_EQ(e_reused, e_fresh) << "smooth creases " << smooth << ", round " << round;
      EXPECT_EQ((g_reused - g_fresh).cwiseAbs().maxCoeff(), 0.0);
      for (int k = 0; k < y.size(); ++k) y[k] += step(rng);
    }
  }
}

// The smooth creases' query (one walk of the tree) gives closest_point's answer and exactly
// the faces within the band, each with its own closest point, as brute force over all faces.
TEST(Energies, BodyMeshClosestPointAndFacesWithinTheBandMatchBruteForce) {
  const BodyMesh sphere = testing::uv_sphere(Vec3(0, 1, 0), 0.3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<BodyMesh::FaceNear> near;
  int with_faces = 0;
  for (int k = 0; k < 300; ++k) {
    Vec3 dir(u(rng), u(rng), u(rng));
    dir.normalize();
    const double band = 0.004 + 0.02 * (k % 3);
    const Vec3 p = Vec3(0, 1, 0) + dir * (0.3 + 0.03 * u(rng));  // within a few cm of the surface
    const ClosestPoint a = sphere.closest_point(p), b = sphere.closest_point_and_faces_within(p, band, near);
    EXPECT_EQ(a.face, b.face);
    EXPECT_EQ(a.distance, b.distance);
    std::vector<int> expected, got;
    for (size_t f = 0; f < sphere.faces().size(); ++f) {
      Eigen::Vector3d w;
      const auto& t = sphere.faces()[f];
      const Vec3 q = weft::closest_point_on_triangle(p, sphere.vertices().row(t[0]).transpose(),
                                                     sphere.vertices().row(t[1]).transpose(),
                                                     sphere.vertices().row(t[2]).transpose(), w);
      if ((p - q).norm() < band) expected.push_back(int(f));
    }
    for (const BodyMesh::FaceNear& n : near) {
      got.push_back(n.face);
      EXPECT_NEAR((p - n.point).squaredNorm(), n.distance2, 1e-15);
      EXPECT_LT(n.distance2, band * band);
    }
    std::sort(got.begin(), got.end());
    EXPECT_EQ(got, expected) << "point " << k;
    with_faces += !expected.empty();
  }
  EXPECT_GT(with_faces, 100);  // the points test the band, not only its absence
}

TEST(Energies, RigidMotionsGiveZeroMembraneAndBendingForce) {
  ClothMesh flat = small_grid(5);
  Positions rest = flat.rest;
  for (int i = 0; i < flat.num_vertices(); ++i) rest[3 * i + 1] = 0.1 * std::sin(5 * rest[3 * i]);
  const ClothMesh mesh = make_cloth_mesh(rest, flat.triangles, 0.2);
  MembraneEnergy membrane(mesh, material());
  BendingEnergy bending(mesh, material());
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(0.9, Eigen::Vector3d(1, 2, -0.5).normalized()).toRotationMatrix();
  Positions x(rest.size());
  for (int i = 0; i < mesh.num_vertices(); ++i)
    x.segment<3>(3 * i) = R * rest.segment<3>(3 * i) + Vec3(0.3, -1.0, 2.0);
  for (const Energy* e : {static_cast<const Energy*>(&membrane), static_cast<const Energy*>(&bending)}) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
    const double w = e->evaluate(x, &g, nullptr);
    EXPECT_NEAR(w, 0.0, 1e-14) << e->name();
    EXPECT_LT(g.lpNorm<Eigen::Infinity>(), 1e-9) << e->name();
  }
  // A non-rigid motion does produce forces (the test can fail).
  Positions y = x;
  y[0] += 0.01;
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  membrane.evaluate(y, &g, nullptr);
  EXPECT_GT(g.lpNorm<Eigen::Infinity>(), 1e-3);
}

// The finite-difference check of every energy the simulator assembles: each entry builds
// an energy and checks value, gradient and exact Hessian against central differences
// (testing::expect_derivatives_match). The coverage test below fails on an energy of the
// simulator without an entry, as the op registry's gradient checks do for ops.
struct EnergyCase {
  std::string energy;  // Energy::name()
  std::string what;
  std::function<void()> check;
};

std::vector<EnergyCase> energy_cases() {
  std::vector<EnergyCase> c;
  c.push_back({"inertia", "inertia about a perturbed prediction", [] {
    const ClothMesh mesh = small_grid();
    InertiaEnergy e(mesh.mass, 0.01);
    e.set_prediction(perturbed(mesh.rest, 1.0, 0.01, 1));
    testing::expect_derivatives_match(e, perturbed(mesh.rest, 1.0, 0.01, 2));
  }});
  c.push_back({"gravity", "linear: gradient −m g, zero Hessian", [] {
    const ClothMesh mesh = small_grid();
    GravityEnergy e(mesh.mass, Vec3(0, -9.81, 0));
    // Linear energy: its Hessian is zero, and the gradient is −m g.
    Eigen::VectorXd g = Eigen::VectorXd::Zero(mesh.rest.size());
    e.evaluate(mesh.rest, &g, nullptr);
    EXPECT_NEAR(g[1], mesh.mass[0] * 9.81, 1e-15);
    testing::expect_derivatives_match(e, perturbed(mesh.rest, 1.0, 0.01, 3));
  }});
  c.push_back({"membrane", "StVK and tension field, stretched, compressed and near rest", [] {
    const ClothMesh mesh = small_grid();
    for (MembraneModel model : {MembraneModel::stvk, MembraneModel::tension_field}) {
      SCOPED_TRACE(to_string(model));
      ClothMaterial m = material();
      m.membrane = model;
      m.compression_ratio = 1e-2;
      MembraneEnergy e(mesh, m);
      testing::expect_derivatives_match(e, perturbed(mesh.rest, 1.2, 0.01, 4));
      testing::expect_derivatives_match(e, perturbed(mesh.rest, 0.8, 0.02, 5));
      // Near rest, with noise: elements on both sides of the tension/compression boundary.
      testing::expect_derivatives_match(e, perturbed(mesh.rest, 1.0, 0.004, 6));
    }
  }});
  c.push_back({"bending", "flat rest shape", [] {
    const ClothMesh mesh = small_grid();
    BendingEnergy e(mesh, material());
    testing::expect_derivatives_match(e, perturbed(mesh.rest, 1.0, 0.02, 6));
  }});
  c.push_back({"bending", "curved rest shape (non-zero rest angles)", [] {
    // A rest shape with non-zero rest angles (a grid bent into a cylinder arc).
    ClothMesh flat = small_grid(5);
    Positions rest = flat.rest;
    for (int i = 0; i < flat.num_vertices(); ++i) {
      const double u = rest[3 * i];
      rest[3 * i] = std::sin(u * 3.0) / 3.0;
      rest[3 * i + 1] = (1 - std::cos(u * 3.0)) / 3.0;
    }
    const ClothMesh mesh = make_cloth_mesh(rest, flat.triangles, 0.2);
    BendingEnergy e(mesh, material());
    EXPECT_NEAR(e.evaluate(mesh.rest, nullptr, nullptr), 0.0, 1e-18);
    testing::expect_derivatives_match(e, perturbed(mesh.rest, 1.0, 0.02, 7));
  }});
  c.push_back({"pins", "three pinned vertices off their targets", [] {
    const ClothMesh mesh = small_grid();
    PinEnergy pins({0, 3, 7}, {Vec3(0, 0.1, 0), Vec3(0.2, 0, 0), Vec3(0, 0, 0.3)}, 50.0);
    testing::expect_derivatives_match(pins, perturbed(mesh.rest, 1.0, 0.01, 8));
  }});
  c.push_back({"collision", "sphere: inside, within and outside the band", [] {
    // Points inside, within and outside the collision band of a sphere.
    const int n = 4;
    Eigen::VectorXd x(3 * n);
    x << 0.0, 0.48, 0.01, 0.3, 0.0, 0.22, -0.1, -0.2, 0.4, 0.0, 0.0, 0.9;
    CollisionEnergy e(n, 0.05, 1e4);
    e.set_spheres({{Vec3(0, 0, 0), 0.5}});
    testing::expect_derivatives_match(e, x);
  }});
  c.push_back({"collision", "mesh: face, edge and corner regions of a cube", [] {
    // Near a cube's face (inside and outside), edge and corner: face, edge and vertex
    // regions of the closest-point query.
    const BodyMesh box = testing::cube(Vec3(0, 0, 0), 0.5);
    const int n = 5;
    Eigen::VectorXd x(3 * n);
    x << 0.1, 0.52, -0.2,   // above the top face
        0.2, 0.49, 0.1,     // just inside the top face
        0.52, 0.53, 0.1,    // beside an edge
        0.52, 0.51, 0.53,   // beside a corner
        0.0, 2.0, 0.0;      // far away
    CollisionEnergy e(n, 0.05, 1e4);
    e.set_bodies({&box});
    testing::expect_derivatives_match(e, x);
  }});
  c.push_back({"collision", "mesh with smooth creases: faces, edges and corners of a cube from outside", [] {
    const BodyMesh box = testing::cube(Vec3(0, 0, 0), 0.5);
    const int n = 4;
    Eigen::VectorXd x(3 * n);
    x << 0.1, 0.52, -0.2,  0.05, 0.51, 0.04,  0.52, 0.53, 0.1,  0.52, 0.51, 0.53;
    CollisionEnergy e(n, 0.05, 1e4);
    e.set_bodies({&box});
    e.set_smooth_creases(true);
    testing::expect_derivatives_match(e, x);
  }});
  c.push_back({"ray_constraint", "two rays, one through a vertex's neighbourhood", [] {
    const ClothMesh mesh = small_grid();
    RayConstraintEnergy rays({{1, Vec3(0, 1, 0), Vec3(0.1, -1, 0.2)}, {5, Vec3(1, 1, 1), Vec3(-1, -1, -1)}}, 30.0);
    testing::expect_derivatives_match(rays, perturbed(mesh.rest, 1.0, 0.01, 9));
  }});
  c.push_back({"friction", "sliding contacts on a sphere, lagged at the step's start", [] {
    const int n = 3;
    Eigen::VectorXd x_start(3 * n), x(3 * n);
    x_start << 0.0, 0.52, 0.0, 0.3, 0.41, 0.0, 0.0, 0.0, 0.53;
    x = x_start + Eigen::VectorXd::Constant(3 * n, 0.004);  // 4 mm slips: the sliding regime
    CollisionEnergy collision(n, 0.05, 1e4);
    collision.set_spheres({{Vec3::Zero(), 0.5, 0.4}});
    FrictionEnergy friction(n, collision, 0.1, 0.01);
    testing::expect_derivatives_match(friction, x, 1e-4, &x_start);
  }});
  return c;
}

TEST(EnergyCoverage, EveryEnergyOfTheSimulatorHasAFiniteDifferenceCase) {
  // The simulator assembles every energy it has, whether its scene uses it or not.
  ClothSimulator sim(small_grid(), testing::simulation_settings(0.01));
  std::set<std::string> covered;
  for (const EnergyCase& c : energy_cases()) covered.insert(c.energy);
  std::string missing;
  ASSERT_GE(sim.solver().energies().size(), 8u);
  for (const Energy* e : sim.solver().energies())
    if (!covered.count(e->name())) missing += " " + e->name();
  EXPECT_TRUE(missing.empty()) << "energies without a case in energy_cases():" << missing;
}

class EnergyCaseTest : public ::testing::TestWithParam<size_t> {};

TEST_P(EnergyCaseTest, MatchesFiniteDifferences) {
  const EnergyCase c = energy_cases().at(GetParam());
  SCOPED_TRACE(c.energy + ": " + c.what);
  c.check();
}

INSTANTIATE_TEST_SUITE_P(AllEnergies, EnergyCaseTest, ::testing::Range<size_t>(0, energy_cases().size()),
                         [](const ::testing::TestParamInfo<size_t>& info) {
                           return energy_cases().at(info.param).energy + "_" + std::to_string(info.param);
                         });

TEST(SparseHessian, MultiplyMatchesFullMatrix) {
  const ClothMesh mesh = small_grid();
  MembraneEnergy e(mesh, material());
  std::vector<std::array<int, 2>> pairs;
  e.add_pattern(pairs);
  SparseHessian h(mesh.num_vertices(), pairs);
  e.evaluate(perturbed(mesh.rest, 1.1, 0.01, 11), nullptr, &h);
  h.add_to_diagonal(0.5);
  const Eigen::VectorXd v = perturbed(mesh.rest, 1.0, 1.0, 12);
  EXPECT_LT((h.multiply(v) - h.to_full() * v).norm(), 1e-9 * v.norm());
}

// The preconditioner's bound (NewtonOptions::factor_without_weak_pairs): on the pattern
// without the hinges' cross pairs, the blocks both patterns hold are the Hessian's own,
// and the matrix bounds the Hessian from above (their difference is PSD), so its factor
// is positive definite whenever the Hessian is.
TEST(SparseHessian, BoundWithoutTheWeakPairsIsAnUpperBound) {
  const ClothMesh mesh = small_grid();
  ClothMaterial m = material();
  m.bending_stiffness = 1e-2;  // a hinge coupling far from negligible
  BendingEnergy bending(mesh, m);
  MembraneEnergy membrane(mesh, m);
  std::vector<std::array<int, 2>> pairs, weak, strong;
  bending.add_pattern(pairs);
  membrane.add_pattern(pairs);
  bending.add_weak_pairs(weak);
  ASSERT_EQ(weak.size(), mesh.hinges.size());
  for (const auto& p : pairs) {
    const bool is_weak = std::any_of(weak.begin(), weak.end(), [&](const auto& w) {
      return (w[0] == p[0] && w[1] == p[1]) || (w[0] == p[1] && w[1] == p[0]);
    });
    if (!is_weak) strong.push_back(p);
  }
  SparseHessian h(mesh.num_vertices(), pairs), coarse(mesh.num_vertices(), strong);
  const Eigen::VectorXd x = perturbed(mesh.rest, 1.05, 0.02, 21);
  bending.evaluate(x, nullptr, &h);
  membrane.evaluate(x, nullptr, &h);
  h.bound_into(coarse);
  const Eigen::MatrixXd H = h.to_full(), C = coarse.to_full();
  int dropped = 0;
  for (int i = 0; i < mesh.num_vertices(); ++i)
    for (int j = 0; j < mesh.num_vertices(); ++j) {
      if (i == j) continue;
      const Eigen::Matrix3d hb = H.block<3, 3>(3 * i, 3 * j), cb = C.block<3, 3>(3 * i, 3 * j);
      if (cb.norm() == 0 && hb.norm() > 0) ++dropped;
      else EXPECT_LT((hb - cb).norm(), 1e-12 * (1 + hb.norm())) << i << ", " << j;
    }
  EXPECT_GT(dropped, 0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(C - H);
  EXPECT_GT(eig.eigenvalues().minCoeff(), -1e-9 * H.norm());
}

}  // namespace
}  // namespace weft::physics
