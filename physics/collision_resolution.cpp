#include "physics/collision_resolution.h"

#include <chrono>
#include <cmath>
#include <queue>

#include "graph/error.h"
#include "physics/bending_energy.h"
#include "physics/membrane_energy.h"
#include "physics/vertex_energies.h"

namespace weft::physics {

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Signed distance of every listed vertex (all when `vertices` is null) to the obstacles, m.
void signed_distances(const Positions& x, const CollisionEnergy& obstacles, const std::vector<int>* vertices,
                      std::vector<double>& d) {
  const int n = static_cast<int>(x.size() / 3);
  d.resize(n);
  if (vertices) {
    for (int i : *vertices) d[i] = obstacles.min_signed_distance(x.segment<3>(3 * i));
  } else {
    for (int i = 0; i < n; ++i) d[i] = obstacles.min_signed_distance(x.segment<3>(3 * i));
  }
}

PenetrationStats penetration_of(const std::vector<double>& d) {
  PenetrationStats s;
  double sum = 0;
  for (double di : d)
    if (di < 0) {
      ++s.vertices_inside;
      sum -= di;
      s.max_depth = std::max(s.max_depth, -di);
    }
  if (s.vertices_inside > 0) s.mean_depth = sum / s.vertices_inside;
  return s;
}

CollisionEnergy obstacle_energy(int n, const CollisionObstacles& obstacles, const CollisionResolutionOptions& o) {
  CollisionEnergy c(n, o.collision_thickness, o.collision_stiffness);
  c.set_spheres(obstacles.spheres);
  c.set_bodies(obstacles.bodies);
  return c;
}

// Geodesic distance (m, along the cloth's edges at x) from the seed vertices, up to
// `radius`; +inf beyond. Dijkstra over the edge graph.
std::vector<double> geodesic_distance(const ClothMesh& mesh, const Positions& x, const std::vector<int>& seeds,
                                      double radius) {
  const int n = mesh.num_vertices();
  std::vector<int> start(n + 1, 0), adj(2 * mesh.edges.size());
  for (const auto& e : mesh.edges) {
    ++start[e[0] + 1];
    ++start[e[1] + 1];
  }
  for (int i = 0; i < n; ++i) start[i + 1] += start[i];
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (const auto& e : mesh.edges) {
    adj[fill[e[0]]++] = e[1];
    adj[fill[e[1]]++] = e[0];
  }
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> queue;
  for (int s : seeds) {
    dist[s] = 0;
    queue.push({0.0, s});
  }
  while (!queue.empty()) {
    const auto [di, i] = queue.top();
    queue.pop();
    if (di > dist[i]) continue;
    for (int k = start[i]; k < start[i + 1]; ++k) {
      const int j = adj[k];
      const double dj = di + (x.segment<3>(3 * i) - x.segment<3>(3 * j)).norm();
      if (dj < dist[j] && dj <= radius) {
        dist[j] = dj;
        queue.push({dj, j});
      }
    }
  }
  return dist;
}

double triangle_area(const Positions& x, const std::array<int, 3>& t) {
  const Vec3 a = x.segment<3>(3 * t[0]), b = x.segment<3>(3 * t[1]), c = x.segment<3>(3 * t[2]);
  return 0.5 * (b - a).cross(c - a).norm();
}

}  // namespace

void validate(const CollisionResolutionOptions& o) {
  validate(o.material);
  WEFT_CHECK(std::isfinite(o.collision_thickness) && o.collision_thickness > 0,
             "collision resolution: collision_thickness must be > 0 m, got ", o.collision_thickness);
  WEFT_CHECK(std::isfinite(o.collision_stiffness) && o.collision_stiffness > 0,
             "collision resolution: collision_stiffness must be > 0 N/m, got ", o.collision_stiffness);
  WEFT_CHECK(std::isfinite(o.pin_stiffness) && o.pin_stiffness > 0,
             "collision resolution: pin_stiffness must be > 0 N/m, got ", o.pin_stiffness);
  WEFT_CHECK(std::isfinite(o.proximal_stiffness) && o.proximal_stiffness > 0,
             "collision resolution: proximal_stiffness must be > 0 1/s², got ", o.proximal_stiffness);
  WEFT_CHECK(o.region_radius > 0, "collision resolution: region_radius must be > 0 m (inf: whole cloth), got ",
             o.region_radius);
  WEFT_CHECK(o.max_iterations >= 1, "collision resolution: max_iterations must be >= 1, got ", o.max_iterations);
  WEFT_CHECK(std::isfinite(o.tolerance_m) && o.tolerance_m > 0,
             "collision resolution: tolerance_m must be > 0 m, got ", o.tolerance_m);
  WEFT_CHECK(std::isfinite(o.energy_tolerance) && o.energy_tolerance >= 0,
             "collision resolution: energy_tolerance must be >= 0, got ", o.energy_tolerance);
  WEFT_CHECK(o.min_reference_area_ratio >= 0 && o.min_reference_area_ratio < 1,
             "collision resolution: min_reference_area_ratio must be in [0, 1), got ", o.min_reference_area_ratio);
}

