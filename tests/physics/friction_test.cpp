// Coulomb friction against obstacles (FrictionEnergy): derivatives against finite
// differences in the static and the sliding regime, the Coulomb force law, a cloth patch
// on an inclined plane that sticks (μ > tan θ) or slides at g(sin θ − μ cos θ), a cloth
// dragged along by a moving body, and monotone Newton steps with friction on.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>

#include "physics/cloth_metrics.h"
#include "physics/cloth_simulator.h"
#include "physics/friction_energy.h"
#include "tests/physics/physics_test_util.h"

namespace weft::physics {
namespace {

// Sphere of radius 0.5 at the origin, band δ = 0.05 m, k = 1e4 N/m; ε = ε_v·h = 1 mm.
constexpr double kDelta = 0.05, kStiffness = 1e4, kVelocity = 0.1, kStep = 0.01;

Vec3 on_sphere(const Vec3& dir, double d) { return (0.5 + d) * dir.normalized(); }

// Slip `s` tangential to the sphere at p (plus a normal part friction must ignore).
Vec3 slipped(const Vec3& p, const Vec3& along, double s, double normal) {
  const Vec3 n = p.normalized();
  const Vec3 t = (along - along.dot(n) * n).normalized();
  return p + s * t + normal * n;
}

TEST(Friction, MatchesFiniteDifferencesStaticAndSliding) {
  // Sphere contacts slipping less than ε (static regime: 0.3 and 0.8 mm) and more
  // (sliding: 2 and 5 mm, one of them penetrating, which is no contact: the penalty pushes
  // it out first), one outside the band (no contact), and a vertex on a cube that moves by
  // 3 mm over the step, slipping 0.4 mm against it.
  const Vec3 dirs[] = {{0.1, 1, 0.2}, {1, 0.3, -0.2}, {-0.4, 0.2, 1}, {0.3, -1, 0.5}};
  const double slips[] = {3e-4, 8e-4, 2e-3, 5e-3};
  const double dists[] = {0.02, 0.01, 0.04, -0.01};
  const int n = 6;
  Eigen::VectorXd x_start(3 * n), x(3 * n);
  for (int i = 0; i < 4; ++i) {
    x_start.segment<3>(3 * i) = on_sphere(dirs[i], dists[i]);
    x.segment<3>(3 * i) = slipped(x_start.segment<3>(3 * i), Vec3(1, -0.5, 0.3), slips[i], 1e-3);
  }
  x_start.segment<3>(12) = on_sphere(Vec3(0, 0, 1), 0.2);  // outside the band
  x.segment<3>(12) = x_start.segment<3>(12) + Vec3(0.01, 0, 0);

  BodyMesh box = testing::cube(Vec3(3, 0, 0), 0.5);  // top face at y = 0.5
  const Eigen::MatrixX3d start = box.vertices();
  Eigen::MatrixX3d moved = start;
  moved.col(0).array() += 0.003;
  box.set_vertices(moved, start);
  x_start.segment<3>(15) = Vec3(3.1, 0.52, -0.2);
  x.segment<3>(15) = x_start.segment<3>(15) + Vec3(0.003, 0.001, 0.0004);

  CollisionEnergy collision(n, kDelta, kStiffness);
  collision.set_spheres({{Vec3::Zero(), 0.5, 0.4}});
  collision.set_bodies({&box});
  FrictionEnergy friction(n, collision, kVelocity, kStep);
  friction.set_body_friction({0.6});
  testing::expect_derivatives_match(friction, x, 1e-4, &x_start);
  EXPECT_EQ(friction.num_contacts(), 4);
}

TEST(Friction, CoulombLawAndTheStaticRegime) {
  const double mu = 0.4, d = 0.02;
  CollisionEnergy collision(1, kDelta, kStiffness);
  collision.set_spheres({{Vec3::Zero(), 0.5, mu}});
  FrictionEnergy friction(1, collision, kVelocity, kStep);
  friction.set_body_friction({});
  const double lambda = kStiffness / (2 * kDelta) * (kDelta - d) * (kDelta - d);
  const double eps = friction.smoothing();
  ASSERT_DOUBLE_EQ(eps, kVelocity * kStep);
  const Eigen::VectorXd x0 = on_sphere(Vec3(0, 1, 0), d);
  friction.begin_step(x0);
  ASSERT_EQ(friction.num_contacts(), 1);
  std::vector<std::array<int, 2>> pairs;
  SparseHessian h(1, pairs);
  // No slip: energy μλε/3, no force, stiffness 2μλ/ε in the tangent plane, 0 along n.
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3);
  h.set_zero();
  EXPECT_NEAR(friction.evaluate(x0, &g, &h), mu * lambda * eps / 3, 1e-12);
  EXPECT_EQ(g.norm(), 0.0);
  const Eigen::Matrix3d expected =
      2 * mu * lambda / eps * (Eigen::Matrix3d::Identity() - Vec3::UnitY() * Vec3::UnitY().transpose());
  EXPECT_LT((Eigen::Matrix3d(h.to_full()) - expected).norm(), 1e-9 * expected.norm());
  // Sliding (slip > ε): the force is μλ, against the tangential slip, whatever the normal
  // motion; at half of ε, 75 % of it (f1(ε/2) = 1 − 1/4).
  for (double s : {2 * eps, 10 * eps, 0.5 * eps}) {
    Eigen::VectorXd x = x0 + Eigen::Vector3d(s, 0.003, 0);
    g.setZero();
    friction.evaluate(x, &g, nullptr);
    const double expected_force = s > eps ? mu * lambda : 0.75 * mu * lambda;
    EXPECT_NEAR(g[0], expected_force, 1e-12 * mu * lambda) << "slip " << s;
    EXPECT_NEAR(g[1], 0.0, 1e-15);
    EXPECT_NEAR(g[2], 0.0, 1e-15);
  }
  // μ = 0 disables it.
  collision.set_spheres({{Vec3::Zero(), 0.5, 0.0}});
  friction.begin_step(x0);
  EXPECT_EQ(friction.num_contacts(), 0);
}

TEST(Friction, ACubeMovingWithTheVertexExertsNoForce) {
  // The contact point moves with its face: a vertex that moved exactly with the body has
  // not slipped (no force), one that stayed behind is dragged along the motion.
  BodyMesh box = testing::cube(Vec3(0, 0, 0), 0.5);
  const Eigen::MatrixX3d start = box.vertices();
  Eigen::MatrixX3d moved = start;
  moved.rowwise() += Eigen::RowVector3d(0.01, 0.0, -0.02);
  box.set_vertices(moved);
  EXPECT_TRUE(box.previous_vertices().isApprox(start));
  CollisionEnergy collision(1, kDelta, kStiffness);
  collision.set_bodies({&box});
  FrictionEnergy friction(1, collision, kVelocity, kStep);
  friction.set_body_friction({0.5});
  const Eigen::VectorXd x0 = Vec3(0.1, 0.53, 0.2);
  friction.begin_step(x0);
  ASSERT_EQ(friction.num_contacts(), 1);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(3);
  friction.evaluate(x0 + Vec3(0.01, 0.002, -0.02), &g, nullptr);
  EXPECT_LT(g.norm(), 1e-9 * 0.5 * collision.normal_force(0.03));
  g.setZero();
  friction.evaluate(x0, &g, nullptr);
  EXPECT_LT(g.dot(Vec3(0.01, 0, -0.02)), 0.0);  // the force −g points along the motion
}

TEST(Friction, TheNormalForceIsLaggedAgainstTheBodyAtTheStepStart) {
  // The body moves toward the vertex during the step (the simulator moves it before the
  // step): at the step's start the vertex rested 3 cm above the face (its distance then),
  // now the moved face is 1 cm from it. The friction bound μλ is the normal force of the
  // start, not the moved body's much larger one, and a vertex that was outside the band
  // at the start gets no friction.
  BodyMesh box = testing::cube(Vec3(0, 0, 0), 0.5);
  Eigen::MatrixX3d moved = box.vertices();
  moved.rowwise() += Eigen::RowVector3d(0.0, 0.02, 0.0);
  box.set_vertices(moved);
  CollisionEnergy collision(2, kDelta, kStiffness);
  collision.set_bodies({&box});
  FrictionEnergy friction(2, collision, kVelocity, kStep);
  const double mu = 0.5;
  friction.set_body_friction({mu});
  Eigen::VectorXd x0(6);
  x0 << 0.1, 0.53, 0.2,    // 3 cm above the top face at the start, 1 cm now
      -0.1, 0.565, 0.0;    // 6.5 cm at the start (outside the 5 cm band), 4.5 cm now
  friction.begin_step(x0);
  ASSERT_EQ(friction.num_contacts(), 1);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(6);
  Eigen::VectorXd x = x0;
  x[0] += 10 * friction.smoothing();  // sliding, relative to the face that moved along y only
  friction.evaluate(x, &g, nullptr);
  EXPECT_NEAR(g.head<3>().norm(), mu * collision.normal_force(0.03), 1e-9 * mu * collision.normal_force(0.03));
  EXPECT_GT(collision.normal_force(0.01), 1.5 * collision.normal_force(0.03));
  EXPECT_EQ(g.tail<3>().norm(), 0.0);
}

// ---- Whole simulations ----

SimulationSettings sim_settings(double h) { return testing::simulation_settings(h); }

// A 10 cm cloth patch (6 × 6) resting on the top face of a large box tilted by θ about z,
// each vertex at the depth in the collision band where the penalty carries its weight's
// normal component (so the lagged normal force exists from step 1 and nothing bounces).
struct Incline {
  ClothMesh cloth;
  BodyMesh plane;
  Vec3 normal, downhill;
  Positions x0;
};

Incline make_incline(double theta, const SimulationSettings& s) {
  Incline in;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(theta, Vec3::UnitZ()).toRotationMatrix();
  const double half = 1.5;
  // The box's top face is the plane through the origin with normal R·y.
  const BodyMesh box = testing::cube(Vec3(0, -half, 0), half);
  Eigen::MatrixX3d v = box.vertices();
  for (int k = 0; k < v.rows(); ++k) v.row(k) = (R * v.row(k).transpose()).transpose();
  in.plane = BodyMesh(v, box.faces());
  in.normal = R * Vec3::UnitY();
  const Vec3 g = s.gravity;
  in.downhill = (g - g.dot(in.normal) * in.normal).normalized();
  // In the box's frame the patch spans x ∈ [0.6, 0.7], z ∈ [−0.55, −0.45]: clear of the top
  // face's diagonal (x = z), so it slides over one flat triangle.
  const ClothMesh flat = make_grid_cloth(Vec3(0.6, 0, -0.55), 0.1, 0.1, 6, 6, "xz", s.material.density);
  Positions rest = flat.rest;
  for (int i = 0; i < flat.num_vertices(); ++i) rest.segment<3>(3 * i) = R * flat.rest.segment<3>(3 * i);
  in.cloth = make_cloth_mesh(rest, flat.triangles, s.material.density);
  in.x0 = rest;
  const double cos_theta = std::cos(theta);
  for (int i = 0; i < in.cloth.num_vertices(); ++i) {
    const double weight_n = in.cloth.mass[i] * g.norm() * cos_theta;
    const double d = s.collision_thickness -
                     std::sqrt(2 * s.collision_thickness * weight_n / s.collision_stiffness);
    in.x0.segment<3>(3 * i) += d * in.normal;
  }
  return in;
}

// Centroid's position along the slope (m) at each frame of a run of `frames` steps.
std::vector<double> slide(double theta, double mu, int frames, double h, Positions* last = nullptr,
                          double* worst_oob = nullptr) {
  const SimulationSettings s = sim_settings(h);
  Incline in = make_incline(theta, s);
  ClothSimulator sim(in.cloth, s);
  sim.add_body(in.plane, mu);
  const int n = in.cloth.num_vertices();
  auto along = [&](const Positions& x) {
    Vec3 c = Vec3::Zero();
    for (int i = 0; i < n; ++i) c += x.segment<3>(3 * i) / n;
    return c.dot(in.downhill);
  };
  std::vector<double> s_along{along(in.x0)};
  Positions x2 = in.x0, x1 = in.x0;
  for (int f = 0; f < frames; ++f) {
    const StepResult r = sim.step(x2, x1);
    EXPECT_EQ(r.status, StepStatus::converged) << "μ " << mu << " frame " << f;
    if (worst_oob && f > 0) {
      const FrameMetrics m = frame_metrics(sim, x2, x1, r.x, h);
      *worst_oob = std::max(*worst_oob, m.oob_force_max_rel);
    }
    x2 = x1;
    x1 = r.x;
    s_along.push_back(along(r.x));
  }
  if (last) *last = x1;
  return s_along;
}

constexpr double kTheta = 20.0 * M_PI / 180.0;

TEST(Friction, PatchSticksOnAnInclineSteeperThanItsFrictionAngleAllows) {
  // μ = 0.5 > tan 20° ≈ 0.364: static friction holds the patch; it only creeps at under
  // ε_v (friction_velocity; here ~0.48 ε_v: f1(y) = tan θ/μ at y ≈ 0.48 ε).
  const double h = 0.01;
  const int settle = 20, hold = 100;  // 0.2 s, then 1 s
  double worst_oob = 0;
  const std::vector<double> s = slide(kTheta, 0.5, settle + hold, h, nullptr, &worst_oob);
  const double drift = s.back() - s[settle];
  const double eps_v = sim_settings(h).friction_velocity;  // m/s
  std::printf("incline, mu 0.5: drift %.3f mm over %.1f s after settling (%.3f mm while settling; "
              "eps_v %.3g m/s), out-of-balance max %.2e of weight\n",
              1e3 * drift, hold * h, 1e3 * (s[settle] - s[0]), eps_v, worst_oob);
  EXPECT_LT(std::abs(drift), eps_v * hold * h);  // slower than ε_v
  EXPECT_GE(drift, 0.0);  // if it moves at all, downhill
  // The out-of-balance metric counts friction: a patch held by it is in balance.
  EXPECT_LT(worst_oob, 1e-3);
}

TEST(Friction, PatchSlidesDownAnInclineAtTheCoulombAcceleration) {
  // μ = 0.1 < tan 20°: the patch slides at a = g(sin θ − μ cos θ) ≈ 2.43 m/s².
  const double h = 0.01, mu = 0.1;
  const int frames = 50;
  const std::vector<double> s = slide(kTheta, mu, frames, h);
  // Least-squares fit s(t) = s0 + v0 t + ½ a t² over frames 5..50 (past the onset).
  const int first = 5, m = frames + 1 - first;
  Eigen::MatrixXd A(m, 3);
  Eigen::VectorXd b(m);
  for (int k = 0; k < m; ++k) {
    const double t = (first + k) * h;
    A.row(k) << 1, t, 0.5 * t * t;
    b[k] = s[first + k];
  }
  const Eigen::Vector3d fit = A.colPivHouseholderQr().solve(b);
  const double g = 9.81, expected = g * (std::sin(kTheta) - mu * std::cos(kTheta));
  std::printf("incline, mu 0.1: acceleration %.4f m/s^2, g(sin - mu cos) = %.4f (%.2f %%), "
              "travel %.3f m in %.2f s\n",
              fit[2], expected, 100 * (fit[2] / expected - 1), s.back() - s[0], frames * h);
  EXPECT_NEAR(fit[2], expected, 0.1 * expected);
  // Without friction it would be g sin θ ≈ 3.36 m/s²: friction is really acting.
  EXPECT_LT(fit[2], 0.9 * g * std::sin(kTheta));
}

TEST(Friction, AMovingBodyDragsTheClothAlong) {
  // The patch lies on a level box that moves at 0.2 m/s along x from rest (a step in
  // velocity): with μ = 0.5 the box drags it to its own speed (static friction can
  // accelerate it at up to μg ≈ 4.9 m/s², so within a few frames); with μ = 0 it stays.
  const double h = 0.01, speed = 0.2;
  for (double mu : {0.5, 0.0}) {
    const SimulationSettings s = sim_settings(h);
    Incline in = make_incline(0.0, s);
    ClothSimulator sim(in.cloth, s);
    sim.add_body(in.plane, mu);
    const int n = in.cloth.num_vertices();
    Positions x2 = in.x0, x1 = in.x0;
    Eigen::MatrixX3d body = in.plane.vertices();
    const int frames = 30;
    for (int f = 0; f < frames; ++f) {
      Eigen::MatrixX3d next = body;
      next.col(0).array() += speed * h;
      const StepResult r = sim.step(x2, x1, &body, &next);
      ASSERT_EQ(r.status, StepStatus::converged) << "μ " << mu << " frame " << f;
      body = next;
      x2 = x1;
      x1 = r.x;
    }
    double v = 0;
    for (int i = 0; i < n; ++i) v += (x1[3 * i] - x2[3 * i]) / h / n;
    std::printf("moving body, mu %.1f: cloth speed %.4f m/s after %.2f s (body %.1f m/s)\n", mu, v,
                frames * h, speed);
    if (mu > 0)
      EXPECT_NEAR(v, speed, 2 * s.friction_velocity);
    else
      EXPECT_NEAR(v, 0.0, 1e-5);
  }
}

TEST(Friction, AcceptedStepsNeverIncreaseTheEnergyWithFriction) {
  // A cloth dropped onto a sphere with μ = 0.5: in every step of the contact no accepted
  // Newton iterate raises the incremental potential, friction included, and every step
  // converges.
  ClothMesh mesh = make_grid_cloth(Vec3(-0.4, 0.62, -0.4), 0.8, 0.8, 10, 10, "xz", 0.2);
  SimulationSettings s = sim_settings(1.0 / 60);
  s.collision_thickness = 0.01;
  ClothSimulator sim(mesh, s);
  sim.set_spheres({{Vec3(0, 0.3, 0), 0.3, 0.5}});
  Positions x2 = mesh.rest, x1 = mesh.rest;
  int contact_steps = 0;
  for (int f = 0; f < 30; ++f) {
    const StepResult r = sim.step(x2, x1);
    ASSERT_EQ(r.status, StepStatus::converged) << "frame " << f;
    const auto& e = r.last.accepted_energies;
    for (size_t k = 1; k < e.size(); ++k) EXPECT_LE(e[k], e[k - 1]) << "frame " << f;
    FrameMetrics m;
    measure_penetration(sim, r.x, m);
    contact_steps += m.min_signed_distance < s.collision_thickness;
    x2 = x1;
    x1 = r.x;
  }
  EXPECT_GT(contact_steps, 20);
}


// The slip-reversal clamp (FrictionEnergy::limit_vertex_steps): a sliding contact whose
// move would carry its slip through zero stops where the move passes closest to zero
// slip; a move that keeps the slip's direction, a contact in the smooth regime and a
// vertex with no contact are left alone, and the clamp never caps the whole step.
TEST(Friction, ASlipReversalStopsAtTheMovesPointClosestToZeroSlip) {
  const int n = 4;
  const Vec3 p = on_sphere(Vec3(0, 1, 0), 0.01);  // in the band, on top: tangents x and z
  Eigen::VectorXd x_start(3 * n), x(3 * n), dx = Eigen::VectorXd::Zero(3 * n);
  for (int i = 0; i < 3; ++i) x_start.segment<3>(3 * i) = p;
  x_start.segment<3>(9) = on_sphere(Vec3(0, 0, 1), 0.2);  // outside the band
  x = x_start;
  x.segment<3>(0) += Vec3(0.004, 0, 0);    // sliding: 4 mm of slip (ε = 1 mm)
  dx.segment<3>(0) = Vec3(-0.010, 0, 0);   // back through zero to −6 mm: stop at t = 0.4
  x.segment<3>(3) += Vec3(0.004, 0, 0);
  dx.segment<3>(3) = Vec3(0.003, 0, 0);    // further the same way: no limit
  x.segment<3>(6) += Vec3(0.0005, 0, 0);   // static regime (0.5 mm < ε)
  dx.segment<3>(6) = Vec3(-0.002, 0, 0);
  x.segment<3>(9) += Vec3(0.004, 0, 0);
  dx.segment<3>(9) = Vec3(-0.010, 0, 0);

  CollisionEnergy collision(n, kDelta, kStiffness);
  collision.set_spheres({{Vec3::Zero(), 0.5, 0.4}});
  FrictionEnergy friction(n, collision, kVelocity, kStep);
  friction.set_body_friction({});
  friction.begin_step(x_start);
  ASSERT_EQ(friction.num_contacts(), 3);
  Eigen::VectorXd limits = Eigen::VectorXd::Ones(n);
  friction.limit_vertex_steps(x, dx, limits);
  EXPECT_NEAR(limits[0], 0.4, 1e-12);
  EXPECT_EQ(limits[1], 1.0);
  EXPECT_EQ(limits[2], 1.0);
  EXPECT_EQ(limits[3], 1.0);
  // At the limit the slip is (to round-off) zero: the vertex is back in the static regime.
  const Vec3 stopped = x.segment<3>(0) + limits[0] * dx.segment<3>(0);
  EXPECT_LT((stopped - x_start.segment<3>(0)).norm(), 1e-12);
  EXPECT_EQ(friction.max_step(x, dx), 1.0);
}

}  // namespace
}  // namespace weft::physics
