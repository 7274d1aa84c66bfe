// Cloth simulator speed: time per 1/30 s frame (two implicit Euler steps of 1/60 s; the key
// steps_per_frame=K takes K steps of 1/(30 K) s instead),
// Newton iterations and the share of the linear solve, collision queries and the
// remaining energy evaluation/assembly, for
//   drape: a 1 m square cloth dropped on a radius-0.3 m sphere (ARCSim's comparison scene)
//   skirt: a tube (skirt-like) whose top ring follows a body mesh moving sideways.
// Usage: bench_cloth_sim [drape|skirt] [direct|reused_factor] N FRAMES
//                        [automatic|simplicial|supernodal] [TOLERANCE] [project|exact]
//                        [amd|nested_dissection|metis] [KEY=VALUE ...]
// KEY=VALUE arguments (anywhere) set further Newton options: cg_max_iterations,
// cg_relative_tolerance, adaptive_cg_tolerance (0/1), start_from_prediction (0/1), start_filter_per_vertex (0/1),
// start_following_body (0/1), secant_stiffness (0/1: the collision's secant stiffness along the
// contact normal, off by default),
// precondition_exact_hessian (0/1), negative_curvature_search (0/1), per_vertex_step_limits
// (0/1), refine_limited_steps (0/1), planar_step_bounds (0/1: the per-vertex collision bound along the normal only, or
// scaling the whole move), smooth_creases (0/1: the body's concave creases, as weft synth's default),
// factor_without_weak_pairs (0/1), CHOLMOD's supernode
// amalgamation nrelax=A,B,C and zrelax=A,B,C, max_iterations (per
// step; 1 = one linear solve per step, as a linearised implicit Euler like ARCSim's);
// and, to find what the iteration count depends on, the scene's bending_stiffness (N·m),
// youngs_modulus (Pa), collision_stiffness (N/m), collision_thickness (m), the membrane
// model (membrane=stvk|tension_field) with its compression_ratio and min_area_ratio, the
// obstacle's friction coefficient (friction, default 0.3) and friction_velocity (m/s).
// (N×N vertices; TOLERANCE relative to the vertex weight; membrane Hessian projected or
// exact)
// Runs single-threaded; prints one line per frame and a median summary.
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <ctime>
#include <vector>

#include "bench/bench_clock.h"
#include "graph/threads.h"
#include "physics/cloth_simulator.h"

using namespace weft::physics;

namespace {

// The drape's obstacle (ARCSim's comparison scene), metres.
const Vec3 kDrapeSphereCentre(0, 0.4, 0);
constexpr double kDrapeSphereRadius = 0.3;

// A closed cylinder (capped) of radius r from y0 to y1 around the y axis.
BodyMesh cylinder_body(double r, double y0, double y1, int rings, int segments) {
  std::vector<Eigen::Vector3d> v;
  std::vector<std::array<int, 3>> f;
  for (int i = 0; i <= rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double a = 2 * M_PI * j / segments;
      v.emplace_back(r * std::cos(a), y0 + (y1 - y0) * i / rings, r * std::sin(a));
    }
  const int bottom = static_cast<int>(v.size());
  v.emplace_back(0, y0, 0);
  const int top = static_cast<int>(v.size());
  v.emplace_back(0, y1, 0);
  auto id = [&](int i, int j) { return i * segments + (j % segments); };
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      f.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      f.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
    }
  for (int j = 0; j < segments; ++j) {
    f.push_back({bottom, id(0, j), id(0, j + 1)});
    f.push_back({top, id(rings, j + 1), id(rings, j)});
  }
  Eigen::MatrixX3d m(v.size(), 3);
  for (size_t k = 0; k < v.size(); ++k) m.row(k) = v[k].transpose();
  return BodyMesh(m, f);
}

// A tube of n×n vertices (n around, n down), radius r, hanging from y_top, length len.
ClothMesh tube(int n, double r, double y_top, double len, double density) {
  Positions x(3 * n * n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const double a = 2 * M_PI * j / n;
      x.segment<3>(3 * (i * n + j)) = Vec3(r * std::cos(a), y_top - len * i / (n - 1), r * std::sin(a));
    }
  std::vector<std::array<int, 3>> t;
  for (int i = 0; i + 1 < n; ++i)
    for (int j = 0; j < n; ++j) {
      const int a = i * n + j, b = i * n + (j + 1) % n, c = (i + 1) * n + j, d = (i + 1) * n + (j + 1) % n;
      t.push_back({a, c, d});
      t.push_back({a, d, b});
    }
  return make_cloth_mesh(x, t, density);
}

