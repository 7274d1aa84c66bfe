// The synthetic studio end to end (`weft synth` on a small config): the written masks are
// the silhouettes of the written ground-truth meshes seen by the written cameras (checked
// with OpenCV's projection and polygon filling, independently of the renderer), keypoints
// reproject from the written pose, the calibration round-trips, the garment stays out of
// the body, and one seed gives identical files.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "capture/io/camera.h"
#include "capture/character/character.h"
#include "geometry/mesh_io.h"
#include "capture/io/openpose.h"
#include "capture/character/skeletool_io.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "capture/studio/studio_rig.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/studio/synthetic_studio.h"
#include "physics/body_mesh.h"
#include "tests/capture/opencv_silhouette.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
using weft::capture::testing::centre_sampled_silhouette;
using weft::capture::testing::opencv_silhouette;
namespace fs = std::filesystem;

using weft::capture::testing::slurp;

using weft::capture::testing::kHuman;
using weft::capture::testing::repo_file;

namespace {



// 4 frames of the procedural walk, coarse skirt, 6 studio views at 256².
std::string config_text(uint64_t seed) {
  std::ostringstream s;
  s << "name: studio_test\n"
    << "seed: " << seed << "\n"
    << "character: " << repo_file("configs/characters/makehuman_skirt_coarse.yaml") << "\n"
    << "motion:\n"
    << "  procedural: " << repo_file("configs/motions/walk_in_place.yaml") << "\n"
    << "  mapping: " << repo_file("configs/retarget/humanoid_to_makehuman.yaml") << "\n"
    << "  fps: 30\n  start: 1.5\n  frames: 4\n"
    << "simulation: {settle_frames: 4}\n"
    << "cameras: {rig: studio, views: 6, width: 256, height: 256, k1: -0.05}\n"
    << "keypoints: {noise_px: 2.0, dropout: 0.1}\n"
    << "splits: {val: 0.25, test: 0.25}\n";
  return s.str();
}

struct Dataset {
  fs::path dir;
  SynthConfig config;
  SynthSummary summary;
};

fs::path studio_scratch_root() {
  return fs::temp_directory_path() / ("weft_synth_test_" + std::to_string(::getpid()));
}

// Written once per test program (a few seconds), removed at exit.
const Dataset& dataset() {
  static std::unique_ptr<Dataset> d;
  if (!d) {
    d = std::make_unique<Dataset>();
    d->dir = studio_scratch_root() / "a";
    fs::remove_all(d->dir);
    d->config = parse_synth_config(config_text(7), "studio_test.yaml");
    d->summary = synthesize_dataset(d->config, d->dir.string());
    static struct Cleanup {
      ~Cleanup() {
        std::error_code ec;
        fs::remove_all(studio_scratch_root(), ec);
      }
    } cleanup;
  }
  return *d;
}

std::string frame_path(const fs::path& dir, const char* kind, const std::string& view, int frame, const char* suffix) {
  return (dir / kind / view / (dataset_frame_name(frame) + suffix)).string();
}

double iou(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat i, u;
  cv::bitwise_and(a > 0, b > 0, i);
  cv::bitwise_or(a > 0, b > 0, u);
  return static_cast<double>(cv::countNonZero(i)) / std::max(1, cv::countNonZero(u));
}

}  // namespace