PenetrationStats measure_penetration(const Positions& x, const CollisionObstacles& obstacles) {
  WEFT_CHECK(x.size() % 3 == 0, "penetration: positions size ", x.size(), " is not 3n");
  CollisionResolutionOptions o;
  const CollisionEnergy c = obstacle_energy(static_cast<int>(x.size() / 3), obstacles, o);
  std::vector<double> d;
  signed_distances(x, c, nullptr, d);
  return penetration_of(d);
}

CollisionResolutionResult resolve_collisions(const ClothMesh& mesh, const Positions& x0,
                                             const CollisionObstacles& obstacles,
                                             const CollisionResolutionOptions& o, const std::vector<int>& held) {
  const auto t_start = std::chrono::steady_clock::now();
  validate(o);
  const int n = mesh.num_vertices();
  WEFT_CHECK(x0.size() == 3 * n, "collision resolution: the cloth has ", n, " vertices but the positions have ",
             x0.size(), " entries (expected ", 3 * n, ")");
  for (int i = 0; i < n; ++i)
    WEFT_CHECK(x0.segment<3>(3 * i).allFinite(), "collision resolution: cloth vertex ", i,
               " has a non-finite position");
  for (int v : held)
    WEFT_CHECK(v >= 0 && v < n, "collision resolution: held vertex ", v, " outside [0, ", n, ")");
  for (const BodyMesh* b : obstacles.bodies) {
    WEFT_CHECK(b != nullptr, "collision resolution: null body obstacle");
    WEFT_CHECK(b->vertices().allFinite(), "collision resolution: the body has a non-finite vertex");
  }

  CollisionResolutionResult result;
  result.x = x0;
  const CollisionEnergy all = obstacle_energy(n, obstacles, o);
  auto t0 = std::chrono::steady_clock::now();
  std::vector<double> d;
  signed_distances(x0, all, nullptr, d);
  result.distance_ms = ms_since(t0);
  result.before = penetration_of(d);
  std::vector<int> seeds;
  for (int i = 0; i < n; ++i)
    if (d[i] < 0) seeds.push_back(i);
  if (seeds.empty()) {  // nothing inside: the prediction is kept as it is
    result.after = result.before;
    result.energies.push_back(0.0);
    result.total_ms = ms_since(t_start);
    return result;
  }

  // The region, its border ring and the local numbering.
  t0 = std::chrono::steady_clock::now();
  const std::vector<double> geo = geodesic_distance(mesh, x0, seeds, o.region_radius);
  std::vector<int> local(n, -1), global;
  std::vector<char> in_region(n, 0);
  for (int i = 0; i < n; ++i)
    if (std::isfinite(geo[i])) {
      in_region[i] = 1;
      local[i] = static_cast<int>(global.size());
      global.push_back(i);
    }
  const int region_size = static_cast<int>(global.size());
  for (const auto& e : mesh.edges)
    for (int k = 0; k < 2; ++k) {
      const int a = e[k], b = e[1 - k];
      if (in_region[a] && local[b] < 0) {
        local[b] = static_cast<int>(global.size());
        global.push_back(b);
      }
    }
  const int m = static_cast<int>(global.size());
  result.region_vertices = region_size;

  // The sub-cloth with the prediction as its rest shape, its masses the cloth's own.
  Positions x_sub(3 * m);
  Eigen::VectorXd mass(m);
  const double mass_floor = 1e-6 * mesh.mass.mean();
  for (int j = 0; j < m; ++j) {
    x_sub.segment<3>(3 * j) = x0.segment<3>(3 * global[j]);
    mass[j] = std::max(mesh.mass[global[j]], mass_floor);
  }
  std::vector<std::array<int, 3>> tris;
  for (const auto& t : mesh.triangles) {
    if (local[t[0]] < 0 || local[t[1]] < 0 || local[t[2]] < 0) continue;
    if (triangle_area(x0, t) < o.min_reference_area_ratio * triangle_area(mesh.rest, t) ||
        triangle_area(x0, t) <= 1e-14)
      continue;
    tris.push_back({local[t[0]], local[t[1]], local[t[2]]});
  }
  ClothMesh sub = make_cloth_mesh(x_sub, std::move(tris), o.material.density);
  sub.mass = mass;

  // m/(2h²)‖x − x̂‖² with h = 1/√k is the proximal term k/2 m‖x − x₀‖².
  InertiaEnergy proximal(mass, 1.0 / std::sqrt(o.proximal_stiffness));
  proximal.set_prediction(x_sub);
  MembraneEnergy membrane(sub, o.material);
  membrane.set_hessian_projection(false);  // as the simulator: exact, corrected when indefinite
  BendingEnergy bending(sub, o.material);
  std::vector<int> pinned;
  std::vector<Vec3> targets;
  for (int j = region_size; j < m; ++j) pinned.push_back(j);
  for (int v : held)
    if (in_region[v]) pinned.push_back(local[v]);
  for (int j : pinned) targets.push_back(x_sub.segment<3>(3 * j));
  PinEnergy pins(pinned, targets, o.pin_stiffness);
  CollisionEnergy collision = obstacle_energy(m, obstacles, o);
  NewtonOptions newton;
  newton.max_iterations = 1;  // one iteration per call: the loop below judges convergence
  newton.tolerance = o.tolerance_m;
  NewtonSolver solver(m, {&proximal, &membrane, &bending, &pins, &collision}, newton);
  // ‖∇_i E‖ / (k·m_i) ≤ tolerance_m: the residual as a displacement (see the options).
  solver.set_force_scale(o.proximal_stiffness * mass);
  for (Energy* e : solver.energies()) e->begin_step(x_sub);
  result.setup_ms = ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  Positions x = x_sub, x_before;
  result.status = StepStatus::max_iterations;
  result.energy_ms.assign(solver.energies().size(), 0.0);
  for (const Energy* e : solver.energies()) result.energy_names.push_back(e->name());
  for (int it = 0; it < o.max_iterations; ++it) {
    x_before = x;
    const NewtonReport report = solver.minimize(x);
    if (result.energies.empty() && !report.accepted_energies.empty())
      result.energies.push_back(report.accepted_energies.front());
    if (report.status == StepStatus::converged && report.iterations == 0) {
      result.status = StepStatus::converged;
      break;
    }
    if (report.status == StepStatus::line_search_failed || report.status == StepStatus::non_finite) {
      result.status = report.status;
      break;
    }
    ++result.iterations;
    for (size_t e = 0; e < report.energy_ms.size(); ++e) result.energy_ms[e] += report.energy_ms[e];
    result.linear_solve_ms += report.linear_solve_ms;
    result.energies.push_back(report.accepted_energies.back());
    double move = 0;
    for (int j = 0; j < m; ++j) move = std::max(move, (x.segment<3>(3 * j) - x_before.segment<3>(3 * j)).norm());
    if (report.status == StepStatus::converged || move <= o.tolerance_m) {
      result.status = StepStatus::converged;
      break;
    }
    const double e_prev = result.energies[result.energies.size() - 2], e_now = result.energies.back();
    if (e_prev - e_now <= o.energy_tolerance * std::abs(e_now)) {
      bool clear = true;
      for (int j = 0; j < region_size && clear; ++j) clear = collision.min_signed_distance(x.segment<3>(3 * j)) >= 0;
      if (clear) {
        result.status = StepStatus::converged;
        break;
      }
    }
  }
  result.newton_ms = ms_since(t0);
  if (x.allFinite()) {
    for (int j = 0; j < region_size; ++j) result.x.segment<3>(3 * global[j]) = x.segment<3>(3 * j);
  } else {
    result.status = StepStatus::non_finite;  // x₀ is returned
  }

  t0 = std::chrono::steady_clock::now();
  const std::vector<int> moved(global.begin(), global.begin() + region_size);
  signed_distances(result.x, all, &moved, d);
  result.distance_ms += ms_since(t0);
  result.after = penetration_of(d);
  result.total_ms = ms_since(t_start);
  return result;
}

}  // namespace weft::physics
