// Forward semantics of the geometry ops: what each computes, checked against direct
// constructions with Eigen.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "ops/geometry.h"
#include "ops/ops.h"

namespace weft {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

Tensor rigid_tensor(const std::vector<Eigen::Isometry3d>& transforms) {
  Tensor t = Tensor::empty({1, static_cast<int64_t>(transforms.size()), 3, 4}, DType::F64);
  for (size_t j = 0; j < transforms.size(); ++j)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) t.data<double>()[j * 12 + r * 4 + c] = transforms[j].matrix()(r, c);
  return t;
}

Vector3d row(const Tensor& t, int64_t i) {
  return {t.data<double>()[3 * i], t.data<double>()[3 * i + 1], t.data<double>()[3 * i + 2]};
}

TEST(Geometry, EulerAnglesComposeZYX) {
  const double a = 0.3, b = -1.1, c = 2.0;
  Tensor R = ops::euler_to_rotation(Tensor::from_data({3}, std::vector<double>{a, b, c}, DType::F64));
  const Matrix3d expect = (Eigen::AngleAxisd(c, Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(b, Vector3d::UnitY()) *
                           Eigen::AngleAxisd(a, Vector3d::UnitX())).toRotationMatrix();
  ASSERT_EQ(R.shape(), (Shape{3, 3}));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) EXPECT_NEAR(R.at({i, j}), expect(i, j), 1e-12);
}

TEST(Geometry, DualQuaternionSkinningOfOneJointIsItsRigidMotion) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.rotate(Eigen::AngleAxisd(2.5, Vector3d(1, 2, -1).normalized()));
  T.pretranslate(Vector3d(0.4, -1.0, 2.0));
  Tensor dq = ops::rigid_to_dual_quaternion(rigid_tensor({T}));
  Tensor verts = Tensor::from_data({2, 3}, std::vector<double>{1, 2, 3, -0.5, 0.1, 0.7}, DType::F64);
  Tensor out = ops::dual_quaternion_skinning(verts, dq, Tensor::from_indices({2, 1}, {0, 0}),
                                             Tensor::ones({2, 1}, DType::F64));
  for (int64_t v = 0; v < 2; ++v)
    EXPECT_LT((row(out, v) - T * row(verts, v)).norm(), 1e-12);
}

TEST(Geometry, DualQuaternionSkinningIgnoresTheSignOfAQuaternion) {
  // q and −q are one rotation: with the antipodality fix the blend must not change.
  Eigen::Isometry3d A = Eigen::Isometry3d::Identity(), B = Eigen::Isometry3d::Identity();
  A.rotate(Eigen::AngleAxisd(0.4, Vector3d::UnitY()));
  B.rotate(Eigen::AngleAxisd(0.9, Vector3d::UnitY()));
  B.pretranslate(Vector3d(0, 0.2, 0));
  Tensor dq = ops::rigid_to_dual_quaternion(rigid_tensor({A, B})).clone();
  Tensor verts = Tensor::from_data({1, 3}, std::vector<double>{0.3, 1.0, -0.2}, DType::F64);
  Tensor index = Tensor::from_indices({1, 2}, {0, 1});
  Tensor weights = Tensor::from_data({1, 2}, std::vector<double>{0.5, 0.5}, DType::F64);
  Tensor before = ops::dual_quaternion_skinning(verts, dq, index, weights);
  for (int k = 8; k < 16; ++k) dq.data<double>()[k] *= -1;
  Tensor after = ops::dual_quaternion_skinning(verts, dq, index, weights);
  EXPECT_LT((row(before, 0) - row(after, 0)).norm(), 1e-12);
  // Halfway between two rotations about y: the blend is the rotation by 0.65 rad.
  Eigen::Isometry3d mid = Eigen::Isometry3d::Identity();
  mid.rotate(Eigen::AngleAxisd(0.65, Vector3d::UnitY()));
  EXPECT_NEAR(row(before, 0).norm(), (mid * row(verts, 0) + Vector3d(0, 0.1, 0)).norm(), 1e-3);
}

