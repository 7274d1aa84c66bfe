// The differentiable deformation layer against the plain-Eigen reference posing, on the
// real ddc subject (skipped when ../shared/data/ddc is absent).
#include <gtest/gtest.h>

#include <filesystem>

#include "capture/deformation/deformation_layer.h"
#include "capture/character/skeletool_io.h"
#include "graph/autograd.h"
#include "ops/ops.h"
#include "tests/test_requirements.h"

namespace weft::capture {
namespace {

using weft::testing::kDdcDir;

class DeformationLayerDdc : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!std::filesystem::exists(kDdcDir + "/ddc.skeleton")) return;
    character_ = new Character(load_character(std::string(WEFT_SOURCE_DIR) + "/configs/characters/ddc.yaml"));
    motion_ = new Motion(read_motion(kDdcDir + "/walk_0000_0299.motion", character_->skeleton.num_dofs()));
  }
  static void TearDownTestSuite() {
    delete character_;
    delete motion_;
    character_ = nullptr;
    motion_ = nullptr;
  }
  void SetUp() override {
    REQUIRE_DDC_DATA();
  }
  Tensor frames(const std::vector<int>& ids, DType dtype) const {
    const int64_t D = character_->skeleton.num_dofs();
    std::vector<double> v;
    for (int f : ids)
      for (int64_t d = 0; d < D; ++d) v.push_back(motion_->dofs(f, d));
    return Tensor::from_data({static_cast<int64_t>(ids.size()), D}, v, dtype);
  }
  static Character* character_;
  static Motion* motion_;
};
Character* DeformationLayerDdc::character_ = nullptr;
Motion* DeformationLayerDdc::motion_ = nullptr;

TEST_F(DeformationLayerDdc, MatchesTheReferencePosingOnCapturedFrames) {
  const DeformationLayer layer(*character_, DType::F64);
  const std::vector<int> ids = {0, 77, 150, 299};
  const PosedJoints joints = layer.pose(frames(ids, DType::F64));
  const Tensor verts = layer.deform(layer.body(), joints, Tensor(), Tensor());
  double worst_vertex = 0, worst_marker = 0;
  for (size_t i = 0; i < ids.size(); ++i) {
    const PosedCharacter ref = pose_character(*character_, motion_->dofs.row(ids[i]).transpose());
    for (int64_t v = 0; v < ref.body.rows(); ++v)
      for (int a = 0; a < 3; ++a)
        worst_vertex = std::max(worst_vertex, std::abs(verts.at({static_cast<int64_t>(i), v, a}) - ref.body(v, a)));
    for (int64_t m = 0; m < ref.markers.rows(); ++m)
      for (int a = 0; a < 3; ++a)
        worst_marker = std::max(worst_marker, std::abs(joints.markers.at({static_cast<int64_t>(i), m, a}) - ref.markers(m, a)));
  }
  EXPECT_LT(worst_vertex, 1e-6) << "mm";
  EXPECT_LT(worst_marker, 1e-6) << "mm";
}

TEST_F(DeformationLayerDdc, Body25KeypointsMatchTheReference) {
  const DeformationLayer layer(*character_, DType::F64);
  const PosedJoints joints = layer.pose(frames({42}, DType::F64));
  const Tensor k = layer.body25(joints);
  const PosedCharacter ref = pose_character(*character_, motion_->dofs.row(42).transpose());
  int mapped = 0;
  for (int64_t i = 0; i < 25; ++i) {
    if (layer.body25_mask().at({i}) == 0) continue;
    ++mapped;
    for (int a = 0; a < 3; ++a) EXPECT_NEAR(k.at({0, i, a}), ref.body25(i, a), 1e-6) << "keypoint " << i;
  }
  EXPECT_EQ(mapped, 25);  // configs/characters/ddc.yaml maps every BODY_25 keypoint
}

TEST_F(DeformationLayerDdc, IdentityEmbeddedDeformationChangesNothing) {
  const DeformationLayer layer(*character_, DType::F64);
  const PosedJoints joints = layer.pose(frames({10, 20}, DType::F64));
  const int64_t K = layer.body().num_nodes();
  const Tensor plain = layer.deform(layer.body(), joints, Tensor(), Tensor());
  const Tensor with_ed = layer.deform(layer.body(), joints, Tensor::zeros({2, K, 3}, DType::F64),
                                      Tensor::zeros({2, K, 3}, DType::F64));
  const Tensor diff = ops::abs(ops::sub(plain, with_ed));
  EXPECT_LT(ops::max(diff).item(), 1e-9);
}

TEST_F(DeformationLayerDdc, GradientsReachPoseAndGraphParameters) {
  const DeformationLayer layer(*character_, DType::F32);
  Tensor dofs = frames({5, 6}, DType::F32);
  dofs.set_requires_grad();
  const int64_t K = layer.body().num_nodes();
  Generator g(3);
  Tensor angles = Tensor::randn({2, K, 3}, g, DType::F32, 0, 0.01).set_requires_grad();
  Tensor trans = Tensor::randn({2, K, 3}, g, DType::F32, 0, 1.0).set_requires_grad();
  const Tensor v = layer.deform(layer.body(), layer.pose(dofs), angles, trans);
  ops::mean(ops::mul(v, v)).backward();
  for (const Tensor* t : {&dofs, &angles, &trans}) {
    ASSERT_TRUE(t->grad().defined());
    EXPECT_GT(ops::max(ops::abs(t->grad())).item(), 0.0);
  }
}

}  // namespace
}  // namespace weft::capture
