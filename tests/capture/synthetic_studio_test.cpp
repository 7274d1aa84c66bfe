// `weft synth` configs: what a user gets for a typo, a wrong type or a missing file.
#include <gtest/gtest.h>

#include "capture/studio/synthetic_studio.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::expect_error;
using weft::capture::testing::ScratchDir;

using weft::capture::testing::kHuman;
using weft::capture::testing::repo_file;

namespace {


std::string base(const std::string& extra = "", const std::string& motion_extra = "") {
  return "name: t\n"
         "character: " + repo_file("configs/characters/makehuman_skirt_coarse.yaml") + "\n" +
         "motion:\n"
         "  procedural: " + repo_file("configs/motions/walk_in_place.yaml") + "\n" +
         "  mapping: " + repo_file("configs/retarget/humanoid_to_makehuman.yaml") + "\n" + motion_extra + extra;
}

// `motions:` lists clips, each a motion section; their frames follow one another.
std::string clip(const char* motion, const std::string& extra = "") {
  return "  - procedural: " + repo_file(std::string("configs/motions/") + motion + ".yaml") + "\n" +
         "    mapping: " + repo_file("configs/retarget/humanoid_to_makehuman.yaml") + "\n" + extra;
}
std::string with_clips(const std::string& clips, const std::string& extra = "") {
  return "name: t\ncharacter: " + repo_file("configs/characters/makehuman_skirt_coarse.yaml") + "\nmotions:\n" +
         clips + extra;
}

}  // namespace

TEST(SynthConfig, ShippedConfigsLoad) {
  for (const char* name : {"tiny", "training", "in_the_wild", "training_set"}) {
    const SynthConfig c = load_synth_config(repo_file(std::string("configs/synth/") + name + ".yaml"));
    EXPECT_EQ(c.name, name);
    EXPECT_GT(c.frames(), 0);
  }
  // The training set: every motion not kept for testing, ≥ 1,500 frames at 30 fps, 8 views.
  const SynthConfig set = load_synth_config(repo_file("configs/synth/training_set.yaml"));
  ASSERT_EQ(set.motions.size(), 4u);
  EXPECT_TRUE(set.motion_list);
  EXPECT_GE(set.frames(), 1500);
  EXPECT_EQ(set.fps(), 30);
  EXPECT_EQ(set.cameras.studio.views, 8);
  EXPECT_EQ(set.cameras.studio.width, 256);
  EXPECT_EQ(set.motions[3].bvh, "/usr/share/assimp/models/BVH/01_01.bvh");
  const SynthConfig wild = load_synth_config(repo_file("configs/synth/in_the_wild.yaml"));
  EXPECT_EQ(wild.cameras.kind, CameraRigKind::wild);
  EXPECT_EQ(wild.render.background, BackgroundKind::clutter);
  // Poses that cover the space: ≥ 5,000 frames, 8 views, the unseen motion left out, the
  // held-out stretch from the middle of each clip, lights drawn per clip.
  const SynthConfig random = load_synth_config(repo_file("configs/synth/training_set_random_poses.yaml"));
  EXPECT_GE(random.frames(), 5000);
  EXPECT_EQ(random.cameras.studio.views, 8);
  for (const SynthMotionConfig& m : random.motions) EXPECT_EQ(m.bvh.find("01_03"), std::string::npos);
  EXPECT_DOUBLE_EQ(random.split_place, 0.5);
  EXPECT_EQ(random.render.lighting.lights, 2);
  // Over photographs: Debian's mate-backgrounds (scripts/setup.sh).
  REQUIRE_DEBIAN_FILE("/usr/share/backgrounds/mate/nature", "mate-backgrounds");
  const SynthConfig photos = load_synth_config(repo_file("configs/synth/in_the_wild_photos.yaml"));
  EXPECT_EQ(photos.render.background, BackgroundKind::image);
  EXPECT_GE(photos.render.photos.size(), 10u);
  EXPECT_EQ(photos.render.lighting.lights, 2);
  EXPECT_NE(photos.motions[0].bvh.find("01_03"), std::string::npos);  // the unseen motion
  const SynthConfig tiny = load_synth_config(repo_file("configs/synth/tiny.yaml"));
  EXPECT_EQ(tiny.cameras.kind, CameraRigKind::studio);
  EXPECT_EQ(tiny.cameras.studio.views, 8);
  EXPECT_EQ(tiny.cameras.studio.width, 256);
}

