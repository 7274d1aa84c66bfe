// The oracle pose perturbed as PoseNet errs (capture/training/pose_noise.h): each listed
// dof's error has the configured spread and correlation time, the draws are a function of
// the config (same seed, same motion; another seed, another), limits hold, unlisted dofs
// keep the truth, and a bad key, a missing file or an unknown dof is one error naming it.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "capture/training/pose_noise.h"
#include "capture/training/training_config.h"
#include "tests/capture/stick_figure.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;

namespace {

Motion rest_motion(const Skeleton& s, int frames) {
  Motion m;
  m.dofs = Eigen::MatrixXd::Zero(frames, s.num_dofs());
  for (int f = 0; f < frames; ++f) m.frame_ids.push_back(f);
  return m;
}

// The first unlimited dof with a rotation, and the first limited dof whose range holds 0.
int first_dof(const Skeleton& s, bool limited) {
  for (int d = 0; d < s.num_dofs(); ++d)
    if (s.dofs[d].limited == limited && (!limited || (s.dofs[d].lower < -0.3 && s.dofs[d].upper > 0.3)) &&
        s.dofs[d].name.find("root") == std::string::npos)
      return d;
  return -1;
}

}  // namespace

TEST(PoseNoise, EachDofErrsWithItsSpreadAndCorrelationTime) {
  const Skeleton s = weft::capture::testing::stick_figure_skeleton();
  const int a = first_dof(s, false), b = first_dof(s, true);
  ASSERT_GE(a, 0);
  ASSERT_GE(b, 0);
  PoseNoiseConfig c;
  c.file = "noise.yaml";
  c.seed = 4;
  c.correlation_frames = 5;
  c.spread = {{s.dofs[a].name, 0.2}, {s.dofs[b].name, 0.05}};
  const int n = 40000;
  const Motion truth = rest_motion(s, n);
  const Motion m = perturbed_motion(truth, s, c);
  for (const auto& [d, sigma] : {std::pair{a, 0.2}, std::pair{b, 0.05}}) {
    SCOPED_TRACE(s.dofs[d].name);
    const Eigen::VectorXd e = m.dofs.col(d);
    const double sd = std::sqrt(e.squaredNorm() / n);
    // Effective sample size n(1 − ρ)/(1 + ρ) ≈ 4,000: the spread within 5 %.
    EXPECT_NEAR(sd, sigma, 0.05 * sigma);
    EXPECT_LT(std::abs(e.mean()), 0.1 * sigma);
    const double lag1 = e.head(n - 1).dot(e.tail(n - 1)) / e.head(n - 1).squaredNorm();
    EXPECT_NEAR(lag1, std::exp(-1.0 / 5), 0.03) << "an AR(1) process of correlation time 5 frames";
  }
  // Unlisted dofs keep the truth, exactly.
  for (int d = 0; d < s.num_dofs(); ++d)
    if (d != a && d != b) EXPECT_EQ(m.dofs.col(d), truth.dofs.col(d)) << s.dofs[d].name;
  // A function of the config: the same again; another seed, other draws.
  EXPECT_EQ(perturbed_motion(truth, s, c).dofs, m.dofs);
  c.seed = 5;
  EXPECT_GT((perturbed_motion(truth, s, c).dofs - m.dofs).cwiseAbs().maxCoeff(), 0.1);
  // scale multiplies the spread.
  c.seed = 4, c.scale = 0.5;
  const Motion half = perturbed_motion(truth, s, c);
  EXPECT_NEAR(half.dofs(7, a), 0.5 * m.dofs(7, a), 1e-12);
  // A bias is added to every frame, on top of the draws (scaled too).
  c.scale = 1;
  c.bias = {{s.dofs[a].name, 0.3}};
  const Motion biased = perturbed_motion(truth, s, c);
  EXPECT_NEAR((biased.dofs.col(a) - m.dofs.col(a)).cwiseAbs().maxCoeff(), 0.3, 1e-12);
  EXPECT_NEAR((biased.dofs.col(a) - m.dofs.col(a)).minCoeff(), 0.3, 1e-12);
  EXPECT_EQ(biased.dofs.col(b), m.dofs.col(b));
}