TEST(SyntheticStudio, MasksAreTheProjectedGroundTruthSilhouettes) {
  REQUIRE_HUMAN();
  const Dataset& d = dataset();
  const std::vector<Camera> cameras = read_cameras_yaml((d.dir / "cameras.yaml").string());
  ASSERT_EQ(static_cast<int>(cameras.size()), 6);
  double worst = 1;
  for (int f = 0; f < d.summary.frames; ++f) {
    const std::vector<TriangleMesh> meshes = {
        read_ply((d.dir / "gt" / ("body_" + dataset_frame_name(f) + ".ply")).string()),
        read_ply((d.dir / "gt" / ("cloth_" + dataset_frame_name(f) + ".ply")).string())};
    for (const Camera& cam : cameras) {
      const cv::Mat mask = cv::imread(frame_path(d.dir, "masks", cam.name, f, ".png"), cv::IMREAD_GRAYSCALE);
      ASSERT_FALSE(mask.empty()) << cam.name << " frame " << f;
      // Pixel centres inside a projected triangle (the renderer's and OpenCV's convention)
      // must match to IoU 0.99; cv::fillConvexPoly's edge-touching fill holds the mask.
      const cv::Mat reference = centre_sampled_silhouette(cam, {&meshes[0], &meshes[1]});
      ASSERT_GT(cv::countNonZero(reference), 2000) << "the subject should fill part of " << cam.name;
      const double v = iou(mask, reference);
      worst = std::min(worst, v);
      EXPECT_GE(v, 0.99) << cam.name << " frame " << f;
      const cv::Mat filled = opencv_silhouette(cam, {&meshes[0], &meshes[1]});
      EXPECT_LT(cv::countNonZero(mask & ~filled), cv::countNonZero(mask) / 200) << cam.name << " frame " << f;
    }
  }
  std::printf("worst mask IoU against OpenCV's projected silhouettes: %.4f\n", worst);
}

