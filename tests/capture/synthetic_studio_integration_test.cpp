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

#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "capture/io/camera.h"
#include "capture/character/character.h"
#include "capture/io/mesh_io.h"
#include "capture/io/openpose.h"
#include "capture/character/skeletool_io.h"
#include "capture/studio/studio_rig.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/studio/synthetic_studio.h"
#include "physics/body_mesh.h"
#include "tests/capture/opencv_silhouette.h"
#include "tests/capture/test_files.h"

using namespace weft::capture;
using weft::capture::testing::centre_sampled_silhouette;
using weft::capture::testing::opencv_silhouette;
namespace fs = std::filesystem;

using weft::capture::testing::slurp;

namespace {

const char* kHuman = "/usr/share/assimp/models/Collada/human.zae";
std::string repo_file(const std::string& rel) { return std::string(WEFT_SOURCE_DIR) + "/" + rel; }

#define SKIP_WITHOUT_HUMAN()                                                                   \
  if (!fs::exists(kHuman))                                                                     \
  GTEST_SKIP() << kHuman << " is missing: install Debian's assimp-testmodels (scripts/setup.sh)"

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

fs::path scratch_root() {
  return fs::temp_directory_path() / ("weft_synth_test_" + std::to_string(::getpid()));
}

// Written once per test program (a few seconds), removed at exit.
const Dataset& dataset() {
  static std::unique_ptr<Dataset> d;
  if (!d) {
    d = std::make_unique<Dataset>();
    d->dir = scratch_root() / "a";
    fs::remove_all(d->dir);
    d->config = parse_synth_config(config_text(7), "studio_test.yaml");
    d->summary = synthesize_dataset(d->config, d->dir.string());
    static struct Cleanup {
      ~Cleanup() {
        std::error_code ec;
        fs::remove_all(scratch_root(), ec);
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
  SKIP_WITHOUT_HUMAN();
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
  SKIP_WITHOUT_HUMAN();
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
  SKIP_WITHOUT_HUMAN();
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
  SKIP_WITHOUT_HUMAN();
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
  SKIP_WITHOUT_HUMAN();
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

TEST(SyntheticStudio, OneSeedGivesIdenticalFiles) {
  SKIP_WITHOUT_HUMAN();
  const Dataset& d = dataset();
  const fs::path again = scratch_root() / "b";
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
  SKIP_WITHOUT_HUMAN();
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
