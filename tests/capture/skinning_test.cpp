#include <gtest/gtest.h>

#include <random>

#include "capture/character/automatic_weights.h"
#include "capture/character/skinning.h"

using namespace weft;
using namespace weft::capture;

namespace {

Eigen::Isometry3d rigid(const Eigen::Vector3d& axis, double angle, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  T.translation() = t;
  return T;
}

struct Fixture {
  Vertices V;
  SkinningWeights w;
};

Fixture random_fixture(int n, int joints, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), pos(0.05, 1);
  Fixture f;
  f.V.resize(n, 3);
  for (int i = 0; i < n; ++i) f.V.row(i) << u(rng), u(rng), u(rng);
  f.w.num_joints = joints;
  f.w.vertices.resize(n);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < joints; ++j)
      if (j == i % joints || u(rng) > 0.3) f.w.vertices[i].push_back({j, pos(rng)});
  normalize_weights(f.w, "random");
  return f;
}

TEST(Skinning, IdentityTransformsKeepTheRestPose) {
  const Fixture f = random_fixture(50, 4, 1);
  const Transforms I(4, Eigen::Isometry3d::Identity());
  EXPECT_NEAR((linear_blend_skinning(f.V, f.w, I) - f.V).cwiseAbs().maxCoeff(), 0, 1e-14);
  EXPECT_NEAR((dual_quaternion_skinning(f.V, f.w, I) - f.V).cwiseAbs().maxCoeff(), 0, 1e-14);
}

TEST(Skinning, SingleBoneIsTheRigidTransformForBoth) {
  Fixture f = random_fixture(20, 3, 2);
  for (auto& v : f.w.vertices) v = {{1, 1.0}};
  const Transforms S{Eigen::Isometry3d::Identity(), rigid({1, 2, 3}, 2.5, {0.3, -1, 2}), Eigen::Isometry3d::Identity()};
  const Vertices expected = (f.V * S[1].linear().transpose()).rowwise() + S[1].translation().transpose();
  EXPECT_NEAR((dual_quaternion_skinning(f.V, f.w, S) - expected).cwiseAbs().maxCoeff(), 0, 1e-12);
  EXPECT_NEAR((linear_blend_skinning(f.V, f.w, S) - expected).cwiseAbs().maxCoeff(), 0, 1e-12);
}

TEST(Skinning, LinearBlendAndDualQuaternionAgreeForSmallRotations) {
  const Fixture f = random_fixture(200, 4, 3);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  for (double angle : {1e-2, 1e-3}) {
    Transforms S;
    // Small motions: rotations by `angle`, translations of the same order (unit-size mesh).
    for (int j = 0; j < 4; ++j) S.push_back(rigid({u(rng), u(rng), u(rng)}, angle, {angle * u(rng), angle * u(rng), angle * u(rng)}));
    const double diff = (linear_blend_skinning(f.V, f.w, S) - dual_quaternion_skinning(f.V, f.w, S)).cwiseAbs().maxCoeff();
    // Both are exact to first order in the motion; they differ at second order.
    EXPECT_LT(diff, 5 * angle * angle) << "angle " << angle;
    EXPECT_GT((linear_blend_skinning(f.V, f.w, S) - f.V).cwiseAbs().maxCoeff(), 0.1 * angle);  // it did move
  }
  // And visibly differ for large ones (the test can fail).
  Transforms big{rigid({0, 0, 1}, 1.5, {0, 0, 0}), rigid({0, 0, 1}, -1.5, {0, 0, 0}), Eigen::Isometry3d::Identity(),
                 Eigen::Isometry3d::Identity()};
  EXPECT_GT((linear_blend_skinning(f.V, f.w, big) - dual_quaternion_skinning(f.V, f.w, big)).cwiseAbs().maxCoeff(), 1e-2);
}

