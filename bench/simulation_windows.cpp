// Simulation windows from perturbed starts, as the method's simulation loss runs them:
// each window starts from a ground-truth pair of a `weft synth` dataset (frames t − 1, t)
// perturbed by capture::perturb_start (stretch up to 30 %, smooth displacement up to
// 3 cm, patches pushed 2 cm into the body, noisy velocities; capture/studio/cloth_perturbation.h)
// and simulates FRAMES frames (default 2: a window of F = 3 frames) following the
// ground-truth body and waistband, with the simulator built exactly as the synth built
// the dataset's (capture/garment/garment_simulator.h).
//   Robustness: N windows (default 500) at seeded random starts, one at a time on one
//   thread: each window's statuses, the failures (status != converged) with their window
//   id, a NaN check, the deepest vertex inside the body at the end of every converged
//   window (mm; target <= 1 mm), wall and CPU time per window.
//   Batch: BATCH_WINDOWS windows (default 8; 16 simulated frames) through
//   physics::simulate_windows on THREADS threads (default 2), BATCHES times (default 5):
//   median batch wall time (target <= 1.5 s) and CPU time.
// Usage: bench_simulation_windows DATASET [N] [SEED]
//                                 [frames=2] [batches=5] [batch_windows=8] [threads=2]
//                                 [mode=all|robustness|batch] [first=0]
// e.g. bench_simulation_windows /tmp/runs/training 500 1
// first=ID runs the robustness windows ID .. ID + N − 1 (one window again: N = 1).
// The simulation settings are the dataset's own (dataset.yaml's simulation section). Prints
// one line per window and a SUMMARY line.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <string>
#include <vector>

#include "bench/bench_clock.h"
#include "capture/studio/cloth_perturbation.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "capture/io/portable_random.h"
#include "graph/error.h"
#include "graph/threads.h"
#include "physics/simulation_window.h"

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

double load_average() {
  double l = -1;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &l) != 1) l = -1;
    std::fclose(f);
  }
  return l;
}

struct Start {
  int id = 0, frame = 0;  // window id, ground-truth frame t of x_prev
  physics::SimulationWindow window;
  ClothPerturbation drawn;
};

// The clip (dataset.yaml segments) a frame belongs to: 0 for a one-clip dataset.
int clip_of(const GarmentSequence& s, int frame) {
  return static_cast<int>(std::upper_bound(s.segments.begin(), s.segments.end(), frame) - s.segments.begin());
}

// Window `id`: its start frame t, drawn among the frames whose t − 1 and the window's last
// frame t + window exist and lie in t's clip (a window does not run across the cut between
// two motions), and its perturbation, both from (seed, id) alone.
Start make_start(const GarmentSequence& s, const physics::Positions& rest, int id, int frames, uint64_t seed) {
  PortableRandom rng(mix_seed(seed, static_cast<uint64_t>(id), 1));
  std::vector<int> starts;
  for (int t = 1; t + frames < s.frames; ++t)
    if (clip_of(s, t - 1) == clip_of(s, t + frames)) starts.push_back(t);
  WEFT_CHECK(!starts.empty(), s.dir, ": no clip of ", s.frames, " frames holds a window of ", frames,
             " frames and the frame before it");
  Start st;
  st.id = id;
  const int span = static_cast<int>(starts.size());
  st.frame = starts[std::min(span - 1, static_cast<int>(rng.uniform() * span))];
  const physics::BodyMesh body = collision_body(s, st.frame);
  PerturbedStart p = perturb_start(s.cloth[st.frame - 1], s.cloth[st.frame], rest, body, s.time_step(), {},
                                   mix_seed(seed, static_cast<uint64_t>(id), 2));
  st.drawn = std::move(p.drawn);
  st.window = garment_window(s, st.frame, frames, std::move(p.x_prev2), std::move(p.x_prev));
  return st;
}

