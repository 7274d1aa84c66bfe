// Simulation windows of the garment from perturbed starts (the method's simulation loss
// starts its windows from network predictions): a short synth dataset of the coarse skirt
// on the walk, the window simulator built as the synth builds it (checked by replaying a
// ground-truth frame), the perturbation generator's determinism and bounds, and ~10
// perturbed windows of F = 3 frames that must end converged or with a reported
// non-converged status, never non-finite, and, when converged, with no vertex more than
// 1 mm inside the body. The full-size figures: bench/simulation_windows.cpp.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "tests/capture/test_files.h"
#include "capture/studio/cloth_perturbation.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "capture/io/portable_random.h"
#include "capture/studio/synthetic_studio.h"
#include "physics/simulation_window.h"

using namespace weft;
using namespace weft::capture;
using weft::physics::Positions;
using weft::physics::StepStatus;
using weft::physics::Vec3;
namespace fs = std::filesystem;

using weft::capture::testing::kHuman;
using weft::capture::testing::repo_file;

namespace {



fs::path windows_scratch_root() { return fs::temp_directory_path() / ("weft_windows_test_" + std::to_string(::getpid())); }

// 8 frames of the walk with the 448-vertex skirt; one small view (the windows need only gt/).
std::string config_text() {
  std::ostringstream s;
  s << "name: windows_test\nseed: 3\n"
    << "character: " << repo_file("configs/characters/makehuman_skirt_coarse.yaml") << "\n"
    << "motion:\n"
    << "  procedural: " << repo_file("configs/motions/walk_in_place.yaml") << "\n"
    << "  mapping: " << repo_file("configs/retarget/humanoid_to_makehuman.yaml") << "\n"
    << "  fps: 30\n  start: 1.0\n  frames: 8\n"
    << "simulation: {settle_frames: 6}\n"
    << "cameras: {rig: studio, views: 1, width: 64, height: 64}\n"
    << "splits: {val: 0, test: 0}\n";
  return s.str();
}

struct Fixture {
  fs::path dir;
  GarmentSequence sequence;
  Positions rest;
};

// Written once per test program, removed at exit.
const Fixture& fixture() {
  static std::unique_ptr<Fixture> f;
  if (!f) {
    f = std::make_unique<Fixture>();
    const fs::path root = windows_scratch_root();
    fs::remove_all(root);
    fs::create_directories(root);
    const fs::path config = root / "windows_test.yaml";
    std::ofstream(config) << config_text();
    f->dir = root / "dataset";
    synthesize_dataset(load_synth_config(config.string()), f->dir.string());
    f->sequence = load_garment_sequence(f->dir.string());
    f->rest = to_positions(f->sequence.character.cloth->mesh.V, f->sequence.character.metres_per_unit);
    static struct Cleanup {
      ~Cleanup() {
        std::error_code ec;
        fs::remove_all(windows_scratch_root(), ec);
      }
    } cleanup;
  }
  return *f;
}

double max_vertex_norm(const Positions& d) {
  double m = 0;
  for (int i = 0; i < d.size() / 3; ++i) m = std::max(m, d.segment<3>(3 * i).norm());
  return m;
}

}  // namespace

// The factory's simulator is the synth's: one window of one frame from the ground-truth
// pair (t − 1, t) lands on the ground truth of t + 1 (the dataset's character is read back
// from its files, so agreement is to the files' rounding, not bitwise).
TEST(SimulationWindows, GroundTruthReplaysThroughTheWindowSimulator) {
  REQUIRE_HUMAN();
  const GarmentSequence& s = fixture().sequence;
  for (int t : {2, 5}) {
    const auto w = garment_window(s, t, 1, s.cloth[t - 1], s.cloth[t]);
    const auto r = weft::physics::simulate_windows(s.simulator_factory(), {w});
    ASSERT_EQ(r.size(), 1u);
    const double err = max_vertex_norm(r[0][0].x - s.cloth[t + 1]);
    std::printf("frame %d replayed: %s, max vertex error %.3g m\n", t + 1, weft::physics::to_string(r[0][0].status),
                err);
    EXPECT_LT(err, 1e-4) << "frame " << t + 1;
  }
}

