// The final collision-resolution pass (physics/collision_resolution.h) on a `weft synth`
// dataset's garment, as `weft infer --resolve-collisions` runs it: per frame the
// ground-truth cloth made into a prediction-like input by capture::perturb_start
// (capture/studio/cloth_perturbation.h), then pushed out of the frame's body by
// capture::GarmentCollisionResolver (the dataset's material and collision settings,
// the body as the simulator sees it). One thread.
//   Inputs (perturbation=...):
//     patches: no stretch, a smooth displacement of at most 1 cm and 2 patches pushed 2 cm
//              into the body (radius 5 cm): a good prediction with local penetrations;
//     network: perturb_start's defaults (stretches in [0.7, 1.3], smooth displacement
//              ≤ 3 cm, 2 patches 2 cm deep): the starts of the simulation-loss benchmark.
//   Per frame: RUNS passes (the same input), the median wall and CPU time; over frames the
//   median, and the penetration before and after (deepest vertex, mean depth of the
//   vertices inside), Newton iterations, the solved region and where the time goes.
// Usage: bench_collision_resolution DATASET [FRAMES=20] [RUNS=3] [SEED=1]
//                                   [perturbation=patches|network] [radius=M] [k=1/s²] [compare=0|1]
// compare=1 also solves the whole cloth per frame (untimed) and reports how far the
// region's answer is from it (the region's truncation error), over the vertices moved by
// the region or clear of the collision band at the start.
// e.g. bench_collision_resolution /tmp/collide/train40 20 5
// The simulation settings are the dataset's own (dataset.yaml's simulation section).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "bench/bench_clock.h"
#include "capture/io/portable_random.h"
#include "capture/studio/cloth_perturbation.h"
#include "capture/garment/garment_collision_resolution.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "graph/error.h"
#include "graph/threads.h"

using namespace weft;
using namespace weft::capture;

namespace {

using weft::bench::cpu_ms;
using weft::bench::ms_since;

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0 : s / v.size();
}

double max_of(const std::vector<double>& v) { return v.empty() ? 0 : *std::max_element(v.begin(), v.end()); }

double load_average() {
  double l = -1;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &l) != 1) l = -1;
    std::fclose(f);
  }
  return l;
}

ClothPerturbationConfig perturbation(const std::string& kind) {
  ClothPerturbationConfig c;
  c.velocity_noise_smooth_mps = 0;
  c.velocity_noise_vertex_mps = 0;
  if (kind == "network") return c;
  WEFT_CHECK(kind == "patches", "bench_collision_resolution: perturbation must be patches or network, got ", kind);
  c.max_stretch = 0;
  c.max_displacement_m = 0.01;
  return c;
}

}  // namespace

