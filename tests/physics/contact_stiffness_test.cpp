// The collision's secant stiffness along the contact normal (CollisionEnergy::
// set_secant_stiffness, issue 41): a vertex stopped deep in the penalty band (where the step
// filter leaves an approaching vertex, half the band from the obstacle) reaches the balance
// of its penalty against its weight in a step or two instead of halving its gap per Newton
// iteration, and it reaches the same balance: only Newton's direction changes.
#include <gtest/gtest.h>

#include <cmath>

#include "physics/collision_energy.h"
#include "physics/newton_solver.h"
#include "physics/vertex_energies.h"

namespace weft::physics {
namespace {

constexpr double kContactBand = 0.005;        // δ, m
constexpr double kContactStiffness = 1e4;     // k, N/m
constexpr double kVertexMass = 4.9e-5;       // kg: a vertex of the 1 m², 64×64 drape at 0.2 kg/m²
constexpr double kGravityAcc = 9.81;      // m/s²
constexpr double kSphereRadius = 0.3;        // m
constexpr double kTimeStep = 1.0 / 60.0;   // s

struct ContactRest {
  NewtonReport report;
  double height = 0;  // m, the vertex's distance to the sphere's surface
};

// One vertex at rest (inertia predicts no motion) on top of a sphere, pressed by its weight,
// starting `distance` from the surface; Newton to 1e-6 of its weight.
ContactRest settle(double distance, bool secant) {
  const Eigen::VectorXd mass = Eigen::VectorXd::Constant(1, kVertexMass);
  Eigen::VectorXd x(3);
  x << 0, kSphereRadius + distance, 0;
  InertiaEnergy inertia(mass, kTimeStep);
  inertia.set_prediction(x);
  GravityEnergy gravity(mass, Eigen::Vector3d(0, -kGravityAcc, 0));
  CollisionEnergy collision(1, kContactBand, kContactStiffness);
  collision.set_spheres({{Eigen::Vector3d::Zero(), kSphereRadius, 0.0}});
  collision.set_secant_stiffness(secant);
  NewtonOptions options;
  options.tolerance = 1e-6;
  options.factor_without_weak_pairs = false;
  NewtonSolver solver(1, {&inertia, &gravity, &collision}, options);
  solver.set_force_scale(Eigen::VectorXd::Constant(1, kVertexMass * kGravityAcc));
  ContactRest r;
  r.report = solver.minimize(x);
  r.height = x.norm() - kSphereRadius;
  return r;
}

TEST(ContactStiffness, AVertexDeepInTheBandReachesItsBalanceInOneOrTwoSteps) {
  const ContactRest tangent = settle(0.5 * kContactBand, false);
  const ContactRest secant = settle(0.5 * kContactBand, true);
  ASSERT_EQ(tangent.report.status, StepStatus::converged);
  ASSERT_EQ(secant.report.status, StepStatus::converged);
  // The penalty's force c·gap² (c = k/(2δ)) against the weight plus the inertia term's
  // pull back to the start: both land on the same balance, 1e-9 m apart at most.
  EXPECT_NEAR(secant.height, tangent.height, 1e-9);
  const double c = 0.5 * kContactStiffness / kContactBand;
  const double gap = kContactBand - secant.height;
  const double inertia = kVertexMass / (kTimeStep * kTimeStep) * (0.5 * kContactBand - secant.height);  // N, up: the start was lower
  EXPECT_NEAR(c * gap * gap, kVertexMass * kGravityAcc - inertia, 1e-6 * kVertexMass * kGravityAcc);
  // From a gap of δ/2 (force 1.3e4 weights) the tangent stiffness halves the gap per
  // iteration; the secant one reaches the balance at once and then converges as Newton.
  EXPECT_GE(tangent.report.iterations, 7);
  EXPECT_LE(secant.report.iterations, 3);
}

TEST(ContactStiffness, AVertexBarelyInTheBandIsNotThrownDeep) {
  // 1 µm inside the band the tangent stiffness is tiny, and its Newton step overshoots
  // deep into the band; the secant stiffness aims at the balance.
  const ContactRest tangent = settle(kContactBand - 1e-6, false);
  const ContactRest secant = settle(kContactBand - 1e-6, true);
  ASSERT_EQ(secant.report.status, StepStatus::converged);
  ASSERT_EQ(tangent.report.status, StepStatus::converged);
  EXPECT_NEAR(secant.height, tangent.height, 1e-9);
  EXPECT_LE(secant.report.iterations, 3);
  EXPECT_GT(tangent.report.iterations, secant.report.iterations);
}

TEST(ContactStiffness, AVertexOutsideTheBandIsUntouched) {
  // No collision force, no change: free fall is one Newton step either way.
  const ContactRest secant = settle(0.02, true);
  ASSERT_EQ(secant.report.status, StepStatus::converged);
  EXPECT_EQ(secant.report.iterations, 1);
}

}  // namespace
}  // namespace weft::physics