TEST(SimulationWindows, PerturbationIsDeterministicAndBounded) {
  REQUIRE_HUMAN();
  const Fixture& f = fixture();
  const GarmentSequence& s = f.sequence;
  const ClothPerturbationConfig c;
  const int t = 4;
  const weft::physics::BodyMesh body = collision_body(s, t);
  const double h = s.time_step();
  const PerturbedStart a = perturb_start(s.cloth[t - 1], s.cloth[t], f.rest, body, h, c, 11);
  const PerturbedStart b = perturb_start(s.cloth[t - 1], s.cloth[t], f.rest, body, h, c, 11);
  const PerturbedStart other = perturb_start(s.cloth[t - 1], s.cloth[t], f.rest, body, h, c, 12);
  EXPECT_EQ(a.x_prev, b.x_prev);
  EXPECT_EQ(a.x_prev2, b.x_prev2);
  EXPECT_GT(max_vertex_norm(a.x_prev - other.x_prev), 1e-3) << "another seed should draw another perturbation";

  for (uint64_t seed = 0; seed < 20; ++seed) {
    const PerturbedStart p = perturb_start(s.cloth[t - 1], s.cloth[t], f.rest, body, h, c, seed);
    const ClothPerturbation& d = p.drawn;
    ASSERT_TRUE(p.x_prev.allFinite() && p.x_prev2.allFinite());
    // Stretch: both principal stretches within 30 %.
    EXPECT_GE(d.axial_stretch, 1 - c.max_stretch);
    EXPECT_LE(d.axial_stretch, 1 + c.max_stretch);
    EXPECT_GE(d.lateral_stretch, 1 - c.max_stretch);
    EXPECT_LE(d.lateral_stretch, 1 + c.max_stretch);
    EXPECT_NEAR(d.stretch_axis.norm(), 1, 1e-12);
    // Smooth displacement at most 3 cm, and not trivially small.
    const double disp = max_vertex_norm(d.displacement);
    EXPECT_LE(disp, c.max_displacement_m + 1e-12);
    EXPECT_GT(disp, 0.1 * c.max_displacement_m);
    // Velocity noise bounded, and x_prev2 = x_prev − h v exactly.
    EXPECT_LE(max_vertex_norm(d.velocity_noise), c.velocity_noise_smooth_mps + c.velocity_noise_vertex_mps + 1e-12);
    const Positions v = (s.cloth[t] - s.cloth[t - 1]) / h + d.velocity_noise;
    EXPECT_LT(max_vertex_norm(p.x_prev2 - (p.x_prev - h * v)), 1e-12);
    // Away from the patches x_prev is exactly stretch + displacement; a vertex a patch
    // moved went into the body, by at most the patch depth plus the candidates' distance,
    // and ends no deeper than the patch depth (5 mm of slack for the body's curvature).
    const Eigen::Matrix3d A = d.lateral_stretch * Eigen::Matrix3d::Identity() +
                              (d.axial_stretch - d.lateral_stretch) * d.stretch_axis * d.stretch_axis.transpose();
    EXPECT_EQ(static_cast<int>(d.patch_centres.size()), c.patches);
    int moved = 0;
    double deepest = 0;
    for (int i = 0; i < s.cloth[t].size() / 3; ++i) {
      const Vec3 expected = d.centroid + A * (s.cloth[t].segment<3>(3 * i) - d.centroid) + d.displacement.segment<3>(3 * i);
      const Vec3 actual = p.x_prev.segment<3>(3 * i);
      const double depth = -body.closest_point(actual).distance;
      deepest = std::max(deepest, depth);
      if ((actual - expected).norm() < 1e-12) continue;
      ++moved;
      EXPECT_LE((actual - expected).norm(), c.patch_depth_m + c.patch_candidate_distance_m + 1e-9) << "vertex " << i;
      EXPECT_LE(depth, c.patch_depth_m + 0.005) << "vertex " << i << " seed " << seed;
      EXPECT_LT(body.closest_point(actual).distance, body.closest_point(expected).distance) << "vertex " << i;
    }
    EXPECT_GT(moved, 0) << "the patches should move vertices into the body, seed " << seed;
    EXPECT_GT(deepest, 0.5 * c.patch_depth_m) << "a patch centre should end about 2 cm inside, seed " << seed;
  }
}

// ~10 windows of 2 simulated frames from perturbed starts: the outcome is reported, never
// non-finite, never an exception; converged windows end with the body at most 1 mm deep
// in the cloth; the waistband follows its pins.
TEST(SimulationWindows, PerturbedWindowsEndConvergedOrReportedAndOutOfTheBody) {
  REQUIRE_HUMAN();
  const Fixture& f = fixture();
  const GarmentSequence& s = f.sequence;
  const int frames = 2, count = 10;
  std::vector<weft::physics::SimulationWindow> windows;
  std::vector<int> starts;
  PortableRandom rng(5);
  for (int k = 0; k < count; ++k) {
    const int t = 1 + static_cast<int>(rng.uniform() * (s.frames - frames - 1));
    const PerturbedStart p =
        perturb_start(s.cloth[t - 1], s.cloth[t], f.rest, collision_body(s, t), s.time_step(), {}, 100 + k);
    windows.push_back(garment_window(s, t, frames, p.x_prev2, p.x_prev));
    starts.push_back(t);
  }
  std::vector<std::vector<weft::physics::StepResult>> results;
  ASSERT_NO_THROW(results = weft::physics::simulate_windows(s.simulator_factory(), windows));
  ASSERT_EQ(results.size(), windows.size());
  int converged = 0;
  for (int k = 0; k < count; ++k) {
    ASSERT_EQ(static_cast<int>(results[k].size()), frames);
    bool ok = true;
    for (const auto& r : results[k]) {
      EXPECT_TRUE(r.x.allFinite()) << "window " << k;
      EXPECT_NE(r.status, StepStatus::non_finite) << "window " << k << ": a finite start gave non-finite values";
      ok = ok && r.status == StepStatus::converged;
    }
    const Positions& end = results[k].back().x;
    const Penetration pen = body_penetration(collision_body(s, starts[k] + frames), end);
    std::printf("window %d (start %d): %s, %s, depth %.2f mm\n", k, starts[k],
                weft::physics::to_string(results[k][0].status), weft::physics::to_string(results[k][1].status),
                1e3 * pen.max_depth);
    if (!ok) continue;
    ++converged;
    EXPECT_LE(pen.max_depth, 1e-3) << "window " << k << " converged with a vertex " << 1e3 * pen.max_depth
                                   << " mm inside the body";
    // The pins pulled the waistband to where the skin carries it (stiff soft pins: within
    // a centimetre after two frames from a start up to ~6 cm off).
    const auto& pins = windows[k].pin_vertices;
    const auto& targets = windows[k].pin_targets.back();
    double worst = 0;
    for (size_t j = 0; j < pins.size(); ++j) worst = std::max(worst, (end.segment<3>(3 * pins[j]) - targets[j]).norm());
    EXPECT_LT(worst, 0.01) << "window " << k << ": a pinned vertex is " << worst << " m from its target";
  }
  std::printf("%d of %d windows converged\n", converged, count);
}