// The worst status of a window's frames (the order of StepStatus: converged first).
physics::StepStatus worst(const std::vector<physics::StepResult>& r) {
  physics::StepStatus w = physics::StepStatus::converged;
  for (const auto& x : r)
    if (x.status != physics::StepStatus::converged && w == physics::StepStatus::converged) w = x.status;
  return w;
}

bool all_finite(const std::vector<physics::StepResult>& r) {
  for (const auto& x : r)
    if (!x.x.allFinite()) return false;
  return true;
}

}  // namespace

static int run(int argc_all, char** argv_all) {
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
    std::fprintf(stderr, "usage: bench_simulation_windows DATASET [N] [SEED] [frames=2] [batches=5] "
                         "[batch_windows=8] [threads=2] [mode=all|robustness|batch] [first=0]\n");
    return 2;
  }
  const std::string dataset = positional[1];
  const int n = positional.size() > 2 ? std::atoi(positional[2]) : 500;
  const uint64_t seed = positional.size() > 3 ? std::strtoull(positional[3], nullptr, 10) : 1;
  auto key = [&](const char* k, const char* def) {
    auto it = named.find(k);
    std::string v = it == named.end() ? def : it->second;
    if (it != named.end()) named.erase(it);
    return v;
  };
  const int frames = std::atoi(key("frames", "2").c_str());
  const int batches = std::atoi(key("batches", "5").c_str());
  const int batch_windows = std::atoi(key("batch_windows", "8").c_str());
  const int threads = std::atoi(key("threads", "2").c_str());
  const std::string mode = key("mode", "all");
  const int first = std::atoi(key("first", "0").c_str());  // robustness: windows first .. first + N − 1
  if (!named.empty()) {
    std::fprintf(stderr, "bench_simulation_windows: unknown option '%s'\n", named.begin()->first.c_str());
    return 2;
  }

  const GarmentSequence s = load_garment_sequence(dataset);
  const physics::SimulatorFactory factory = s.simulator_factory();
  const physics::Positions rest = to_positions(s.character.cloth->mesh.V, s.character.metres_per_unit);
  const double tolerance_mm = 1.0;
  std::printf("dataset %s: %d frames (%zu failed in the synth), garment %d vertices, body %d vertices; "
              "windows of %d simulated frames, seed %llu, load %.2f\n",
              dataset.c_str(), s.frames, s.failed_frames.size(), static_cast<int>(rest.size() / 3),
              s.character.body.mesh.num_vertices(), frames, static_cast<unsigned long long>(seed), load_average());
  auto failed_in_synth = [&](int f) {
    return std::find(s.failed_frames.begin(), s.failed_frames.end(), f) != s.failed_frames.end();
  };

  // Robustness: one window at a time, one thread (CPU time = the window's own).
  int failures = 0, nan_windows = 0, converged = 0, deep_windows = 0, failures_clean_start = 0, clean_starts = 0;
  std::map<std::string, int> statuses;
  double max_depth_mm = 0;
  std::vector<double> window_ms, window_cpu_ms, build_ms, iterations;
  if (mode == "all" || mode == "robustness") {
    set_num_threads(1);
    for (int id = first; id < first + n; ++id) {
      const Start st = make_start(s, rest, id, frames, seed);
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = cpu_ms();
      std::unique_ptr<physics::ClothSimulator> sim = factory();
      const double built = ms_since(t0);
      const std::vector<physics::StepResult> r = physics::simulate_window(*sim, st.window);
      window_ms.push_back(ms_since(t0));
      window_cpu_ms.push_back(cpu_ms() - c0);
      build_ms.push_back(built);
      int it = 0;
      std::string per_frame;
      for (const auto& x : r) {
        it += x.newton_iterations;
        per_frame += std::string(per_frame.empty() ? "" : ",") + physics::to_string(x.status);
      }
      iterations.push_back(it);
      const physics::StepStatus status = worst(r);
      const bool finite = all_finite(r);
      nan_windows += !finite;
      ++statuses[physics::to_string(status)];
      // Depth against the body of the window's last frame (the simulator's obstacle there).
      const Penetration pen = body_penetration(collision_body(s, st.frame + frames), r.back().x);
      const bool clean = !failed_in_synth(st.frame) && !failed_in_synth(st.frame - 1);
      clean_starts += clean;
      if (status == physics::StepStatus::converged) {
        ++converged;
        max_depth_mm = std::max(max_depth_mm, 1e3 * pen.max_depth);
        deep_windows += 1e3 * pen.max_depth > tolerance_mm;
      } else {
        ++failures;
        failures_clean_start += clean;
      }
      std::printf("%swindow %d start %d%s: %s [%s], %d Newton iterations, end depth %.2f mm (%d inside), "
                  "stretch %.2f/%.2f, patches %zu, %.0f ms (cpu %.0f, build %.0f)%s\n",
                  status == physics::StepStatus::converged ? "" : "FAIL ", id, st.frame,
                  clean ? "" : " (synth-failed start)", physics::to_string(status), per_frame.c_str(), it,
                  1e3 * pen.max_depth, pen.vertices_inside, st.drawn.axial_stretch, st.drawn.lateral_stretch,
                  st.drawn.patch_centres.size(), window_ms.back(), window_cpu_ms.back(), built,
                  finite ? "" : " NON-FINITE STATE");
      std::fflush(stdout);
    }
  }

  // Batch: simulate_windows on `threads` threads, windows 0 .. batch_windows − 1.
  std::vector<double> batch_ms, batch_cpu_ms;
  int batch_failures = 0;
  if (mode == "all" || mode == "batch") {
    set_num_threads(threads);
    std::vector<physics::SimulationWindow> windows;
    for (int id = 0; id < batch_windows; ++id) windows.push_back(make_start(s, rest, id, frames, seed).window);
    for (int b = 0; b < batches; ++b) {
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = cpu_ms();
      const auto results = physics::simulate_windows(factory, windows);
      batch_ms.push_back(ms_since(t0));
      batch_cpu_ms.push_back(cpu_ms() - c0);
      int fails = 0;
      for (const auto& r : results) fails += worst(r) != physics::StepStatus::converged || !all_finite(r);
      batch_failures = std::max(batch_failures, fails);
      std::printf("batch %d: %d windows x %d frames on %d threads: %.0f ms (cpu %.0f ms), %d not converged\n", b,
                  batch_windows, frames, threads, batch_ms.back(), batch_cpu_ms.back(), fails);
      std::fflush(stdout);
    }
  }

  std::string status_list;
  for (const auto& [k, v] : statuses) status_list += std::string(status_list.empty() ? "" : ",") + k + ":" + std::to_string(v);
  std::printf(
      "SUMMARY windows=%zu frames=%d failures=%d failure_rate=%.3f statuses=%s failures_at_clean_starts=%d/%d "
      "non_finite=%d max_depth_converged_mm=%.3f converged_deeper_than_1mm=%d median_window_ms=%.0f "
      "median_window_cpu_ms=%.0f median_build_ms=%.0f median_newton_iterations=%.0f batch_windows=%d threads=%d "
      "median_batch_ms=%.0f median_batch_cpu_ms=%.0f batch_not_converged=%d load=%.2f\n",
      window_ms.size(), frames, failures, window_ms.empty() ? 0.0 : double(failures) / window_ms.size(),
      status_list.c_str(), failures_clean_start, clean_starts, nan_windows, max_depth_mm, deep_windows,
      median(window_ms), median(window_cpu_ms), median(build_ms), median(iterations), batch_windows, threads,
      median(batch_ms), median(batch_cpu_ms), batch_failures, load_average());
  return 0;
}

// A bad dataset or window (a weft::Error naming the file and what was expected) ends the
// benchmark with its message, not an abort.
int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const weft::Error& e) {
    std::fprintf(stderr, "bench_simulation_windows: %s\n", e.what());
    return 1;
  }
}