TEST(Skinning, DualQuaternionAlignsAntipodalQuaternions) {
  // Bones rotated by +170° and −170° about z, given as quaternions with a negative dot
  // product. Half-half blending must give the 180° rotation between them, not the
  // near-identity that a sign-blind blend (q1 + q2) produces.
  auto dq = [](double degrees) {
    DualQuaternion d;
    d.real = Eigen::Quaterniond(Eigen::AngleAxisd(degrees * M_PI / 180, Eigen::Vector3d::UnitZ()));
    d.dual.coeffs().setZero();
    return d;
  };
  const std::vector<DualQuaternion> q{dq(170), dq(-170)};
  ASSERT_LT(q[0].real.coeffs().dot(q[1].real.coeffs()), 0);
  Vertices V(1, 3);
  V << 1, 0, 0.5;
  for (int first : {0, 1}) {  // either bone may be the reference
    SkinningWeights w;
    w.num_joints = 2;
    w.vertices = {{{first, 0.5}, {1 - first, 0.5}}};
    const Vertices out = dual_quaternion_skinning(V, w, q);
    EXPECT_NEAR((out.row(0) - Eigen::RowVector3d(-1, 0, 0.5)).norm(), 0, 1e-12) << "reference bone " << first;
  }
  // Negating one joint's dual quaternion (the same rigid transform) changes nothing.
  const Fixture f = random_fixture(50, 2, 5);
  const Transforms A{rigid({0, 1, 0}, 0.6, {1, 0, 0}), rigid({1, 1, 0}, 2.9, {0, 0.5, 0})};
  std::vector<DualQuaternion> qa{to_dual_quaternion(A[0]), to_dual_quaternion(A[1])};
  const Vertices ref = dual_quaternion_skinning(f.V, f.w, A);
  qa[1].real.coeffs() *= -1;
  qa[1].dual.coeffs() *= -1;
  EXPECT_NEAR((dual_quaternion_skinning(f.V, f.w, qa) - ref).cwiseAbs().maxCoeff(), 0, 1e-12);
}

TEST(Skinning, DenseCsrAndPaddedViewsAgree) {
  const Fixture f = random_fixture(30, 5, 6);
  const Eigen::MatrixXd D = f.w.dense();
  const auto c = f.w.csr();
  Eigen::Matrix<int, -1, -1, Eigen::RowMajor> J;
  Eigen::Matrix<double, -1, -1, Eigen::RowMajor> W;
  f.w.padded(J, W);
  for (int v = 0; v < f.w.num_vertices(); ++v) {
    double sum = 0;
    for (int k = c.offsets[v]; k < c.offsets[v + 1]; ++k) {
      EXPECT_DOUBLE_EQ(D(v, c.joints[k]), c.weights[k]);
      sum += c.weights[k];
    }
    EXPECT_NEAR(sum, 1, 1e-12);
    EXPECT_NEAR(W.row(v).sum(), 1, 1e-12);
  }
}

TEST(AutomaticWeights, BoneDistanceWeightsFollowTheNearestBone) {
  Skeleton s;
  s.joints.push_back({"root", JointType::revolute, -1, Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ(), 1});
  s.joints.push_back({"elbow", JointType::revolute, 0, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::UnitZ(), 1});
  s.joints.push_back({"hand", JointType::revolute, 1, Eigen::Vector3d(1, 0, 0), Eigen::Vector3d::UnitZ(), 1});
  s.dofs.push_back({"a", {{0, 1}}, false, 0, 0});
  s.dofs.push_back({"b", {{1, 1}}, false, 0, 0});
  const Transforms bind = forward_kinematics(s, Eigen::Vector2d::Zero());
  Vertices V(3, 3);
  V << 0.2, 0.1, 0, 1.8, 0.1, 0, 1.0, 0.1, 0;
  const SkinningWeights w = bone_distance_weights(V, s, bind, {2, 4.0, 1e-3});
  EXPECT_EQ(w.vertices[0][0].joint, 0);  // upper arm segment, driven by root
  EXPECT_GT(w.vertices[0][0].weight, 0.99);
  EXPECT_EQ(w.vertices[1][0].joint, 1);  // forearm segment, driven by the elbow
  EXPECT_NEAR(w.vertices[2][0].weight, 0.5, 1e-9);  // equidistant at the elbow
  for (const auto& v : w.vertices) {
    double sum = 0;
    for (const auto& i : v) sum += i.weight;
    EXPECT_NEAR(sum, 1, 1e-12);
  }
}

}  // namespace
