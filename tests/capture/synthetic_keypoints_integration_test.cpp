// Synthetic keypoints and the studio rig on the default character (Debian's MakeHuman
// body): the rig frames the rendered body in every view, and the occlusion rule hides the
// joints a person would call hidden (the far side in a side view, the face from behind)
// while keeping those facing the camera.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/imgproc.hpp>

#include "tests/capture/test_files.h"
#include "capture/character/default_character.h"
#include "capture/render/renderer.h"
#include "capture/studio/studio_rig.h"
#include "capture/studio/synthetic_keypoints.h"

using namespace weft;
using namespace weft::capture;

using weft::capture::testing::kHuman;
using weft::capture::testing::repo_file;

namespace {



struct Scene {
  DefaultCharacter built;
  PosedCharacter posed;
  std::vector<Camera> cameras;  // the default 8-view rig: cam00 in front, cam02 at the left, …
  std::vector<RenderResult> renders;
};

// Built once per test program (the character takes about a second).
const Scene& scene() {
  static const Scene s = [] {
    DefaultCharacterConfig cfg;
    cfg.garment = GarmentType::none;
    Scene out{make_default_character(cfg), {}, studio_rig({}), {}};
    out.posed = pose_character(out.built.character, out.built.character.rest_dofs);
    for (const Camera& c : out.cameras) {
      RenderMesh body;
      body.mesh = &out.built.character.body.mesh;
      body.vertices = &out.posed.body;
      out.renders.push_back(render(c, {body}));
    }
    return out;
  }();
  return s;
}

std::array<KeypointVisibility, kBody25Count> seen_by(int view) {
  const Scene& s = scene();
  return keypoint_visibility(s.cameras[view], s.posed.body25, s.renders[view].depth, KeypointNoiseConfig{});
}

void expect(const std::array<KeypointVisibility, kBody25Count>& seen, std::initializer_list<const char*> names,
            KeypointVisibility expected, const char* view) {
  for (const char* name : names) {
    const int k = body25_index(name);
    ASSERT_GE(k, 0) << name;
    EXPECT_EQ(seen[k], expected) << view << ": " << name;
  }
}

}  // namespace

TEST(SyntheticKeypointsOnTheDefaultCharacter, RigFramesTheWholeBodyInEveryView) {
  REQUIRE_HUMAN();
  const Scene& s = scene();
  for (size_t v = 0; v < s.cameras.size(); ++v) {
    const cv::Rect box = cv::boundingRect(s.renders[v].mask);
    const Camera& c = s.cameras[v];
    EXPECT_GT(box.height, c.height / 2) << c.name;  // the subject fills a good part of the view
    EXPECT_GE(box.x, c.width / 20) << c.name;        // and keeps a 5% margin on every side
    EXPECT_GE(box.y, c.height / 20) << c.name;
    EXPECT_LE(box.x + box.width, c.width - c.width / 20) << c.name;
    EXPECT_LE(box.y + box.height, c.height - c.height / 20) << c.name;
  }
}

TEST(SyntheticKeypointsOnTheDefaultCharacter, FrontViewSeesEveryMappedKeypoint) {
  REQUIRE_HUMAN();
  const Scene& s = scene();
  const auto seen = seen_by(0);
  for (int k = 0; k < kBody25Count; ++k) {
    if (!s.posed.body25.row(k).allFinite()) continue;
    EXPECT_EQ(seen[k], KeypointVisibility::visible) << kBody25Names[k];
  }
}

TEST(SyntheticKeypointsOnTheDefaultCharacter, SideViewsHideTheFarSide) {
  REQUIRE_HUMAN();
  // cam02 stands at +x, the character's left; cam06 at −x, its right.
  const auto left = seen_by(2), right = seen_by(6);
  expect(left, {"LShoulder", "LElbow", "LWrist", "LHip", "LKnee", "LAnkle"}, KeypointVisibility::visible, "cam02");
  expect(left, {"RShoulder", "RElbow", "RHip", "RKnee", "RAnkle"}, KeypointVisibility::occluded, "cam02");
  expect(right, {"RShoulder", "RElbow", "RWrist", "RHip", "RKnee", "RAnkle"}, KeypointVisibility::visible, "cam06");
  expect(right, {"LShoulder", "LElbow", "LHip", "LKnee", "LAnkle"}, KeypointVisibility::occluded, "cam06");
}

TEST(SyntheticKeypointsOnTheDefaultCharacter, BackViewHidesTheFaceButNotTheLimbs) {
  REQUIRE_HUMAN();
  const auto back = seen_by(4);  // azimuth 180: behind the character
  expect(back, {"Nose", "REye", "LEye"}, KeypointVisibility::occluded, "cam04");
  expect(back, {"Neck", "RShoulder", "LShoulder", "RElbow", "LElbow", "RWrist", "LWrist", "RHip", "LHip", "RKnee",
                "LKnee", "RAnkle", "LAnkle", "RHeel", "LHeel"},
         KeypointVisibility::visible, "cam04");
}

TEST(SyntheticKeypointsOnTheDefaultCharacter, NoisyKeypointsStayNearTheTruthWithLowerConfidenceWhenHidden) {
  REQUIRE_HUMAN();
  const Scene& s = scene();
  const KeypointNoiseConfig cfg;
  for (size_t v = 0; v < s.cameras.size(); ++v) {
    const auto seen = seen_by(static_cast<int>(v));
    const Body25 truth = project_keypoints(s.cameras[v], s.posed.body25);
    const Body25 k = synthesize_keypoints(s.cameras[v], s.posed.body25, s.renders[v].depth, cfg, mix_seed(5, v, 0));
    for (int i = 0; i < kBody25Count; ++i) {
      if (k(i, 2) == 0) continue;  // dropped or unmapped
      EXPECT_LT((k.row(i).head<2>() - truth.row(i).head<2>()).norm(), 6 * cfg.noise_px) << v << " " << i;
      const double expected =
          seen[i] == KeypointVisibility::occluded ? cfg.occluded_confidence : cfg.visible_confidence;
      EXPECT_NEAR(k(i, 2), expected, cfg.confidence_jitter + 1e-12) << v << " " << kBody25Names[i];
    }
  }
}
