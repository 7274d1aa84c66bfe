// PoseNet's outputs as dofs (capture/model/pose_dofs.h): limited dofs stay inside
// their limits for any output, an output of 0 is the rest pose (also when the rest is not
// the middle of the range), the slope at 0 is dof_scale as for unlimited dofs, the
// inverse gives the outputs of a pose back, gradients flow (float64 central differences),
// and a Skeletool skeleton's own limits are respected the same way.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "capture/character/body_skeleton_fit.h"
#include "capture/character/skeletool_io.h"
#include "capture/model/pose_dofs.h"
#include "graph/gradcheck.h"
#include "tests/capture/stick_figure.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using Eigen::Vector3d;
using weft::capture::testing::stick_figure_skeleton;

namespace {


// Every dof but the root's six.
std::vector<int> non_root(const Skeleton& s) {
  std::vector<int> f;
  for (int d = 0; d < s.num_dofs(); ++d)
    if (!s.dofs[d].name.starts_with("hips_")) f.push_back(d);
  return f;
}

Eigen::MatrixXd values(const Tensor& t) {
  const std::vector<double> v = t.to_vector();
  Eigen::MatrixXd m(t.size(0), t.size(1));
  for (int64_t i = 0; i < t.size(0); ++i)
    for (int64_t j = 0; j < t.size(1); ++j) m(i, j) = v[i * t.size(1) + j];
  return m;
}

constexpr double kScale = 0.1;  // NetworkConfig::dof_scale's default

}  // namespace

TEST(PoseDofs, LimitedDofsStayInsideTheirLimitsForExtremeOutputs) {
  const Skeleton s = stick_figure_skeleton();
  const std::vector<int> free = non_root(s);
  Eigen::VectorXd rest = Eigen::VectorXd::Zero(s.num_dofs());
  const PoseDofs map(s, rest, free, kScale);
  EXPECT_GE(map.limited_count(), 40);  // hips, spine, neck, head, ankles, clavicles, wrists, hinges
  const int64_t F = static_cast<int64_t>(free.size());
  // Rows: ±1e4, ±30, and random outputs of spread 100.
  Generator gen(7);
  const Tensor random = Tensor::randn({4, F}, gen, DType::F32);
  std::vector<double> x = random.to_vector();
  for (double& v : x) v *= 100;
  for (double v : {1e4, -1e4, 30.0, -30.0, 0.0})
    for (int64_t i = 0; i < F; ++i) x.push_back(v);
  const int64_t B = static_cast<int64_t>(x.size()) / F;
  const Eigen::MatrixXd q = values(map.dofs(Tensor::from_data({B, F}, x, DType::F32)));
  ASSERT_TRUE(q.allFinite());
  for (int64_t b = 0; b < B; ++b)
    for (int i = 0; i < F; ++i) {
      const Dof& d = s.dofs[free[i]];
      const double v = q(b, free[i]);
      if (d.limited) {
        EXPECT_GE(v, d.lower - 1e-5) << d.name << " row " << b;
        EXPECT_LE(v, d.upper + 1e-5) << d.name << " row " << b;
      } else {
        EXPECT_NEAR(v, kScale * x[b * F + i], 1e-3 * std::max(1.0, std::abs(v))) << d.name;  // unchanged
      }
    }
  // Saturated outputs reach the limits themselves.
  const int hip = s.dof_index("l_hip_ry");
  EXPECT_NEAR(q(B - 5, hip), s.dofs[hip].upper, 1e-5);
  EXPECT_NEAR(q(B - 4, hip), s.dofs[hip].lower, 1e-5);
  // The root chain stays at rest.
  for (int d = 0; d < 6; ++d) EXPECT_EQ(q.col(d).cwiseAbs().maxCoeff(), 0.0);
}