TEST(Geometry, LinearBlendAndDualQuaternionSkinningAgreeForSmallRotations) {
  Eigen::Isometry3d A = Eigen::Isometry3d::Identity(), B = Eigen::Isometry3d::Identity();
  A.rotate(Eigen::AngleAxisd(0.01, Vector3d::UnitX()));
  B.rotate(Eigen::AngleAxisd(-0.01, Vector3d::UnitZ()));
  B.pretranslate(Vector3d(0.01, 0, 0));
  Tensor tf = rigid_tensor({A, B});
  Tensor verts = Tensor::from_data({2, 3}, std::vector<double>{0.1, 0.2, 0.3, -0.3, 0.0, 0.2}, DType::F64);
  Tensor index = Tensor::from_indices({2, 2}, {0, 1, 1, 0});
  Tensor weights = Tensor::from_data({2, 2}, std::vector<double>{0.3, 0.7, 0.6, 0.4}, DType::F64);
  Tensor lbs = ops::linear_blend_skinning(verts, tf, index, weights);
  Tensor dqs = ops::dual_quaternion_skinning(verts, ops::rigid_to_dual_quaternion(tf), index, weights);
  for (int64_t v = 0; v < 2; ++v) EXPECT_LT((row(lbs, v) - row(dqs, v)).norm(), 1e-4);
}

TEST(Geometry, EmbeddedDeformationWithOneNodeIsARigidMotionAboutIt) {
  const Matrix3d R = Eigen::AngleAxisd(1.2, Vector3d(0, 1, 1).normalized()).toRotationMatrix();
  const Vector3d g(0.5, 0.5, 0), t(0.1, 0.2, 0.3);
  Tensor rest = Tensor::from_data({2, 3}, std::vector<double>{1, 0, 0, 0, 2, 1}, DType::F64);
  Tensor nodes = Tensor::from_data({1, 3}, std::vector<double>{g.x(), g.y(), g.z()}, DType::F64);
  Tensor rot = Tensor::empty({1, 1, 3, 3}, DType::F64);
  for (int i = 0; i < 9; ++i) rot.data<double>()[i] = R(i / 3, i % 3);
  Tensor trans = Tensor::from_data({1, 1, 3}, std::vector<double>{t.x(), t.y(), t.z()}, DType::F64);
  Tensor out = ops::embedded_deformation(rest, nodes, rot, trans, Tensor::from_indices({2, 1}, {0, 0}),
                                         Tensor::ones({2, 1}, DType::F64));
  for (int64_t v = 0; v < 2; ++v)
    EXPECT_LT((row(out, v) - (R * (row(rest, v) - g) + g + t)).norm(), 1e-12);
}

TEST(Geometry, ProjectionMatchesThePinholeModel) {
  ops::PinholeCamera cam;
  cam.fx = 1000, cam.fy = 900, cam.cx = 320, cam.cy = 240;
  cam.t[2] = 2.0;
  Tensor p = Tensor::from_data({1, 3}, std::vector<double>{0.2, -0.1, 0.0}, DType::F64);
  Tensor px = ops::project_points(p, cam);
  EXPECT_NEAR(px.at({0, 0}), 1000 * 0.1 + 320, 1e-9);
  EXPECT_NEAR(px.at({0, 1}), 900 * -0.05 + 240, 1e-9);
  cam.k1 = 0.1;  // radial distortion pushes points outwards by 1 + k1 r²
  Tensor pd = ops::project_points(p, cam);
  const double r2 = 0.1 * 0.1 + 0.05 * 0.05;
  EXPECT_NEAR(pd.at({0, 0}), 1000 * 0.1 * (1 + 0.1 * r2) + 320, 1e-9);
}

TEST(Geometry, BadInputsNameTheOpAndShapes) {
  Tensor verts = Tensor::zeros({4, 3}, DType::F64);
  Tensor tf = Tensor::zeros({1, 2, 3, 4}, DType::F64);
  try {
    ops::linear_blend_skinning(verts, tf, Tensor::from_indices({4, 1}, {0, 1, 2, 0}),
                               Tensor::ones({4, 1}, DType::F64));
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("linear_blend_skinning: index 2"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW(ops::linear_blend_skinning(Tensor::zeros({4, 2}, DType::F64), tf,
                                          Tensor::from_indices({4, 1}, {0, 0, 0, 0}),
                                          Tensor::ones({4, 1}, DType::F64)),
               Error);
  EXPECT_THROW(ops::euler_to_rotation(Tensor::zeros({2, 2})), Error);
  ops::PinholeCamera cam;  // at the origin looking down +z: z = 0 is on the camera plane
  EXPECT_THROW(ops::project_points(Tensor::zeros({1, 3}), cam), Error);
}

}  // namespace
}  // namespace weft