int main(int argc_all, char** argv_all) {
  std::vector<char*> positional;
  std::map<std::string, std::string> named;
  for (int k = 0; k < argc_all; ++k) {
    const char* eq = k > 0 ? std::strchr(argv_all[k], '=') : nullptr;
    if (eq)
      named[std::string(argv_all[k], static_cast<size_t>(eq - argv_all[k]))] = eq + 1;
    else
      positional.push_back(argv_all[k]);
  }
  if (positional.size() < 2) {
    std::fprintf(stderr, "usage: bench_collision_resolution DATASET [FRAMES=20] [RUNS=3] [SEED=1] "
                         "[perturbation=patches|network] [radius=M] [k=1/s^2]\n");
    return 2;
  }
  const std::string dataset = positional[1];
  const int frames = positional.size() > 2 ? std::atoi(positional[2]) : 20;
  const int runs = positional.size() > 3 ? std::atoi(positional[3]) : 3;
  const uint64_t seed = positional.size() > 4 ? std::strtoull(positional[4], nullptr, 10) : 1;
  auto key = [&](const char* k, const char* def) {
    auto it = named.find(k);
    std::string v = it == named.end() ? def : it->second;
    if (it != named.end()) named.erase(it);
    return v;
  };
  const std::string kind = key("perturbation", "patches");
  const std::string radius = key("radius", "");
  const std::string k = key("k", "");
  const bool compare = key("compare", "0") == "1";
  if (!named.empty()) {
    std::fprintf(stderr, "bench_collision_resolution: unknown option '%s'\n", named.begin()->first.c_str());
    return 2;
  }
  set_num_threads(1);

  const GarmentSequence s = load_garment_sequence(dataset);
  const double mpu = s.character.metres_per_unit;
  const physics::Positions rest = to_positions(s.character.cloth->mesh.V, mpu);
  GarmentCollisionResolver resolver(s.character, s.simulation), whole(s.character, s.simulation);
  if (!radius.empty()) resolver.options().region_radius = std::strtod(radius.c_str(), nullptr);
  if (!k.empty())
    resolver.options().proximal_stiffness = whole.options().proximal_stiffness = std::strtod(k.c_str(), nullptr);
  whole.options().region_radius = std::numeric_limits<double>::infinity();
  const physics::CollisionResolutionOptions& o = resolver.options();
  std::printf("dataset %s: %d frames, garment %d vertices, body %d vertices; perturbation %s, %d frames x %d runs, "
              "seed %llu; thickness %.4f m, collision stiffness %.0f N/m, proximal k %.3g 1/s^2, region radius %.3f m, "
              "cap %d iterations, tolerance %.1e m; load %.2f\n",
              dataset.c_str(), s.frames, static_cast<int>(rest.size() / 3), s.character.body.mesh.num_vertices(),
              kind.c_str(), frames, runs, static_cast<unsigned long long>(seed), o.collision_thickness,
              o.collision_stiffness, o.proximal_stiffness, o.region_radius, o.max_iterations, o.tolerance_m,
              load_average());

  std::vector<double> wall, cpu, body_ms, dist_ms, setup_ms, newton_ms, iterations, region;
  std::vector<double> before_max, before_mean, after_max, after_mean, inside_before, inside_after, moved_max;
  std::vector<double> region_error;  // mm, against the whole cloth (compare=1)
  std::map<std::string, std::vector<double>> energy_ms;  // Newton's time in each energy
  std::vector<double> linear_ms;
  std::map<std::string, int> statuses;
  const int span = std::max(1, s.frames - 1);
  for (int i = 0; i < frames; ++i) {
    const int f = 1 + (frames > 1 ? static_cast<int>(static_cast<long>(i) * (span - 1) / (frames - 1)) : 0);
    const physics::BodyMesh body = collision_body(s, f);
    const PerturbedStart p = perturb_start(s.cloth[f - 1], s.cloth[f], rest, body, s.time_step(),
                                                    perturbation(kind), mix_seed(seed, static_cast<uint64_t>(f), 3));
    const Vertices body_units = s.body(f) / mpu;
    const Vertices cloth_units = to_vertices(p.x_prev, mpu);
    std::vector<double> run_wall, run_cpu;
    GarmentCollisionResolution r;
    for (int run = 0; run < runs; ++run) {
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = cpu_ms();
      r = resolver.resolve(body_units, cloth_units);
      run_wall.push_back(ms_since(t0));
      run_cpu.push_back(cpu_ms() - c0);
    }
    const physics::CollisionResolutionResult& pass = r.pass;
    wall.push_back(median(run_wall));
    cpu.push_back(median(run_cpu));
    body_ms.push_back(r.body_ms);
    dist_ms.push_back(pass.distance_ms);
    setup_ms.push_back(pass.setup_ms);
    newton_ms.push_back(pass.newton_ms);
    iterations.push_back(pass.iterations);
    region.push_back(pass.region_vertices);
    before_max.push_back(1e3 * pass.before.max_depth);
    before_mean.push_back(1e3 * pass.before.mean_depth);
    after_max.push_back(1e3 * pass.after.max_depth);
    after_mean.push_back(1e3 * pass.after.mean_depth);
    inside_before.push_back(pass.before.vertices_inside);
    inside_after.push_back(pass.after.vertices_inside);
    double moved = 0;
    for (int v = 0; v < pass.x.size() / 3; ++v)
      moved = std::max(moved, (pass.x.segment<3>(3 * v) - p.x_prev.segment<3>(3 * v)).norm());
    moved_max.push_back(1e3 * moved);
    for (size_t e = 0; e < pass.energy_ms.size(); ++e) energy_ms[pass.energy_names[e]].push_back(pass.energy_ms[e]);
    linear_ms.push_back(pass.linear_solve_ms);
    std::string versus;
    if (compare) {
      const GarmentCollisionResolution w = whole.resolve(body_units, cloth_units);
      double e = 0;
      // Over the vertices the region's solve is meant to match: all but those resting in the
      // collision band away from any penetration, which the whole-cloth solve re-balances
      // (pushes out to the penalty's equilibrium) and the region leaves alone by design.
      for (int v = 0; v < pass.x.size() / 3; ++v) {
        const bool moved_by_region = pass.x.segment<3>(3 * v) != p.x_prev.segment<3>(3 * v);
        const double d0 = body.closest_point(p.x_prev.segment<3>(3 * v)).distance;
        if (moved_by_region || d0 >= o.collision_thickness)
          e = std::max(e, (pass.x.segment<3>(3 * v) - w.pass.x.segment<3>(3 * v)).norm());
      }
      region_error.push_back(1e3 * e);
      char buf[200];
      std::snprintf(buf, sizeof buf,
                    "; whole cloth: %d iterations, %.1f ms, max after %.3f mm, region differs by %.3f mm",
                    w.pass.iterations, w.pass.total_ms, 1e3 * w.pass.after.max_depth, region_error.back());
      versus = buf;
    }
    ++statuses[physics::to_string(pass.status)];
    std::printf("frame %d: %s, %d Newton iterations, region %d vertices; inside before %d (max %.2f mm, mean %.2f mm), "
                "after %d (max %.3f mm, mean %.3f mm); largest move %.1f mm; %.1f ms wall, %.1f ms cpu (median of %d; "
                "body %.1f, distances %.1f, setup %.1f, Newton %.1f)%s\n",
                f, physics::to_string(pass.status), pass.iterations, pass.region_vertices, pass.before.vertices_inside,
                before_max.back(), before_mean.back(), pass.after.vertices_inside, after_max.back(), after_mean.back(),
                moved_max.back(), wall.back(), cpu.back(), runs, r.body_ms, pass.distance_ms, pass.setup_ms,
                pass.newton_ms, versus.c_str());
    std::fflush(stdout);
  }
  std::string status_list;
  for (const auto& [name, count] : statuses)
    status_list += std::string(status_list.empty() ? "" : ",") + name + ":" + std::to_string(count);
  std::printf(
      "SUMMARY frames=%zu runs=%d perturbation=%s statuses=%s median_wall_ms=%.1f median_cpu_ms=%.1f max_wall_ms=%.1f "
      "paper_ratio=%.0f median_body_ms=%.1f median_distance_ms=%.1f median_setup_ms=%.1f median_newton_ms=%.1f "
      "median_iterations=%.0f max_iterations=%.0f median_region=%.0f before_max_mm(median/max)=%.2f/%.2f "
      "before_mean_mm=%.2f before_inside=%.0f after_max_mm(median/max)=%.3f/%.3f after_mean_mm=%.3f "
      "after_inside=%.1f frames_over_1mm=%d largest_move_mm(median)=%.1f region_error_mm(median/max)=%.3f/%.3f "
      "load=%.2f\n",
      wall.size(), runs, kind.c_str(), status_list.c_str(), median(wall), median(cpu), max_of(wall),
      2000.0 / std::max(median(cpu), 1e-9), median(body_ms), median(dist_ms), median(setup_ms), median(newton_ms),
      median(iterations), max_of(iterations), median(region), median(before_max), max_of(before_max), mean(before_mean),
      mean(inside_before), median(after_max), max_of(after_max), mean(after_mean), mean(inside_after),
      static_cast<int>(std::count_if(after_max.begin(), after_max.end(), [](double d) { return d > 1.0; })),
      median(moved_max), median(region_error), max_of(region_error), load_average());
  std::printf("NEWTON_BREAKDOWN median ms per frame: linear_solve=%.1f", median(linear_ms));
  for (const auto& [name, v] : energy_ms) std::printf(" %s=%.1f", name.c_str(), median(v));
  std::printf("\n");
  return 0;
}