TEST(PoseDofs, ZeroIsTheRestPoseWithTheUnlimitedSlope) {
  const Skeleton s = stick_figure_skeleton();
  const std::vector<int> free = non_root(s);
  // A rest pose off the middle of the ranges: knees bent 0.3 rad in [−0.05, 2.6], a
  // hip flexed to −60° in [−130°, 40°].
  Eigen::VectorXd rest = Eigen::VectorXd::Zero(s.num_dofs());
  rest(s.dof_index("l_knee_rx")) = 0.3;
  rest(s.dof_index("l_hip_rx")) = -60 * std::numbers::pi / 180;
  rest(s.dof_index("l_shoulder_rz")) = 0.5;  // unlimited
  const PoseDofs map(s, rest, free, kScale, DType::F64);
  const int64_t F = static_cast<int64_t>(free.size());
  const double h = 1e-6;
  const Eigen::MatrixXd q = values(map.dofs(Tensor::from_data(
      {3, F}, [&] {
        std::vector<double> v(3 * F, 0.0);
        for (int64_t i = 0; i < F; ++i) v[F + i] = h, v[2 * F + i] = -h;
        return v;
      }(), DType::F64)));
  for (int d = 0; d < s.num_dofs(); ++d) EXPECT_NEAR(q(0, d), rest(d), 1e-12) << s.dofs[d].name;
  for (int d : free) EXPECT_NEAR((q(1, d) - q(2, d)) / (2 * h), kScale, 1e-6) << s.dofs[d].name;
  // The inverse: outputs for a pose give the pose back, inside the limits.
  Eigen::VectorXd pose = rest;
  pose(s.dof_index("l_hip_ry")) = 0.4;
  pose(s.dof_index("spine_rx")) = -0.2;
  pose(s.dof_index("l_knee_rx")) = 2.0;
  pose(s.dof_index("l_shoulder_rx")) = -2.5;
  const Eigen::VectorXd out = map.outputs_for(pose);
  const Eigen::MatrixXd back = values(map.dofs(Tensor::from_data({1, F}, std::vector<double>(out.data(), out.data() + F), DType::F64)));
  EXPECT_LT((back.row(0).transpose() - pose).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(PoseDofs, GradientsFlowAndMatchFiniteDifferences) {
  const Skeleton s = stick_figure_skeleton();
  const std::vector<int> free = non_root(s);
  const PoseDofs map(s, Eigen::VectorXd::Zero(s.num_dofs()), free, kScale, DType::F64);
  const int64_t F = static_cast<int64_t>(free.size());
  GradcheckCase c;
  c.op = "sigmoid";
  c.name = "PoseDofs [3,F], outputs of spread 5";
  c.make_inputs = [F](Generator& gen) {
    std::vector<double> v = Tensor::randn({3, F}, gen, DType::F64).to_vector();
    for (double& e : v) e *= 5;
    return std::vector<Tensor>{Tensor::from_data({3, F}, v, DType::F64)};
  };
  c.function = [&map](const std::vector<Tensor>& in) { return map.dofs(in[0]); };
  const GradcheckResult r = gradcheck(c);
  EXPECT_TRUE(r.passed) << r.message;
  // In float32 as PoseNet runs it: every free dof gets a gradient at moderate outputs.
  const PoseDofs map32(s, Eigen::VectorXd::Zero(s.num_dofs()), free, kScale);
  Tensor x = Tensor::full({2, F}, 0.7, DType::F32);
  x.set_requires_grad(true);
  map32.dofs(x).backward(Tensor::ones({2, s.num_dofs()}, DType::F32));
  const std::vector<double> g = x.grad().to_vector();
  for (int64_t i = 0; i < F; ++i) EXPECT_GT(g[i], 1e-4) << s.dofs[free[i]].name;
}

TEST(PoseDofs, SkeletoolLimitsAreRespected) {
  // The small Skeletool skeleton of the tests: `bend` limited to [−1, 1], the others free.
  const Skeleton s = parse_skeleton(weft::capture::testing::small_skeleton_text(), "small.skeleton");
  ASSERT_TRUE(s.dofs[1].limited);
  Eigen::VectorXd rest(3);
  rest << 0.0, 0.6, 0.2;  // bend rests at 0.6 in [−1, 1]: off the middle
  const PoseDofs map(s, rest, {1, 2}, kScale);
  const Eigen::MatrixXd q = values(map.dofs(Tensor::from_data({3, 2}, {1e3, 1e3, -1e3, -1e3, 0, 0}, DType::F32)));
  EXPECT_NEAR(q(0, 1), 1.0, 1e-6);
  EXPECT_NEAR(q(1, 1), -1.0, 1e-6);
  EXPECT_NEAR(q(2, 1), 0.6, 1e-6);
  EXPECT_NEAR(q(0, 2), 0.2 + kScale * 1e3, 1e-2);  // the free one is linear
  EXPECT_EQ(q(0, 0), 0.0);                          // not regressed: at rest
}