using weft::bench::cpu_ms;
using weft::bench::ms_since;

}  // namespace

int main(int argc_all, char** argv_all) {
  std::vector<char*> positional;
  std::vector<std::pair<std::string, std::string>> named;
  for (int k = 0; k < argc_all; ++k) {
    const char* eq = k > 0 ? std::strchr(argv_all[k], '=') : nullptr;
    if (eq)
      named.emplace_back(std::string(argv_all[k], static_cast<size_t>(eq - argv_all[k])),
                         std::string(eq + 1));
    else
      positional.push_back(argv_all[k]);
  }
  const int argc = static_cast<int>(positional.size());
  char** argv = positional.data();
  const std::string scene = argc > 1 ? argv[1] : "drape";
  const std::string solver = argc > 2 ? argv[2] : "direct";
  const int n = argc > 3 ? std::atoi(argv[3]) : 32;
  const int frames = argc > 4 ? std::atoi(argv[4]) : 30;
  const std::string cholesky = argc > 5 ? argv[5] : "automatic";
  const double tolerance = argc > 6 ? std::atof(argv[6]) : SimulationSettings{}.newton.tolerance;
  const std::string membrane = argc > 7 ? argv[7] : "default";
  const std::string ordering = argc > 8 ? argv[8] : "default";
  weft::set_num_threads(1);
  SimulationSettings s;
  s.time_step = 1.0 / 60;
  s.collision_thickness = 0.005;
  s.collision_stiffness = 1e4;
  s.newton.tolerance = tolerance;
  s.newton.cholesky = cholesky == "simplicial"   ? CholeskyKind::simplicial
                      : cholesky == "supernodal" ? CholeskyKind::supernodal
                                                 : CholeskyKind::automatic;
  if (ordering != "default")
    s.newton.ordering = ordering == "metis"                ? CholeskyOrdering::metis
                        : ordering == "nested_dissection" ? CholeskyOrdering::nested_dissection
                                                           : CholeskyOrdering::amd;
  if (membrane != "default") s.project_membrane_hessian = membrane == "project";
  s.newton.max_iterations = 50;
  double friction = 0.3;  // against the sphere or the body
  int steps_per_frame = 2;  // implicit Euler steps per 1/30 s frame
  for (const auto& [key, value] : named) {
    if (key == "cg_max_iterations") s.newton.cg_max_iterations = std::atoi(value.c_str());
    else if (key == "cg_relative_tolerance") s.newton.cg_relative_tolerance = std::atof(value.c_str());
    else if (key == "adaptive_cg_tolerance") s.newton.adaptive_cg_tolerance = value != "0";
    else if (key == "precondition_exact_hessian")
      s.newton.precondition_exact_hessian = value != "0";
    else if (key == "negative_curvature_search")
      s.newton.negative_curvature_search = value != "0";
    else if (key == "max_iterations") s.newton.max_iterations = std::atoi(value.c_str());
    else if (key == "per_vertex_step_limits") s.newton.per_vertex_step_limits = value != "0";
    else if (key == "refine_limited_steps") s.newton.refine_limited_steps = value != "0";
    else if (key == "smooth_creases") s.collision_smooth_creases = value != "0";
    else if (key == "planar_step_bounds") s.collision_planar_step_bounds = value != "0";
    else if (key == "secant_stiffness") s.collision_secant_stiffness = value != "0";
    else if (key == "factor_without_weak_pairs") s.newton.factor_without_weak_pairs = value != "0";
    else if (key == "nrelax" || key == "zrelax") {  // three comma-separated numbers
      double* out = key == "nrelax" ? s.newton.amalgamation.nrelax : s.newton.amalgamation.zrelax;
      std::sscanf(value.c_str(), "%lf,%lf,%lf", &out[0], &out[1], &out[2]);
    }
    else if (key == "bending_stiffness") s.material.bending_stiffness = std::atof(value.c_str());
    else if (key == "youngs_modulus") s.material.youngs_modulus = std::atof(value.c_str());
    else if (key == "collision_stiffness") s.collision_stiffness = std::atof(value.c_str());
    else if (key == "collision_thickness") s.collision_thickness = std::atof(value.c_str());
    else if (key == "start_from_prediction") s.start_from_prediction = value != "0";
    else if (key == "start_filter_per_vertex") s.start_filter_per_vertex = value != "0";
    else if (key == "start_following_body") s.start_following_body = value != "0";
    else if (key == "membrane" && (value == "stvk" || value == "tension_field"))
      s.material.membrane = value == "stvk" ? MembraneModel::stvk : MembraneModel::tension_field;
    else if (key == "compression_ratio") s.material.compression_ratio = std::atof(value.c_str());
    else if (key == "min_area_ratio") s.material.min_area_ratio = std::atof(value.c_str());
    else if (key == "steps_per_frame") steps_per_frame = std::max(1, std::atoi(value.c_str()));
    else if (key == "friction") friction = std::atof(value.c_str());
    else if (key == "friction_velocity") s.friction_velocity = std::atof(value.c_str());
    else {
      std::fprintf(stderr, "bench_cloth_sim: unknown option '%s'\n", key.c_str());
      return 2;
    }
  }
  s.time_step = 1.0 / (30 * steps_per_frame);
  s.newton.linear_solver =
      solver == "direct" ? LinearSolverKind::direct : LinearSolverKind::reused_factor;
  const bool skirt = scene == "skirt";
  ClothMesh mesh = skirt ? tube(n, 0.17, 1.0, 0.6, 0.2)
                         : make_grid_cloth(Vec3(-0.5, 0.75, -0.5), 1.0, 1.0, n, n, "xz", 0.2);
  ClothSimulator sim(mesh, s);
  std::vector<int> ring;
  Eigen::MatrixX3d body_rest;
  if (skirt) {
    sim.add_body(cylinder_body(0.15, 0.0, 1.05, 40, 64), friction);
    body_rest = sim.body(0).vertices();
    for (int j = 0; j < n; ++j) ring.push_back(j);
    sim.set_pins(ring);
  } else {
    SphereObstacle sphere{kDrapeSphereCentre, kDrapeSphereRadius};
    sphere.friction = friction;
    sim.set_spheres({sphere});
  }
  std::printf("scene %s solver %s vertices %d triangles %zu frames %d\n", scene.c_str(),
              solver.c_str(), mesh.num_vertices(), mesh.triangles.size(), frames);
  std::printf("cholesky %s: nnz(L) %.3g, %.3g flop per factorisation\n",
              sim.solver().cholmod().supernodal() ? "supernodal" : "simplicial",
              sim.solver().cholmod().factor_nonzeros(), sim.solver().cholmod().factor_flops());
  Positions x = mesh.rest, v = Positions::Zero(x.size());
  std::vector<double> frame_ms, frame_cpu_ms, iters, residuals;
  // Along the converged run, the Newton solves' wall time per frame until each step first
  // met 1e-1, 1e-2 and 1e-3 of the weight (a looser tolerance would have stopped there;
  // its later steps would then start elsewhere, so this prices accuracy, not that run).
  const std::vector<double> kLooser = {1e-1, 1e-2, 1e-3};
  std::vector<std::vector<double>> frame_to_tolerance_ms(kLooser.size()), frame_to_tolerance_cpu_ms(kLooser.size());
  double lin = 0, coll = 0, energy = 0, total = 0;
  int failed = 0;
  long factorizations = 0, cg_iterations = 0;
  for (int f = 0; f < frames; ++f) {
    const auto t0 = std::chrono::steady_clock::now();
    const double c0 = cpu_ms();
    int it = 0;
    double residual = 0;  // the steps' worst max_i ‖∇_i E‖ / (m_i g): out of balance
    std::vector<double> to_tolerance_ms(kLooser.size(), 0.0);
    for (int sub = 0; sub < steps_per_frame; ++sub) {
      if (skirt) {
        const double t = (steps_per_frame * f + sub + 1) * s.time_step;
        const Vec3 offset(0.15 * std::sin(2 * M_PI * 0.8 * t), 0, 0);
        Eigen::MatrixX3d moved = body_rest;
        moved.rowwise() += offset.transpose();
        sim.body(0).set_vertices(moved);
        std::vector<Vec3> targets;
        for (int j : ring) targets.push_back(mesh.rest_vertex(j) + offset);
        sim.set_pins(ring, targets);
      }
      const NewtonReport r = sim.advance(x, v, s.time_step);
      for (size_t k = 0; k < kLooser.size(); ++k) {  // when the step first met each tolerance
        size_t j = 0;
        while (j < r.residual_history.size() && r.residual_history[j] > kLooser[k]) ++j;
        to_tolerance_ms[k] += j < r.residual_ms.size() ? r.residual_ms[j] : r.total_ms;
      }
      it += r.iterations;
      residual = std::max(residual, r.residual);
      factorizations += r.factorizations;
      cg_iterations += r.cg_iterations;
      failed += r.status != StepStatus::converged;
      lin += r.linear_solve_ms;
      for (size_t k = 0; k < r.energy_ms.size(); ++k)
        (sim.solver().energies()[k]->name() == "collision" ? coll : energy) += r.energy_ms[k];
      total += r.total_ms;
    }
    frame_ms.push_back(ms_since(t0));
    frame_cpu_ms.push_back(cpu_ms() - c0);
    // The same in CPU time: the wall times scaled by the frame's CPU/wall ratio (on a shared
    // machine the wall time includes waiting for a core; the bench is single-threaded).
    const double cpu_per_wall = frame_ms.back() > 0 ? frame_cpu_ms.back() / frame_ms.back() : 1.0;
    for (size_t k = 0; k < kLooser.size(); ++k) {
      frame_to_tolerance_ms[k].push_back(to_tolerance_ms[k]);
      frame_to_tolerance_cpu_ms[k].push_back(cpu_per_wall * to_tolerance_ms[k]);
    }
    iters.push_back(it);
    residuals.push_back(residual);
    double depth_mm = 0;  // drape: the deepest vertex inside the sphere
    if (!skirt)
      for (Eigen::Index i = 0; i < x.size() / 3; ++i)
        depth_mm = std::max(depth_mm, 1e3 * (kDrapeSphereRadius - (x.segment<3>(3 * i) - kDrapeSphereCentre).norm()));
    std::printf("frame %d: %.1f ms (cpu %.1f ms), %d Newton iterations, residual %.2g of weight%s\n", f + 1,
                frame_ms.back(), frame_cpu_ms.back(), it, residual,
                skirt ? "" : (", penetration " + std::to_string(depth_mm) + " mm").c_str());
    std::fflush(stdout);
  }
  auto median = [](std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
  };
  double mean_it = 0;
  for (double i : iters) mean_it += i / iters.size();
  if (!skirt) {
    // Is the cloth still draped on the sphere? The highest vertex should sit on its top
    // (centre height + radius + about the collision band), and many vertices in contact.
    double top = -1e9;
    int touching = 0;
    for (Eigen::Index i = 0; i < x.size() / 3; ++i) {
      top = std::max(top, x[3 * i + 1]);
      touching += (x.segment<3>(3 * i) - kDrapeSphereCentre).norm() - kDrapeSphereRadius < 2 * s.collision_thickness;
    }
    std::printf("drape after %.2f s: highest vertex at y = %.4f m (sphere top %.4f m), %d vertices within 2 bands of the sphere\n",
                steps_per_frame * frames * s.time_step, top, kDrapeSphereCentre.y() + kDrapeSphereRadius, touching);
  }
  for (size_t k = 0; k < kLooser.size(); ++k)
    std::printf("to %.0e of weight: median %.1f ms, worst %.1f ms per frame (Newton solves' wall time)\n", kLooser[k],
                median(frame_to_tolerance_ms[k]),
                *std::max_element(frame_to_tolerance_ms[k].begin(), frame_to_tolerance_ms[k].end()));
  for (size_t k = 0; k < kLooser.size(); ++k)
    std::printf("to %.0e of weight: median %.1f ms, worst %.1f ms CPU per frame (the same, times each frame's CPU/wall)\n",
                kLooser[k], median(frame_to_tolerance_cpu_ms[k]),
                *std::max_element(frame_to_tolerance_cpu_ms[k].begin(), frame_to_tolerance_cpu_ms[k].end()));
  std::printf(
      "SUMMARY scene=%s solver=%s vertices=%d median_frame_ms=%.1f median_frame_cpu_ms=%.1f "
      "median_newton_per_frame=%.0f mean_newton_per_frame=%.1f "
      "factorizations_per_frame=%.1f cg_per_frame=%.1f "
      "linear_solve=%.0f%% collision=%.0f%% energies_assembly=%.0f%% non_converged_steps=%d "
      "median_residual=%.2g max_residual=%.2g\n",
      scene.c_str(), solver.c_str(), mesh.num_vertices(), median(frame_ms), median(frame_cpu_ms),
      median(iters), mean_it, double(factorizations) / frames, double(cg_iterations) / frames,
      100 * lin / total, 100 * coll / total, 100 * energy / total, failed, median(residuals),
      *std::max_element(residuals.begin(), residuals.end()));
  return 0;
}
