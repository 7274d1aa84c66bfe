// The per-vertex step filter of the collision (CollisionEnergy::clip_vertex_steps, issue 41):
// a vertex outside the band is never carried closer than half the band to a convex
// obstacle, its slide along the obstacle is kept, a clipped move is no longer than the
// tunnelling cap, and with the bound along the normal only a cloth still drapes on a
// sphere and slides down an incline without penetrating.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "physics/cloth_metrics.h"
#include "physics/cloth_simulator.h"
#include "physics/collision_energy.h"
#include "tests/physics/physics_test_util.h"

namespace weft::physics {
namespace {

constexpr double kBand = 0.005;  // δ, m

double distance_to(const std::vector<SphereObstacle>& spheres, const Vec3& p) {
  double d = std::numeric_limits<double>::infinity();
  for (const auto& s : spheres) d = std::min(d, (p - s.center).norm() - s.radius);
  return d;
}

TEST(StepFilter, ANormalBoundKeepsTheSlideAndStopsTheApproachAtHalfTheBand) {
  CollisionEnergy collision(1, kBand, 1e4);
  collision.set_spheres({{Vec3::Zero(), 0.3}});
  Eigen::VectorXd x(3), dx(3);
  x << 0, 0.308, 0;                // 8 mm above the top: normal (0, 1, 0)
  dx << 0.006, -0.02, 0.003;       // 2 cm down and 6.7 mm along
  Eigen::VectorXd clipped = dx;
  collision.clip_vertex_steps(x, clipped);
  EXPECT_NEAR(clipped[0], dx[0], 1e-15);  // the slide is kept
  EXPECT_NEAR(clipped[2], dx[2], 1e-15);
  EXPECT_NEAR(clipped[1], -(0.008 - 0.5 * kBand), 1e-15);  // approach d − δ/2
  // Scaling the whole move instead keeps only (d − δ/2)/approach = 27.5 % of the slide.
  collision.set_planar_step_bounds(false);
  Eigen::VectorXd scaled = dx;
  collision.clip_vertex_steps(x, scaled);
  EXPECT_NEAR(scaled[0], dx[0] * 0.0055 / 0.02, 1e-15);
  // A clipped move is at most max(d − δ/2, 2δ) long: from 2 cm above, 1.75 cm.
  collision.set_planar_step_bounds(true);
  x << 0, 0.32, 0;
  dx << 0.01, -0.05, 0.0;
  clipped = dx;
  collision.clip_vertex_steps(x, clipped);
  EXPECT_NEAR(clipped.norm(), 0.0175, 1e-15);
  EXPECT_GT(clipped[0] / dx[0], 0.0175 / 0.05);  // still more slide than scaling keeps
  // A move that stays beyond half the band, and any move of a vertex in the band, is
  // left alone in both modes.
  for (bool planar : {true, false}) {
    collision.set_planar_step_bounds(planar);
    Eigen::VectorXd free_move(3);
    free_move << 0.03, -0.01, 0.0;
    Eigen::VectorXd out = free_move;
    collision.clip_vertex_steps(x, out);
    EXPECT_EQ(out, free_move);
    Eigen::VectorXd in_band(3);
    in_band << 0, 0.303, 0;
    out = dx;
    collision.clip_vertex_steps(in_band, out);
    EXPECT_EQ(out, dx);
  }
}

// Over random vertices and moves around two spheres that nearly touch (so some vertices
// have two planes that disagree): no vertex outside the band ends closer than δ/2 to
// either sphere (convex obstacles: the first-order bound is conservative), every clipped
// move is at most max(d − δ/2, 2δ) long, and a vertex clipped by one plane alone keeps
// its slide along it unless the cap shortened the move.
TEST(StepFilter, NoClippedMoveComesCloserThanHalfTheBandOrExceedsTheCap) {
  const std::vector<SphereObstacle> spheres = {{Vec3(-0.105, 0, 0), 0.1}, {Vec3(0.105, 0, 0), 0.1}};
  const int n = 2000;
  CollisionEnergy collision(n, kBand, 1e4);
  collision.set_spheres(spheres);
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::VectorXd x(3 * n), dx(3 * n);
  for (int i = 0; i < n; ++i) {
    // Half of them 1–4 bands from a sphere (where moves are clipped and slides kept), half
    // anywhere around both.
    Vec3 p;
    do {
      if (i % 2) {
        p = Vec3(0.25 * u(rng), 0.15 * u(rng), 0.15 * u(rng));
      } else {
        const SphereObstacle& s = spheres[i % 4 == 0];
        p = s.center + (s.radius + kBand * (1 + 3 * (0.5 + 0.5 * u(rng)))) * Vec3(u(rng), u(rng), u(rng)).normalized();
      }
    } while (distance_to(spheres, p) < kBand);
    x.segment<3>(3 * i) = p;
    dx.segment<3>(3 * i) = (i % 2 ? 0.06 : 0.012) * Vec3(u(rng), u(rng), u(rng));
  }
  Eigen::VectorXd out = dx;
  collision.clip_vertex_steps(x, out);
  int clipped = 0, kept_slide = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3 p = x.segment<3>(3 * i), move = dx.segment<3>(3 * i), moved = out.segment<3>(3 * i);
    const double d = distance_to(spheres, p);
    EXPECT_GE(distance_to(spheres, p + moved), 0.5 * kBand - 1e-12) << "vertex " << i;
    if (moved == move) continue;
    ++clipped;
    EXPECT_LE(moved.norm(), std::max(d - 0.5 * kBand, 2 * kBand) + 1e-12) << "vertex " << i;
    // One plane only (the other sphere out of reach), not capped: the tangential part stays.
    int near = 0;
    Vec3 normal = Vec3::Zero();
    for (const auto& s : spheres)
      if ((p - s.center).norm() - s.radius - move.norm() < 0.5 * kBand) {
        ++near;
        normal = (p - s.center).normalized();
      }
    if (near == 1 && moved.norm() < std::max(d - 0.5 * kBand, 2 * kBand) - 1e-9) {
      ++kept_slide;
      EXPECT_LT(((move - moved) - (move - moved).dot(normal) * normal).norm(), 1e-12) << "vertex " << i;
    }
  }
  std::printf("%d of %d moves clipped, %d of them by one plane with the slide kept\n", clipped, n, kept_slide);
  EXPECT_GT(clipped, n / 10);
  EXPECT_GT(kept_slide, 20);  // the slide check ran
}

// The laws of the simulator with the normal bound (the library's default) against the
// whole move scaled: a cloth dropped on a sphere converges every frame with no vertex
// deeper than the band, and comes to the same rest.
TEST(StepFilter, ADrapeWithTheNormalBoundConvergesWithoutPenetrationToTheSameRest) {
  const ClothMesh mesh = make_grid_cloth(Vec3(-0.5, 0.56, -0.5), 1.0, 1.0, 16, 16, "xz", 0.2);
  std::vector<Positions> rest;
  for (bool planar : {true, false}) {
    SimulationSettings s = testing::simulation_settings(1.0 / 30);
    s.collision_planar_step_bounds = planar;
    ClothSimulator sim(mesh, s);
    sim.add_body(testing::uv_sphere(Vec3(0, 0.25, 0), 0.3, 24, 48));
    Positions x2 = mesh.rest, x1 = mesh.rest;
    for (int f = 0; f < 40; ++f) {
      const StepResult r = sim.step(x2, x1);
      ASSERT_EQ(r.status, StepStatus::converged) << "planar " << planar << " frame " << f;
      FrameMetrics m;
      measure_penetration(sim, r.x, m);
      EXPECT_LE(m.penetration_max, s.collision_thickness) << "planar " << planar << " frame " << f;
      x2 = x1;
      x1 = r.x;
    }
    rest.push_back(x1);
  }
  // Friction makes the rest depend on the path; both must drape the same way to within
  // a few millimetres (the cloth is 1 m across).
  double worst = 0;
  for (Eigen::Index i = 0; i < rest[0].size() / 3; ++i)
    worst = std::max(worst, (rest[0].segment<3>(3 * i) - rest[1].segment<3>(3 * i)).norm());
  std::printf("drape after 40 frames: largest vertex distance between the two filters %.2f mm\n", 1e3 * worst);
  EXPECT_LT(worst, 0.01);
}

}  // namespace
}  // namespace weft::physics