TEST(SynthConfig, DefaultsAndOverrides) {
  const SynthConfig c = parse_synth_config(
      base("seed: 42\nsimulation: {substeps: 3, material: {density: 0.3}}\ncameras: {views: 18, height: 320}\n"
           "keypoints: {noise_px: 0.5}\nsplits: {val: 0.2, test: 0}\n",
           "  frames: 20\n  start: 2\n"),
      "c.yaml");
  EXPECT_EQ(c.seed, 42u);
  ASSERT_EQ(c.motions.size(), 1u);
  EXPECT_FALSE(c.motion_list);
  EXPECT_EQ(c.frames(), 20);
  EXPECT_EQ(c.motions[0].frames, 20);
  EXPECT_DOUBLE_EQ(c.motions[0].start_s, 2);
  EXPECT_LT(c.motions[0].in_place_s, 0);  // the motion's own path
  EXPECT_EQ(c.simulation.substeps, 3);
  EXPECT_DOUBLE_EQ(c.simulation.material.density, 0.3);
  EXPECT_EQ(c.cameras.studio.views, 18);
  EXPECT_EQ(c.cameras.studio.height, 320);
  EXPECT_EQ(c.cameras.studio.width, 512);
  EXPECT_DOUBLE_EQ(c.keypoints.noise_px, 0.5);
  EXPECT_DOUBLE_EQ(c.val_fraction, 0.2);
  EXPECT_DOUBLE_EQ(c.test_fraction, 0);
}

TEST(SynthConfig, ErrorsNameTheFileAndKey) {
  expect_error([] { parse_synth_config(base("colour: red\n"), "bad.yaml"); }, {"bad.yaml", "colour"});
  expect_error([] { parse_synth_config(base("cameras: {views: many}\n"), "bad.yaml"); }, {"bad.yaml", "cameras.views"});
  expect_error([] { parse_synth_config(base("cameras: {rig: drone}\n"), "bad.yaml"); }, {"cameras.rig", "drone"});
  expect_error([] { parse_synth_config(base("cameras: {rig: wild, views: 3}\n"), "bad.yaml"); }, {"views"});
  expect_error([] { parse_synth_config(base("simulation: {material: {poisson_ratio: 0.5}}\n"), "bad.yaml"); },
               {"bad.yaml", "poisson_ratio"});
  expect_error([] { parse_synth_config(base("keypoints: {dropout: 1.5}\n"), "bad.yaml"); }, {"keypoints.dropout"});
  // The message names the key once and the range as written: "cameras.arcdeg", "[0, 1]".
  expect_error([] { parse_synth_config(base("cameras: {rig: wild, arcdeg: 60}\n"), "bad.yaml"); },
               {"bad.yaml", " cameras.arcdeg: unknown key", "arc_deg"});
  expect_error([] { parse_synth_config(base("keypoints: {dropout: 1.5}\n"), "bad.yaml"); },
               {"keypoints.dropout: expected a number in [0, 1], found 1.5"});
  expect_error([] { parse_synth_config(base("render: {background: blue}\n"), "bad.yaml"); }, {"render.background"});
  // The look of a take: a missing texture, a bad light key, a light range backwards, no photos.
  expect_error([] { parse_synth_config(base("render: {body_texture: /nonexistent/skin.png}\n"), "bad.yaml"); },
               {"bad.yaml", "render.body_texture", "/nonexistent/skin.png"});
  expect_error([] { parse_synth_config(base("render: {lighting: {spotlight: 1}}\n"), "bad.yaml"); },
               {"bad.yaml", "render.lighting.spotlight"});
  expect_error([] { parse_synth_config(base("render: {lighting: {lights: 2, intensity: [0.9, 0.1]}}\n"), "bad.yaml"); },
               {"bad.yaml", "render.lighting.intensity"});
  expect_error([] { parse_synth_config(base("render: {background: photos}\n"), "bad.yaml"); },
               {"bad.yaml", "render.background", "render.photos"});
  expect_error(
      [] { parse_synth_config(base("render: {background: photos, photos: /nonexistent/photos}\n"), "bad.yaml"); },
      {"bad.yaml", "render.photos", "/nonexistent/photos"});
  expect_error([] { parse_synth_config(base("render: {photos: /tmp}\n"), "bad.yaml"); },
               {"bad.yaml", "render.photos", "background: photos"});
  expect_error([] { parse_synth_config(base("splits: {val: 0.6, test: 0.6}\n"), "bad.yaml"); }, {"splits"});
  expect_error([] { parse_synth_config(base("", "  bvh: /nonexistent/clip.bvh\n"), "bad.yaml"); }, {"motion"});
  expect_error([] { parse_synth_config("name: t\ncharacter: /nonexistent.yaml\nmotion: {}\n", "bad.yaml"); },
               {"bad.yaml", "character"});
  expect_error([] { load_synth_config("/nonexistent/synth.yaml"); }, {"/nonexistent/synth.yaml"});
  expect_error([] { parse_synth_config(base("", "  in_place_s: -1\n"), "bad.yaml"); }, {"bad.yaml", "motion.in_place_s"});
}