TEST(PoseNoise, PerturbedDofsStayInsideTheirLimits) {
  const Skeleton s = weft::capture::testing::stick_figure_skeleton();
  const int b = first_dof(s, true);
  ASSERT_GE(b, 0);
  PoseNoiseConfig c;
  c.spread = {{s.dofs[b].name, 5.0}};  // far wider than the range
  const Motion m = perturbed_motion(rest_motion(s, 500), s, c);
  EXPECT_GE(m.dofs.col(b).minCoeff(), s.dofs[b].lower);
  EXPECT_LE(m.dofs.col(b).maxCoeff(), s.dofs[b].upper);
  EXPECT_EQ(m.dofs.col(b).maxCoeff(), s.dofs[b].upper) << "a spread that wide reaches the limit";
}

TEST(PoseNoise, ErrorsNameTheFileAndTheKey) {
  const Skeleton s = weft::capture::testing::stick_figure_skeleton();
  const char* stages = "stages:\n  warmup: {steps: 4, silhouette: 1}\n";
  const auto parse = [&](const std::string& extra) {
    return parse_training_config(std::string(stages) + extra, "c.yaml");
  };
  expect_error([&] { parse("oracle_pose_noise: {spread: {a: 0.1}}\n"); },
               {"c.yaml", "oracle_pose_noise", "oracle_pose is not true"});
  expect_error([&] { parse("oracle_pose: true\noracle_pose_noise: {seed: 2}\n"); },
               {"c.yaml", "oracle_pose_noise.spread", "missing"});
  expect_error([&] { parse("oracle_pose: true\noracle_pose_noise: {bias: {a: 11}}\n"); },
               {"c.yaml", "oracle_pose_noise.bias.a"});
  expect_error([&] { parse("oracle_pose: true\noracle_pose_noise: {spread: {a: 0.1}, scal: 2}\n"); },
               {"c.yaml", "scal"});
  expect_error([&] { parse("oracle_pose: true\noracle_pose_noise: {spread: {a: -0.1}}\n"); },
               {"c.yaml", "oracle_pose_noise.spread.a"});
  expect_error([&] { parse("oracle_pose: true\noracle_pose_noise: {spread: {a: 0.1}, correlation_frames: 0}\n"); },
               {"c.yaml", "correlation_frames"});
  expect_error([&] { parse("oracle_pose: true\noracle_pose_noise: no_such_noise.yaml\n"); },
               {"c.yaml", "oracle_pose_noise", "no_such_noise.yaml"});
  // A file of its own: read with its own name in its errors.
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "weft_pose_noise_test";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "noise.yaml") << "seed: 3\nspread:\n  not_a_dof: 0.1\n  other: [1]\n";
  expect_error([&] { parse("oracle_pose: true\noracle_pose_noise: " + (dir / "noise.yaml").string() + "\n"); },
               {"noise.yaml", ":4", "oracle_pose_noise.spread.other"});
  std::ofstream(dir / "noise.yaml") << "seed: 3\ncorrelation_frames: 2.5\nspread:\n  not_a_dof: 0.1\n";
  const TrainingConfig c = parse("oracle_pose: true\noracle_pose_noise: " + (dir / "noise.yaml").string() + "\n");
  EXPECT_TRUE(c.oracle_pose_noise.enabled());
  EXPECT_EQ(c.oracle_pose_noise.seed, 3u);
  EXPECT_EQ(c.oracle_pose_noise.correlation_frames, 2.5);
  EXPECT_NE(c.oracle_pose_noise.file.find("noise.yaml"), std::string::npos);
  // A dof the skeleton does not have: named with the file it came from.
  expect_error([&] { perturbed_motion(rest_motion(s, 3), s, c.oracle_pose_noise); },
               {"noise.yaml", "not_a_dof", "does not have"});
  std::filesystem::remove_all(dir);
}