TEST(SyntheticStudio, PartMasksAndDistanceTransformsAgreeWithTheMask) {
  REQUIRE_HUMAN();
  const Dataset& d = dataset();
  const std::string view = "cam03";
  const cv::Mat mask = cv::imread(frame_path(d.dir, "masks", view, 2, ".png"), cv::IMREAD_GRAYSCALE);
  const cv::Mat parts = cv::imread(frame_path(d.dir, "parts", view, 2, ".png"), cv::IMREAD_GRAYSCALE);
  const cv::Mat dt = cv::imread(frame_path(d.dir, "dt", view, 2, ".png"), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(dt.type(), CV_16UC1);
  EXPECT_EQ(cv::countNonZero((parts > 0) != (mask > 0)), 0);
  EXPECT_GT(cv::countNonZero(parts == 1), 500);  // body
  EXPECT_GT(cv::countNonZero(parts == 2), 500);  // skirt
  EXPECT_EQ(cv::countNonZero((dt == 0) != (mask > 0)), 0);
  // A background pixel's value is its distance to the nearest foreground pixel × dt_scale.
  std::vector<cv::Point> fg;
  cv::findNonZero(mask, fg);
  for (cv::Point p : {cv::Point(5, 5), cv::Point(250, 128), cv::Point(128, 3)}) {
    double best = 1e9;
    for (const cv::Point& q : fg) best = std::min(best, std::hypot(p.x - q.x, p.y - q.y));
    EXPECT_NEAR(dt.at<uint16_t>(p) / d.config.render.dt_scale, best, 0.05) << p;
  }
}

TEST(SyntheticStudio, KeypointsReprojectFromTheWrittenPose) {
  REQUIRE_HUMAN();
  const Dataset& d = dataset();
  const Character ch = load_character((d.dir / "character" / "character.yaml").string());
  const Motion motion = read_motion((d.dir / "gt" / "pose.motion").string(), ch.skeleton.num_dofs());
  ASSERT_EQ(motion.num_frames(), d.summary.frames);
  const std::vector<Camera> cameras = read_cameras_yaml((d.dir / "cameras.yaml").string());
  double sum_sq = 0;
  int detected = 0, total = 0;
  for (int f = 0; f < d.summary.frames; ++f) {
    const PosedCharacter posed = pose_character(ch, motion.dofs.row(f).transpose());
    // The written body is the written pose applied to the written character.
    const TriangleMesh body = read_ply((d.dir / "gt" / ("body_" + dataset_frame_name(f) + ".ply")).string());
    EXPECT_LT((body.V - posed.body).cwiseAbs().maxCoeff(), 1e-5) << "frame " << f;
    for (const Camera& cam : cameras) {
      const OpenPoseFrame op = read_openpose_json(frame_path(d.dir, "keypoints", cam.name, f, "_keypoints.json"));
      ASSERT_EQ(op.people.size(), 1u);
      for (int k = 0; k < kBody25Count; ++k) {
        if (!posed.body25.row(k).allFinite()) continue;
        ++total;
        if (op.people[0](k, 2) <= 0) continue;
        ++detected;
        const Eigen::Vector2d e = Eigen::Vector2d(op.people[0](k, 0), op.people[0](k, 1)) -
                                  cam.project(posed.body25.row(k).transpose());
        EXPECT_LT(e.norm(), 6 * 2.0 * std::sqrt(2.0)) << cam.name << " frame " << f << " keypoint " << k;
        sum_sq += e.squaredNorm();
      }
    }
  }
  const double rms_per_axis = std::sqrt(sum_sq / (2.0 * detected));
  std::printf("%d of %d mapped keypoints detected; rms error per axis %.2f px (noise 2 px)\n", detected, total,
              rms_per_axis);
  EXPECT_NEAR(rms_per_axis, 2.0, 0.4);
  EXPECT_GT(detected, 0.8 * total);  // 10% dropout, some outside or hidden-and-dropped
  EXPECT_LT(detected, total);
}

TEST(SyntheticStudio, CalibrationRoundTripsAndIsTheConfiguredRig) {
  REQUIRE_HUMAN();
  const Dataset& d = dataset();
  const std::vector<Camera> read = read_cameras_yaml((d.dir / "cameras.yaml").string());
  const std::vector<Camera> rig = studio_rig(d.config.cameras.studio);
  ASSERT_EQ(read.size(), rig.size());
  for (size_t i = 0; i < rig.size(); ++i) {
    EXPECT_EQ(read[i].name, rig[i].name);
    EXPECT_LT((read[i].K - rig[i].K).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_LT((read[i].R - rig[i].R).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((read[i].t - rig[i].t).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_LT((read[i].dist - rig[i].dist).cwiseAbs().maxCoeff(), 1e-15);
    EXPECT_EQ(read[i].width, 256);
  }
  // Written again, the file is the same bytes.
  weft::capture::testing::ScratchDir scratch("synth");
  write_cameras_yaml(scratch.file("again.yaml"), read);
  EXPECT_EQ(slurp(scratch.file("again.yaml")), slurp(d.dir / "cameras.yaml"));
}

TEST(SyntheticStudio, GarmentStaysOutsideTheBodyAndSplitsAreDisjoint) {
  REQUIRE_HUMAN();
  const Dataset& d = dataset();
  const Character ch = load_character((d.dir / "character" / "character.yaml").string());
  std::vector<std::array<int, 3>> faces(ch.body.mesh.num_faces());
  for (int i = 0; i < ch.body.mesh.num_faces(); ++i)
    faces[i] = {ch.body.mesh.F(i, 0), ch.body.mesh.F(i, 1), ch.body.mesh.F(i, 2)};
  for (int f = 0; f < d.summary.frames; ++f) {
    const TriangleMesh body = read_ply((d.dir / "gt" / ("body_" + dataset_frame_name(f) + ".ply")).string());
    const TriangleMesh cloth = read_ply((d.dir / "gt" / ("cloth_" + dataset_frame_name(f) + ".ply")).string());
    const weft::physics::BodyMesh obstacle(body.V, faces, ch.inactive_body_faces);
    double min_d = 1e9;
    for (int i = 0; i < cloth.num_vertices(); ++i)
      min_d = std::min(min_d, obstacle.closest_point(cloth.V.row(i).transpose()).distance);
    EXPECT_GT(min_d, -1e-3) << "frame " << f << ": a garment vertex is " << -min_d << " m inside the body";
    EXPECT_FALSE(d.summary.reports[f].failed) << "frame " << f << ": " << d.summary.reports[f].status;
  }
  const nlohmann::json metrics = nlohmann::json::parse(slurp(d.dir / "metrics.json"));
  ASSERT_EQ(metrics["frames"].size(), 4u);
  for (size_t f = 1; f < 4; ++f) {
    EXPECT_EQ(metrics["frames"][f]["status"], "converged");
    EXPECT_LT(metrics["frames"][f]["oob_force_max_rel"].get<double>(), 0.01);  // Newton's tolerance 1e-3
  }
  EXPECT_EQ(d.summary.train, (std::vector<int>{0, 1}));
  EXPECT_EQ(d.summary.val, (std::vector<int>{2}));
  EXPECT_EQ(d.summary.test, (std::vector<int>{3}));
}

TEST(SyntheticStudio, TheDatasetCarriesItsSimulationSettings) {
  // dataset.yaml holds the config's simulation section: training, evaluation and
  // inference read the garment's material there, not from the recipe.
  const Dataset& d = dataset();
  EXPECT_EQ(read_dataset_simulation(d.dir.string()), d.config.simulation);
}

TEST(SyntheticStudio, OneSeedGivesIdenticalFiles) {
  REQUIRE_HUMAN();
  const Dataset& d = dataset();
  const fs::path again = studio_scratch_root() / "b";
  fs::remove_all(again);
  synthesize_dataset(parse_synth_config(config_text(7), "studio_test.yaml"), again.string());
  int compared = 0;
  for (const auto& e : fs::recursive_directory_iterator(d.dir)) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), d.dir);
    if (rel == "timing.json") continue;  // wall-clock times, the one file allowed to differ
    ASSERT_TRUE(fs::exists(again / rel)) << rel;
    EXPECT_EQ(slurp(e.path()), slurp(again / rel)) << rel << " differs between two runs with one seed";
    ++compared;
  }
  EXPECT_GT(compared, 6 * 4 * 5);  // images, masks, parts, dt, keypoints per view and frame
  std::printf("%d files identical\n", compared);
}

// What training reads: the reader opens every split of the written dataset, and each
// sample's crop camera projects the written pose's keypoints onto the sample's keypoints.
TEST(SyntheticStudio, TheReaderOpensEverySplitAndCropsAgreeWithTheGroundTruth) {
  REQUIRE_HUMAN();
  const Dataset& d = dataset();
  const DatasetInfo info = read_dataset_info(d.dir.string());
  EXPECT_EQ(info.frames, 4);
  EXPECT_EQ(info.views.size(), 6u);
  EXPECT_EQ(info.splits.at("train"), d.summary.train);
  const Character ch = load_character(info.character);
  const Motion motion = read_motion((d.dir / "gt" / "pose.motion").string(), ch.skeleton.num_dofs());
  int checked = 0;
  for (const char* split : {"train", "val", "test"}) {
    DatasetOptions o;
    o.split = split;
    o.input_size = 128;
    const SyntheticDataset set(d.dir.string(), o);
    ASSERT_EQ(set.size(), static_cast<int>(set.frames().size() * 6)) << split;
    for (int i = 0; i < set.size(); i += 5) {
      const Sample s = set.load(i);
      EXPECT_EQ(s.mask.rows, 128);
      EXPECT_GT(cv::countNonZero(s.mask), 500) << "the person fills the crop";
      const PosedCharacter posed = pose_character(ch, motion.dofs.row(s.frame).transpose());
      for (int k = 0; k < kBody25Count; ++k) {
        if (s.keypoints(k, 2) <= 0 || !posed.body25.row(k).allFinite()) continue;
        const Eigen::Vector2d truth = s.crop_camera.project(posed.body25.row(k).transpose());
        // 2 px of noise in the full image, scaled into the crop.
        EXPECT_LT((Eigen::Vector2d(s.keypoints(k, 0), s.keypoints(k, 1)) - truth).norm(), 12 * 2.0 * s.crop.scale)
            << split << " sample " << i << " keypoint " << k;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 50);
}

// ---------------------------------------------------------------------- several clips

namespace {

std::string clip_text(const char* motion, double start_s, const std::string& extra = "") {
  std::ostringstream s;
  s << "  - procedural: " << repo_file(std::string("configs/motions/") + motion + ".yaml") << "\n"
    << "    mapping: " << repo_file("configs/retarget/humanoid_to_makehuman.yaml") << "\n"
    << "    start: " << start_s << "\n    frames: 4\n" << extra;
  return s.str();
}

// Clips in a `motions:` list; coarse skirt, 2 views at 64².
std::string clips_config(const std::string& clips, const std::string& simulation = "{settle_frames: 4}") {
  return "name: clips_test\nseed: 5\ncharacter: " + repo_file("configs/characters/makehuman_skirt_coarse.yaml") +
         "\nmotions:\n" + clips + "simulation: " + simulation + "\n" +
         "cameras: {rig: studio, views: 2, width: 64, height: 64}\nsplits: {val: 0.25, test: 0.25}\n";
}

// The mean distance between corresponding vertices (character units).
double mean_distance(const Vertices& a, const Vertices& b) {
  double d = 0;
  for (int i = 0; i < a.rows(); ++i) d += (a.row(i) - b.row(i)).norm();
  return d / std::max<Eigen::Index>(1, a.rows());
}

TriangleMesh gt_mesh(const fs::path& dir, const char* kind, int frame) {
  return read_ply((dir / "gt" / (std::string(kind) + "_" + dataset_frame_name(frame) + ".ply")).string());
}

}  // namespace

// Stepping on the spot, then rising from a squat (the hips lower): one dataset
// with continuous frame ids whose second clip is simulated afresh from its own first pose,
// exactly as if it had been made alone.
TEST(SyntheticStudio, SeveralClipsMakeOneDatasetWithASimulationPerClip) {
  REQUIRE_HUMAN();
  weft::capture::testing::ScratchDir scratch("clips");
  const std::string walk = clip_text("walk_in_place", 1.5), squat = clip_text("squat_jump", 2.2);
  const fs::path both = scratch.file("both"), alone_a = scratch.file("walk"), alone_b = scratch.file("squat");
  const SynthSummary s =
      synthesize_dataset(parse_synth_config(clips_config(walk + squat), "clips.yaml"), both.string());
  synthesize_dataset(parse_synth_config(clips_config(walk), "walk.yaml"), alone_a.string());
  synthesize_dataset(parse_synth_config(clips_config(squat), "squat.yaml"), alone_b.string());

  // Frame ids run on over the clip boundary; dataset.yaml names the clips' first frames.
  EXPECT_EQ(s.frames, 8);
  EXPECT_EQ(s.segments, (std::vector<int>{0, 4}));
  for (int f = 0; f < 8; ++f) EXPECT_TRUE(fs::exists(frame_path(both, "images", "cam01", f, ".png"))) << f;
  EXPECT_FALSE(fs::exists(frame_path(both, "images", "cam01", 8, ".png")));
  const DatasetInfo info = read_dataset_info(both.string());
  EXPECT_EQ(info.frames, 8);
  EXPECT_EQ(info.segments, (std::vector<int>{0, 4}));
  EXPECT_TRUE(same_segment(info, 0, 3));
  EXPECT_FALSE(same_segment(info, 3, 4));
  EXPECT_NE(slurp(both / "dataset.yaml").find("\nsegments: [0, 4]\n"), std::string::npos);
  EXPECT_EQ(slurp(alone_a / "dataset.yaml").find("segments"), std::string::npos) << "one clip: the file as before";
  const Character ch = load_character(info.character);
  const Motion motion = read_motion((both / "gt" / "pose.motion").string(), ch.skeleton.num_dofs());
  ASSERT_EQ(motion.num_frames(), 8);
  for (int f = 0; f < 8; ++f) EXPECT_EQ(motion.frame_ids[f], f);

  // Splits: a quarter of each clip from its end for test, the quarter before for val.
  for (const auto& r : s.reports) ASSERT_FALSE(r.failed) << "frame " << r.frame << ": " << r.status;
  EXPECT_EQ(s.train, (std::vector<int>{0, 1, 4, 5}));
  EXPECT_EQ(s.val, (std::vector<int>{2, 6}));
  EXPECT_EQ(s.test, (std::vector<int>{3, 7}));
  EXPECT_EQ(info.splits.at("val"), s.val);

  // Each clip's first frame is a settled frame; metrics.json lists the clips.
  const nlohmann::json metrics = nlohmann::json::parse(slurp(both / "metrics.json"));
  ASSERT_EQ(metrics["frames"].size(), 8u);
  for (int f : {0, 4}) {
    EXPECT_EQ(metrics["frames"][f]["frame"], f);
    EXPECT_EQ(metrics["frames"][f]["status"], "settled");
  }
  EXPECT_EQ(metrics["frames"][5]["status"], "converged");
  EXPECT_EQ(metrics["summary"]["segments"], nlohmann::json({0, 4}));

  // The garment restarts on the squat: its first frame is the skinned garment settled for
  // 4 frames on that pose, not one more step of the walk's garment.
  const SynthConfig cfg = parse_synth_config(clips_config(walk + squat), "clips.yaml");
  const double mpu = ch.metres_per_unit;
  auto body_metres = [&](int f) { return Eigen::MatrixX3d(gt_mesh(both, "body", f).V * mpu); };
  const PosedCharacter squat_pose = pose_character(ch, motion.dofs.row(4).transpose());
  const std::vector<weft::physics::Vec3> pins = garment_pin_targets(ch, squat_pose.cloth);
  auto sim = make_garment_simulator(ch, cfg.simulation, cfg.fps(), body_metres(4), pins);
  weft::physics::Positions x2 = to_positions(squat_pose.cloth, mpu), x1 = x2;
  for (int i = 0; i < cfg.simulation.settle_frames; ++i) {
    weft::physics::StepResult r = sim->step(x2, x1);
    x2 = std::move(x1);
    x1 = std::move(r.x);
  }
  const Vertices settled = to_vertices(x1, mpu);
  const Eigen::MatrixX3d body3 = body_metres(3), body4 = body_metres(4);
  auto going_on = make_garment_simulator(ch, cfg.simulation, cfg.fps(), body3, pins);
  going_on->set_pins(garment_pin_vertices(ch), pins);
  const weft::physics::StepResult next = going_on->step(to_positions(gt_mesh(both, "cloth", 2).V, mpu),
                                                        to_positions(gt_mesh(both, "cloth", 3).V, mpu), &body3, &body4);
  const Vertices cloth4 = gt_mesh(both, "cloth", 4).V;
  const double from_settled = mean_distance(cloth4, settled), from_walk = mean_distance(cloth4, to_vertices(next.x, mpu));
  std::printf("clip 2's first frame: %.3f mm from the skinned garment settled on its pose, %.1f mm from one more "
              "step of the walk's garment (mean)\n", 1e3 * from_settled, 1e3 * from_walk);
  EXPECT_LT(from_settled, 1e-4);
  EXPECT_GT(from_walk, 0.01);
  // Simulation windows over the ground truth stay inside a clip.
  const GarmentSequence sequence = load_garment_sequence(both.string());
  EXPECT_EQ(sequence.segments, (std::vector<int>{0, 4}));
  EXPECT_NO_THROW(garment_window(sequence, 4, 3, sequence.cloth[3], sequence.cloth[4]));
  weft::capture::testing::expect_error(
      [&] { garment_window(sequence, 2, 2, sequence.cloth[1], sequence.cloth[2]); },
      {"window of 2 frames after frame 2", "crosses the clip starting at frame 4"});
  // ... and each clip's ground truth is what that clip makes alone, to the byte.
  for (int f = 0; f < 4; ++f)
    for (const char* kind : {"cloth", "body"}) {
      const std::string name = std::string(kind) + "_" + dataset_frame_name(f) + ".ply";
      EXPECT_EQ(slurp(both / "gt" / name), slurp(alone_a / "gt" / name)) << name;
      EXPECT_EQ(slurp(both / "gt" / (std::string(kind) + "_" + dataset_frame_name(f + 4) + ".ply")),
                slurp(alone_b / "gt" / name))
          << name << " of the squat";
    }
}

// in_place_s: the walk after the turn travels 0.8 m along x in one second; taking away
// its path smoothed over 0.5 s walks it on the spot, and changes nothing else.
TEST(SyntheticStudio, InPlaceTakesAwayTheRootsHorizontalPath) {
  REQUIRE_HUMAN();
  weft::capture::testing::ScratchDir scratch("in_place");
  // The garment skinned, not simulated: the motion is what matters here.
  std::unique_ptr<Character> ch;
  auto make = [&](const std::string& name, const std::string& extra) {
    const std::string clip = "  - procedural: " + repo_file("configs/motions/walk_in_place.yaml") +
                             "\n    mapping: " + repo_file("configs/retarget/humanoid_to_makehuman.yaml") +
                             "\n    start: 7.4\n    frames: 30\n" + extra;
    const fs::path dir = scratch.file(name);
    synthesize_dataset(parse_synth_config(clips_config(clip, "{enabled: false}"), name + ".yaml"), dir.string());
    if (!ch) ch = std::make_unique<Character>(load_character((dir / "character" / "character.yaml").string()));
    return read_motion((dir / "gt" / "pose.motion").string(), ch->skeleton.num_dofs());
  };
  const Motion own = make("own", ""), treadmill = make("treadmill", "    in_place_s: 0.5\n"),
               pinned = make("pinned", "    in_place_s: 0\n");
  const Skeleton& skeleton = ch->skeleton;
  const int tx = skeleton.dof_index("hips_tx"), tz = skeleton.dof_index("hips_tz");
  ASSERT_GE(tx, 0);
  ASSERT_GE(tz, 0);
  auto range = [](const Eigen::MatrixXd& m, int col) {
    double lo = m(0, col), hi = m(0, col);
    for (int f = 1; f < m.rows(); ++f) lo = std::min(lo, m(f, col)), hi = std::max(hi, m(f, col));
    return hi - lo;
  };
  auto largest = [](const Eigen::MatrixXd& m, int col) {
    double v = 0;
    for (int f = 0; f < m.rows(); ++f) v = std::max(v, std::abs(m(f, col)));
    return v;
  };
  std::printf("root x travel: own %.2f m, in_place_s 0.5: %.2g m, in_place_s 0: %.2g m\n", range(own.dofs, tx),
              range(treadmill.dofs, tx), range(pinned.dofs, tx));
  EXPECT_GT(range(own.dofs, tx), 0.6);
  // The procedural walk travels at a steady speed: the local line fits take all of it.
  std::vector<Eigen::Vector3d> track;
  for (int f = 0; f < own.num_frames(); ++f) track.emplace_back(own.dofs(f, tx), 0, own.dofs(f, tz));
  const std::vector<Eigen::Vector3d> path = smooth_track(track, 0.5 * 30);
  for (int f = 0; f < own.num_frames(); ++f) {
    EXPECT_NEAR(treadmill.dofs(f, tx), own.dofs(f, tx) - path[f].x(), 1e-9) << f;
    EXPECT_NEAR(treadmill.dofs(f, tz), own.dofs(f, tz) - path[f].z(), 1e-9) << f;
  }
  EXPECT_LT(range(treadmill.dofs, tx), 0.01);
  EXPECT_LT(largest(pinned.dofs, tx), 1e-9);
  EXPECT_LT(largest(pinned.dofs, tz), 1e-9);
  // Only the horizontal root translations change: heights, turns and limbs stay.
  const Eigen::MatrixXd change = own.dofs - treadmill.dofs;
  for (int d = 0; d < skeleton.num_dofs(); ++d) {
    if (d == tx || d == tz) continue;
    EXPECT_LT(largest(change, d), 1e-12) << skeleton.dofs[d].name;
  }
}

// `weft synth` crashed (a std::map insert racing in its progress bars) when the rendering's
// parallel loop reported progress from two threads at once. The callback is entered by one
// thread at a time, each stage counts up to its total, and nothing is reported twice.
TEST(SyntheticStudio, ProgressIsReportedFromOneThreadAtATime) {
  REQUIRE_HUMAN();
  weft::capture::testing::ScratchDir scratch("progress");
  const std::string clip = "  - procedural: " + repo_file("configs/motions/walk_in_place.yaml") +
                           "\n    mapping: " + repo_file("configs/retarget/humanoid_to_makehuman.yaml") +
                           "\n    start: 1.5\n    frames: 8\n";
  std::atomic<int> inside{0}, most{0};
  std::map<std::string, std::vector<int>> done;  // deliberately not thread-safe, like the app's bars
  std::map<std::string, int> total;
  synthesize_dataset(parse_synth_config(clips_config(clip, "{enabled: false}"), "progress.yaml"),
                     scratch.file("out"), [&](const SynthProgress& p) {
                       const int now = ++inside;
                       most = std::max(most.load(), now);
                       std::this_thread::sleep_for(std::chrono::milliseconds(2));  // widen any overlap
                       done[p.stage].push_back(p.done);
                       total[p.stage] = p.total;
                       --inside;
                     });
  EXPECT_EQ(most.load(), 1);
  ASSERT_EQ(done.count("rendering"), 1u);
  EXPECT_EQ(total["rendering"], 16);  // 8 frames × 2 views
  for (const auto& [stage, counts] : done) {
    ASSERT_FALSE(counts.empty()) << stage;
    for (size_t i = 1; i < counts.size(); ++i) EXPECT_GT(counts[i], counts[i - 1]) << stage << " report " << i;
    EXPECT_EQ(counts.back(), total[stage]) << stage;
  }
}