TEST(SynthConfig, MotionsListClipsInOrder) {
  const SynthConfig c = parse_synth_config(
      with_clips(clip("walk_in_place", "    frames: 12\n    in_place_s: 1\n") +
                 clip("squat_jump", "    frames: 5\n    start: 1.5\n    stride: 2\n")),
      "c.yaml");
  ASSERT_EQ(c.motions.size(), 2u);
  EXPECT_TRUE(c.motion_list);
  EXPECT_EQ(c.frames(), 17);
  EXPECT_EQ(c.fps(), 30);
  EXPECT_NE(c.motions[0].procedural.find("walk_in_place"), std::string::npos);
  EXPECT_DOUBLE_EQ(c.motions[0].in_place_s, 1);
  EXPECT_EQ(c.motions[1].stride, 2);
  EXPECT_DOUBLE_EQ(c.motions[1].start_s, 1.5);
  EXPECT_LT(c.motions[1].in_place_s, 0);
  EXPECT_EQ(c.motion_key(1), "motions[1]");
  const SynthConfig one = parse_synth_config(base(), "one.yaml");
  EXPECT_EQ(one.motion_key(0), "motion");
}

TEST(SynthConfig, MotionsErrorsNameTheClip) {
  // Both keys: the message names the one that is too many.
  expect_error([] { parse_synth_config(base("motions:\n" + clip("squat_jump")), "bad.yaml"); },
               {"bad.yaml:", "motions", "either motion (one clip) or motions"});
  expect_error([] { parse_synth_config(with_clips("") + " []\n", "bad.yaml"); }, {"bad.yaml", "motions", "a list"});
  expect_error([] { parse_synth_config(with_clips(clip("walk_in_place") + clip("squat_jump", "    colour: red\n")),
                                       "bad.yaml"); },
               {"bad.yaml:", "motions[1].colour", "unknown key"});
  expect_error([] { parse_synth_config(with_clips(clip("walk_in_place") + clip("squat_jump", "    fps: 25\n")),
                                       "bad.yaml"); },
               {"bad.yaml:", "motions[1].fps", "same fps"});
  expect_error([] { parse_synth_config(with_clips(clip("walk_in_place") + "  - {frames: 3}\n"), "bad.yaml"); },
               {"bad.yaml:", "motions[1]", "exactly one of procedural, bvh or skeletool"});
  expect_error([] { parse_synth_config(with_clips(clip("walk_in_place") + "  - 7\n"), "bad.yaml"); },
               {"bad.yaml:", "motions[1]", "expected a motion section"});
  expect_error([] { parse_synth_config("name: t\ncharacter: " +
                                           repo_file("configs/characters/makehuman_skirt_coarse.yaml") + "\n",
                                       "bad.yaml"); },
               {"bad.yaml", "motion", "missing"});
}

TEST(SynthConfig, HeldOutStretchSitsWhereSplitsPlaceSaysInEachClip) {
  // 1 (the default): at the clip's end, as before; 0.5: a stretch from the middle of the motion.
  const ClipSplit end = split_clip(10, 30, 0.1, 0.2, 1.0);
  EXPECT_EQ(end.val, (std::vector<int>{24, 25}));
  EXPECT_EQ(end.test, (std::vector<int>{26, 27, 28, 29}));
  EXPECT_EQ(end.train.size(), 14u);
  EXPECT_EQ(end.train.back(), 23);
  const ClipSplit mid = split_clip(10, 30, 0.1, 0.2, 0.5);
  EXPECT_EQ(mid.val, (std::vector<int>{17, 18}));
  EXPECT_EQ(mid.test, (std::vector<int>{19, 20, 21, 22}));
  EXPECT_EQ(mid.train.front(), 10);
  EXPECT_EQ(mid.train.back(), 29);
  EXPECT_EQ(mid.train.size(), 14u);
  const ClipSplit start = split_clip(0, 10, 0.0, 0.3, 0.0);
  EXPECT_EQ(start.test, (std::vector<int>{0, 1, 2}));
  EXPECT_TRUE(start.val.empty());
  const SynthConfig c = parse_synth_config(base("splits: {val: 0.1, test: 0.1, place: 0.5}\n"), "c.yaml");
  EXPECT_DOUBLE_EQ(c.split_place, 0.5);
  EXPECT_DOUBLE_EQ(parse_synth_config(base(), "d.yaml").split_place, 1.0);
  expect_error([] { parse_synth_config(base("splits: {place: 2}\n"), "bad.yaml"); }, {"bad.yaml", "splits.place"});
}
