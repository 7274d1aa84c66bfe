// `weft train` on the tiny dataset (configs/synth/tiny.yaml) with configs/train/tiny.yaml:
// every stage runs and lowers its loss; a run killed with SIGKILL in the middle of each
// stage and resumed gives the same losses, step for step, as a run never stopped; bad
// data stops with an error naming the file or the step, and a non-finite loss never
// reaches a checkpoint.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <nlohmann/json.hpp>
#include <thread>
#include <iterator>
#include <opencv2/imgcodecs.hpp>

#include "tests/capture/shared_fixture.h"
#include "tests/capture/test_files.h"
#include "capture/character/skeletool_io.h"
#include "capture/evaluation/frame_measures.h"
#include "capture/training/split_evaluation.h"
#include "capture/io/openpose.h"
#include "capture/studio/synthetic_studio.h"
#include "capture/model/capture_networks.h"
#include "capture/training/loss_log.h"
#include "capture/training/multiview_losses.h"
#include "capture/training/trainer.h"
#include "capture/evaluation/detection_accuracy.h"
#include "capture/evaluation/capture_evaluation.h"
#include "capture/evaluation/evaluation_report.h"
#include "capture/inference/sequence_capture.h"
#include "capture/inference/sequence_detection.h"
#include "graph/autograd.h"
#include "nn/checkpoint.h"
#include "nn/optim.h"
#include "ops/ops.h"

using namespace weft;
using namespace weft::capture;
namespace fs = std::filesystem;

using weft::capture::testing::kHuman;
using weft::capture::testing::repo_file;

namespace {

std::string weft_binary() { return std::string(WEFT_BINARY_DIR) + "/apps/weft"; }


fs::path training_scratch_root() { return weft::capture::testing::process_scratch("training"); }

struct Fixture {
  fs::path data;       // the tiny dataset (shared_fixture.h)
  fs::path reference;  // an uninterrupted run of configs/train/tiny.yaml on it (shared too)
  // What that run's TrainSummary said (kept in the fixture's summary.txt).
  int simulation_windows = 0, simulation_failures = 0, validation_samples = 0;
  double validation_iou = -1;
};

// The tiny dataset alone, for the tests that train nothing of the reference.
fs::path tiny_data() { return weft::capture::testing::tiny_dataset(); }

const Fixture& fixture() {
  static std::unique_ptr<Fixture> f;
  if (!f) {
    f = std::make_unique<Fixture>();
    f->data = tiny_data();
    f->reference = weft::capture::testing::tiny_reference_run();
    std::ifstream(f->reference / "summary.txt") >> f->simulation_windows >> f->simulation_failures >>
        f->validation_samples >> f->validation_iou;
  }
  return *f;
}

double mean_total(const std::vector<LossRow>& rows, size_t first, size_t count) {
  double s = 0;
  for (size_t i = first; i < first + count; ++i) s += rows.at(i).terms.at("total");
  return s / count;
}

// Starts (or resumes) `weft train` on the tiny config; SIGKILLs it once losses.csv has a
// row for `kill_at` (or later). Returns the last step it had logged (−1: it ended first).
int64_t run_and_kill(const fs::path& run, int64_t kill_at, bool resume,
                     const std::string& config = repo_file("configs/train/tiny.yaml")) {
  const std::string bin = weft_binary();
  const std::string data = tiny_data().string(), out = run.string();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1), ::dup2(null, 2);
    ::execl(bin.c_str(), bin.c_str(), "train", "--config", config.c_str(), "--data", data.c_str(), "--out",
            out.c_str(), resume ? "--resume" : static_cast<char*>(nullptr), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int64_t logged = 0;
  // A stall, not a slow machine: one run of the tiny config takes 10–40 s alone, and CI's
  // 2 cores may be shared (the fresh-machine run of 2026-12-03, load 5, hit 120 s).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(300);
  while (std::chrono::steady_clock::now() < deadline) {
    try {
      const auto rows = read_loss_log((run / "losses.csv").string());
      if (!rows.empty()) logged = rows.back().step;
    } catch (const weft::Error&) {  // caught between a rewrite's rename and its row: retry
    }
    if (logged >= kill_at) break;
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return -1;  // finished before the kill: no test
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return logged;
}

}  // namespace

TEST(Training, EveryStageOfTheTinyConfigRunsAndLowersItsLoss) {
  REQUIRE_HUMAN();
  const Fixture& f = fixture();
  const TrainingConfig cfg = load_training_config(repo_file("configs/train/tiny.yaml"));
  const auto rows = read_loss_log((f.reference / "losses.csv").string());
  ASSERT_EQ(int64_t(rows.size()), cfg.total_steps());
  size_t first = 0;
  for (const StageConfig& s : cfg.stages) {
    if (s.kind == StageKind::detector) {  // tiny.yaml trains no person detector
      EXPECT_EQ(s.steps, 0);
      continue;
    }
    ASSERT_GE(s.steps, 6) << stage_name(s.kind);
    EXPECT_EQ(rows[first].stage, stage_name(s.kind));
    const double start = mean_total(rows, first, 3), end = mean_total(rows, first + s.steps - 3, 3);
    EXPECT_LT(end, start) << "stage " << stage_name(s.kind) << ": mean loss of its first 3 steps " << start
                          << ", of its last 3 " << end;
    first += s.steps;
  }
  // The physics stage simulated windows and used some of them.
  EXPECT_GT(f.simulation_windows, 0);
  EXPECT_LT(f.simulation_failures, f.simulation_windows);
  bool simulated = false;
  for (const LossRow& r : rows) simulated |= r.terms.count("simulation") > 0;
  EXPECT_TRUE(simulated) << "no step of the physics stage had a converged window";
  // Every window is in windows.csv with its start's penetration, status and Newton
  // iterations; the silhouette constraint had rays, and converged windows kept all F − 1
  // simulated frames as targets.
  std::istringstream windows(slurp(f.reference / "windows.csv"));
  std::string line;
  std::getline(windows, line);
  EXPECT_EQ(line, "step,window,frame,start_max_mm,start_inside,cleaned_inside,cleanup_iterations,status,"
                  "newton_iterations,frames_kept,rays");
  int logged = 0, with_rays = 0;
  while (std::getline(windows, line)) {
    std::vector<std::string> c;
    std::stringstream ss(line);
    for (std::string v; std::getline(ss, v, ',');) c.push_back(v);
    ASSERT_EQ(c.size(), 11u) << line;
    ++logged;
    with_rays += std::stoi(c[10]) > 0;
    EXPECT_GT(std::stoi(c[8]), 0) << line;
    if (c[7] == "converged") EXPECT_EQ(std::stoi(c[9]), cfg.physics.window_frames - 1) << line;
    else EXPECT_LT(std::stoi(c[9]), cfg.physics.window_frames - 1) << line;
  }
  EXPECT_EQ(logged, f.simulation_windows);
  EXPECT_GT(with_rays, 0);
  for (const char* file : {"losses.csv", "losses.png", "validation.csv", "validation.png", "config.yaml",
                           "model.safetensors"})
    EXPECT_TRUE(fs::exists(f.reference / file)) << file;
  // The learning curve's figures: the articulated pose's error and the root orientation's.
  std::istringstream validation(slurp(f.reference / "validation.csv"));
  std::string header, row, last;
  std::getline(validation, header);
  EXPECT_EQ(header,
            "step,samples,keypoint_error_px,joint_error_mm,silhouette_iou,penetration_mean_mm,penetration_max_mm,"
            "penetrating_fraction,joint_error_root_relative_mm,root_rotation_median_deg,root_rotation_above_45,"
            "root_heading_median_deg,root_heading_above_45");
  while (std::getline(validation, row)) last = row;
  std::vector<double> c;
  std::stringstream cells(last);
  for (std::string v; std::getline(cells, v, ',');) c.push_back(std::stod(v));
  ASSERT_EQ(c.size(), 13u) << last;
  EXPECT_GT(c[8], 0.0) << last;  // an untrained PoseNet's articulated pose is off
  EXPECT_TRUE(c[9] >= 0 && c[9] <= 180) << last;
  EXPECT_TRUE(c[10] >= 0 && c[10] <= 1) << last;
  EXPECT_TRUE(c[11] >= 0 && c[11] <= c[9] + 1e-9) << last;  // the heading is part of the rotation's error
  EXPECT_TRUE(c[12] >= 0 && c[12] <= 1) << last;
  EXPECT_GE(f.validation_iou, 0.0);
  EXPECT_GT(f.validation_samples, 0);
}

// A SIGKILL in the middle of each stage, then --resume (one run killed three times: in
// the pose stage, then in the warm start, then in the physics stage): every step's loss is
// bit-identical to the uninterrupted run's (losses.csv prints 9 significant digits of each
// float32 loss; the files are compared whole).
// The true root orientation that validation and the split evaluation measure PoseNet's
// against is the rotation that places the root chain as a prediction does: with any root
// transform (every root-chain dof moved) and the rest of the skeleton at rest, each body
// vertex is R (x0 − p0) + pivot, x0 its rest position and p0 the rest pivot.
TEST(Training, RootRotationWorldPlacesTheBodyAsAPredictionDoes) {
  const DatasetInfo info = read_dataset_info(tiny_data().string());
  const Character ch = load_character(info.character);
  const PoseParametrisation param = pose_parametrisation(ch);
  ASSERT_FALSE(param.root_dofs.empty());
  const PosedCharacter rest = pose_character(ch, ch.rest_dofs);
  EXPECT_LT((root_rotation_world(ch, param, rest) - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  Eigen::VectorXd dofs = ch.rest_dofs;
  const double moves[] = {0.3, -0.2, 0.15, 2.5, -0.7, 1.1};
  for (size_t i = 0; i < param.root_dofs.size(); ++i) dofs[param.root_dofs[i]] += moves[i % 6];
  const PosedCharacter posed = pose_character(ch, dofs);
  const Eigen::Matrix3d R = root_rotation_world(ch, param, posed);
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-9);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
  EXPECT_GT(rotation_error_deg(R, Eigen::Matrix3d::Identity()), 10.0);  // the moves turned it
  const Eigen::Vector3d pivot = posed.joints[param.pivot_joint].translation();
  const Vertices expected = ((rest.body.rowwise() - param.pivot.transpose()) * R.transpose()).rowwise() +
                            pivot.transpose();
  EXPECT_LT((posed.body - expected).cwiseAbs().maxCoeff(), 1e-6 / ch.metres_per_unit);
}

TEST(Training, ResumeAfterSigkillInEachStageGivesTheSameLosses) {
  REQUIRE_HUMAN();
  ASSERT_TRUE(fs::exists(weft_binary())) << weft_binary();
  const Fixture& f = fixture();
  const std::string expected = slurp(f.reference / "losses.csv");
  const TrainingConfig cfg = load_training_config(repo_file("configs/train/tiny.yaml"));
  const fs::path run = training_scratch_root() / "killed";
  int64_t stage_start = 0, last_steps = 0;
  for (const StageConfig& s : cfg.stages) {
    if (s.steps == 0) continue;  // a stage the config skips (the detector)
    last_steps = s.steps;
    const int64_t kill_at = stage_start + s.steps / 2 + 1;  // after a checkpoint inside the stage
    const int64_t logged = run_and_kill(run, kill_at, stage_start > 0);
    ASSERT_GE(logged, kill_at) << "the run ended or stalled before step " << kill_at;
    ASSERT_LT(logged, stage_start + s.steps) << "killed after the stage " << stage_name(s.kind) << " ended";
    stage_start += s.steps;
  }
  TrainOptions o;
  o.config = repo_file("configs/train/tiny.yaml");
  o.data = f.data.string();
  o.run = run.string();
  o.resume = true;
  const TrainSummary r = train(o);
  EXPECT_GT(r.first_step, stage_start - last_steps) << "resumed from before the last stage";
  EXPECT_EQ(slurp(run / "losses.csv"), expected);
}

// oracle_pose: the deformation stages pose the character by gt/pose.motion, so the
// validated joints are the ground truth's (PoseNet is never trained), the physics stage
// runs its windows on the true bodies; without gt/pose.motion it is one clear error.
TEST(Training, OraclePoseDrivesTheDeformationStagesByTheGroundTruth) {
  REQUIRE_HUMAN();
  const fs::path dir = training_scratch_root() / "oracle";
  fs::create_directories(dir);
  const fs::path config = dir / "oracle.yaml";
  std::ofstream(config) << "seed: 3\noracle_pose: true\nnetwork: {backbone: resnet18, input_size: 64}\n"
                           "stages:\n  warmup: {steps: 3, batch_size: 4, lr: 1.0e-3, landmarks: 1, silhouette: 1, "
                           "arap: 10, attachment: 10}\n  physics: {steps: 2, batch_size: 6, lr: 5.0e-4, landmarks: 1, "
                           "silhouette: 1, simulation: 1, attachment: 10}\n"
                           "physics: {window_frames: 3, max_iterations: 60, tolerance: 1.0e-2}\n"
                           "silhouette_size: 64\nloader_threads: 0\nvalidate_every: 0\nvalidation_samples: 8\n";
  TrainOptions o;
  o.config = config.string();
  o.data = tiny_data().string();
  o.run = (dir / "run").string();
  const TrainSummary summary = train(o);
  EXPECT_GT(summary.simulation_windows, 0);
  std::istringstream validation(slurp(dir / "run" / "validation.csv"));
  std::string header, row;
  std::getline(validation, header);
  ASSERT_TRUE(std::getline(validation, row)) << "no validation row";
  std::vector<std::string> c;
  std::stringstream ss(row);
  for (std::string v; std::getline(ss, v, ',');) c.push_back(v);
  ASSERT_EQ(c.size(), 13u) << row;
  // Only PADefNet's graph moves the keypoints off the ground truth's (by millimetres after
  // 5 steps; an untrained PoseNet is hundreds of millimetres off).
  EXPECT_LT(std::stod(c[3]), 20.0) << "joint error (mm) under the oracle pose: " << row;
  EXPECT_LT(std::stod(c[8]), 20.0) << "root-relative joint error (mm) under the oracle pose: " << row;
  EXPECT_EQ(c[9], "nan") << "the oracle's root rotation is the truth's: not measured: " << row;
  // Its evaluation poses by the ground truth too: no root rotation to measure.
  const nlohmann::json ev = nlohmann::json::parse(
      evaluate_split(config.string(), tiny_data().string(), (dir / "run" / "model.safetensors").string(), "val")
          .to_json());
  EXPECT_TRUE(ev["oracle_pose"].get<bool>());
  EXPECT_TRUE(ev["root_rotation_error_deg"].is_null());
  EXPECT_LT(ev["joint_error_mm"].get<double>(), 20.0);

  // Without PADefNet the oracle prediction is the ground truth's posed template.
  const DatasetInfo info = read_dataset_info(tiny_data().string());
  const Character ch = load_character(info.character);
  const CaptureModel model(ch, NetworkConfig{});
  const Motion gt = read_motion((tiny_data() / "gt" / "pose.motion").string(), int(ch.rest_dofs.size()));
  const int64_t D = gt.dofs.cols();
  std::vector<double> d;
  for (int f = 0; f < 2; ++f)
    for (int64_t k = 0; k < D; ++k) d.push_back(gt.dofs(f, k));
  const CapturePrediction p =
      model.predict_posed(weft::Tensor::from_data({2, D}, d, weft::DType::F32), weft::Tensor());
  const double mm = 1e-3 / ch.metres_per_unit;  // float32 posing: within a millimetre
  for (int f = 0; f < 2; ++f) {
    const PosedCharacter posed = pose_character(ch, gt.dofs.row(f).transpose());
    EXPECT_LT((sample_vertices(p.body, f) - posed.body).cwiseAbs().maxCoeff(), mm) << "frame " << f;
    EXPECT_LT((sample_vertices(p.cloth, f) - posed.cloth).cwiseAbs().maxCoeff(), mm) << "frame " << f;
  }

  const fs::path no_gt = dir / "no_gt";
  fs::copy(tiny_data(), no_gt, fs::copy_options::recursive);
  fs::remove(no_gt / "gt" / "pose.motion");
  o.data = no_gt.string();
  o.run = (dir / "run_no_gt").string();
  weft::capture::testing::expect_error([&] { train(o); }, {"oracle_pose", "pose.motion", "does not exist"});
}

// The evaluation of a trained model on a split (`weft train --evaluate`): every prediction
// (frame × input view) has its row, the summary is the rows' pooled figures, the garment's
// out-of-balance force is measured on every frame with two predecessors in its view and
// split into its terms, and what is not measured is null.
TEST(Training, SplitEvaluationMeasuresEveryPrediction) {
  REQUIRE_HUMAN();
  const Fixture& f = fixture();
  const SplitEvaluation e = evaluate_split(repo_file("configs/train/tiny.yaml"), f.data.string(),
                                           (f.reference / "model.safetensors").string(), "train");
  const nlohmann::json j = nlohmann::json::parse(e.to_json());
  EXPECT_EQ(j["split"], "train");
  EXPECT_FALSE(j["oracle_pose"].get<bool>());
  const int frames = j["frames"], views = j["views"];
  EXPECT_EQ(frames, 4);
  ASSERT_EQ(int(j["per_frame"].size()), frames * views);
  EXPECT_EQ(j["predictions"], frames * views);
  // Frames 0..3 of one clip: frames 2 and 3 of each view have two predecessors.
  EXPECT_EQ(j["oob_frames"], 2 * views);
  int with_force = 0;
  double sum_cloth = 0, sum_force = 0;
  for (const auto& row : j["per_frame"]) {
    ASSERT_TRUE(row["cloth_error_mean_mm"].is_number());
    ASSERT_TRUE(row["cloth_chamfer_mm"].is_number());
    // A surface distance never exceeds the vertex-to-vertex one.
    EXPECT_LE(row["cloth_chamfer_mm"].get<double>(), row["cloth_error_mean_mm"].get<double>() + 1e-9);
    sum_cloth += row["cloth_error_mean_mm"].get<double>();
    const int frame = row["frame"];
    if (frame >= 2) {
      ++with_force;
      sum_force += row["oob_force_mean_n"].get<double>();
      EXPECT_GE(row["oob_force_p95_n"].get<double>(), 0.0);
      EXPECT_LE(row["oob_force_p95_n"].get<double>(), row["oob_force_max_n"].get<double>());
      EXPECT_TRUE(row["inertia_mean_n"].is_number() && row["elastic_mean_n"].is_number() &&
                  row["collision_mean_n"].is_number() && row["friction_mean_n"].is_number());
    } else {
      EXPECT_TRUE(row["oob_force_mean_n"].is_null()) << "frame " << frame << " has no two predecessors";
    }
  }
  EXPECT_EQ(with_force, 2 * views);
  EXPECT_NEAR(j["cloth_error_mm"].get<double>(), sum_cloth / (frames * views), 1e-6);
  // Every measured frame has the same free vertices: the pooled mean is the frames' mean.
  EXPECT_NEAR(j["oob_force_n"]["mean"].get<double>(), sum_force / with_force, 1e-9);
  EXPECT_LE(j["oob_force_n"]["p95"].get<double>(), j["oob_force_n"]["p99"].get<double>());
  EXPECT_LE(j["oob_force_n"]["p99"].get<double>(), j["oob_force_n"]["max"].get<double>());
  EXPECT_TRUE(j["root_rotation_error_deg"].is_number());
  EXPECT_GT(j["penetration_mean_all_mm"].get<double>(), -1e-12);
}

TEST(Training, AMissingKeypointFileIsAnErrorNamingIt) {
  REQUIRE_HUMAN();
  const fs::path data = training_scratch_root() / "missing_file";
  fs::copy(tiny_data(), data, fs::copy_options::recursive);
  const fs::path gone = data / "keypoints" / "cam03" / "0002_keypoints.json";
  ASSERT_TRUE(fs::remove(gone));
  TrainOptions o;
  o.config = repo_file("configs/train/tiny.yaml");
  o.data = data.string();
  o.run = (training_scratch_root() / "missing_file_run").string();
  try {
    train(o);
    FAIL() << "expected an error";
  } catch (const weft::Error& e) {
    EXPECT_NE(std::string(e.what()).find(gone.string()), std::string::npos) << e.what();
  }
}

// Absurd detections make the landmark loss infinite: a run resumed on such data stops at
// that step with an error naming it and the term, and the checkpoint it resumed from is
// untouched, finite and loadable.
TEST(Training, ANonFiniteLossStopsTheRunAndNeverReachesACheckpoint) {
  REQUIRE_HUMAN();
  const fs::path data = training_scratch_root() / "absurd_keypoints";
  fs::copy(tiny_data(), data, fs::copy_options::recursive);
  TrainOptions o;
  o.config = repo_file("configs/train/tiny.yaml");
  o.data = data.string();
  o.run = (training_scratch_root() / "nan_run").string();
  o.stop_after = 5;
  train(o);
  const fs::path checkpoint = fs::path(o.run) / "checkpoints" / "step_0000005.safetensors";
  ASSERT_TRUE(fs::exists(checkpoint));
  const std::string before = slurp(checkpoint);
  // Every view of every train frame: whichever frame the next batch holds has one.
  for (const auto& view : fs::directory_iterator(data / "keypoints"))
    for (const auto& file : fs::directory_iterator(view.path())) {
      OpenPoseFrame frame = read_openpose_json(file.path().string());
      if (frame.people.empty()) continue;
      frame.people[0](1, 0) = 1e300;  // the neck 1e300 px to the right: finite in the file, not in float32
      write_openpose_json(file.path().string(), frame);
    }
  o.stop_after = -1;
  o.resume = true;
  try {
    train(o);
    FAIL() << "expected the non-finite loss to stop the run";
  } catch (const weft::Error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("step 6"), std::string::npos) << m;
    EXPECT_NE(m.find("landmarks"), std::string::npos) << m;
  }
  EXPECT_EQ(slurp(checkpoint), before);
  const TrainingConfig cfg = load_training_config(o.config);
  for (const auto& entry : fs::directory_iterator(fs::path(o.run) / "checkpoints")) {
    const Character ch = load_character((data / "character" / "character.yaml").string());
    CaptureNetworks nets(ch, cfg.network, 0);
    weft::nn::load_checkpoint(entry.path().string(), nets, nullptr, nullptr);
    for (const auto& p : nets.named_parameters())
      for (int64_t i = 0; i < p.tensor.numel(); ++i)
        ASSERT_TRUE(std::isfinite(p.tensor.data<float>()[i])) << entry.path() << ": " << p.name;
  }
}

// The networks' parametrisation can say what the ground truth says: PoseNet outputs made
// from gt/pose.motion (the regressed dofs, and the 6D rotation R_c R_gt C) give back the
// true root rotation and articulation exactly, and the keypoints to the closed-form
// translation's accuracy from the noisy detections.
TEST(CaptureModel, ExpressesTheGroundTruthPose) {
  REQUIRE_HUMAN();
  const fs::path data = tiny_data();
  const DatasetInfo info = read_dataset_info(data.string());
  const Character ch = load_character(info.character);
  const TrainingConfig cfg = load_training_config(repo_file("configs/train/tiny.yaml"));
  const CaptureModel model(ch, cfg.network);
  const PoseParametrisation& param = model.parametrisation();
  const Motion motion = read_motion((data / "gt" / "pose.motion").string(), int(ch.rest_dofs.size()));
  const std::vector<int> frames = {0, 3, 5};
  const MultiviewSupervision sup(info, frames, 64);
  const Eigen::Matrix3d rest = forward_kinematics(ch.skeleton, ch.rest_dofs)[param.pivot_joint].linear();
  const Eigen::Matrix3d C = Eigen::Vector3d(1, -1, -1).asDiagonal();
  for (int frame : frames) {
    const PosedCharacter gt = pose_character(ch, motion.dofs.row(frame).transpose());
    const Eigen::Matrix3d R_gt = gt.joints[param.pivot_joint].linear() * rest.transpose();
    for (int v : {0, 5}) {
      const Camera& cam = sup.camera(frame, v);
      const Eigen::Matrix3d relative = cam.R * R_gt * C;  // R_world = R_cᵀ R(α) C
      const Eigen::VectorXd free = model.pose_dofs().outputs_for(motion.dofs.row(frame).transpose());
      std::vector<double> out(free.data(), free.data() + free.size());
      for (int c = 0; c < 2; ++c)
        for (int r = 0; r < 3; ++r) out.push_back(relative(r, c) - (r == c ? 1.0 : 0.0));
      std::vector<std::vector<KeypointView>> views(1);
      for (int w = 0; w < sup.views(); ++w) views[0].push_back({sup.camera(frame, w), sup.detections(frame, w)});
      const SampleViews placed = sample_views({cam}, views, model.keypoint_mask(), weft::DType::F32);
      const CapturePrediction p = model.predict(
          weft::Tensor::from_data({1, int64_t(out.size())}, out, weft::DType::F32), weft::Tensor(), placed);
      Eigen::Matrix3d R;
      for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = p.rotation.data<float>()[i];
      EXPECT_LT((R - R_gt).norm(), 1e-5) << "frame " << frame << " view " << v;
      const Eigen::Vector3d t(p.translation.data<float>()[0], p.translation.data<float>()[1],
                              p.translation.data<float>()[2]);
      EXPECT_LT((t - gt.joints[param.pivot_joint].translation()).norm(), 0.02) << "translation, m";
      const Vertices K = sample_vertices(p.keypoints, 0);
      for (int m = 0; m < kBody25Count; ++m) {
        if (model.keypoint_mask()[m] <= 0) continue;
        const Eigen::Vector3d local = R.transpose() * (K.row(m).transpose() - t);
        const Eigen::Vector3d gt_local =
            R_gt.transpose() * (gt.body25.row(m).transpose() - gt.joints[param.pivot_joint].translation());
        EXPECT_LT((local - gt_local).norm(), 1e-5) << "keypoint " << m << " in the root frame, m";
      }
      const Vertices body = sample_vertices(p.body, 0);
      const Eigen::RowVector3d shift = (t - gt.joints[param.pivot_joint].translation()).transpose();
      EXPECT_LT(((body.rowwise() - shift) - gt.body).rowwise().norm().maxCoeff(), 1e-4) << "body vertices, m";
    }
  }
}

// network.keypoint_input: PoseNet's lifting branch reads the input view's detections
// (crop positions scaled to ±0.5, confidences, the crop centre's ray), starts as no change
// to the ResNet's output, learns from a loss on the output, and is saved and read back
// with the networks.
TEST(CaptureNetworks, TheKeypointBranchReadsTheDetectionsLearnsAndIsSaved) {
  REQUIRE_HUMAN();
  const fs::path data = tiny_data();
  const DatasetInfo info = read_dataset_info(data.string());
  const Character ch = load_character(info.character);
  NetworkConfig config;
  config.input_size = 64;
  config.keypoint_input = true;
  DatasetOptions options;
  options.input_size = config.input_size;
  const SyntheticDataset ds(data.string(), options);
  Batch batch = make_batch({ds.load(0), ds.load(1)});
  float* k = batch.keypoints.data<float>();
  k[3 * 4 + 2] = 0;  // sample 0 loses its right wrist's detection

  const weft::Tensor x = keypoint_lift_input(batch, config.input_size);
  ASSERT_EQ(x.size(0), 2);
  ASSERT_EQ(x.size(1), kLiftInputs);
  const float* in = x.data<float>();
  int detected = 0;
  for (int b = 0; b < 2; ++b)
    for (int j = 0; j < kBody25Count; ++j) {
      const float* d = k + (b * kBody25Count + j) * 3;
      const float* r = in + b * kLiftInputs + 3 * j;
      if (d[2] > 0) {
        ++detected;
        EXPECT_NEAR(r[0], d[0] / 64.0 - 0.5, 1e-6);
        EXPECT_NEAR(r[1], d[1] / 64.0 - 0.5, 1e-6);
        EXPECT_NEAR(r[2], d[2], 1e-6);
        EXPECT_LT(std::abs(r[0]), 0.5 + 1e-6) << "a detection inside the crop is within ±0.5";
      } else {
        EXPECT_EQ(r[0], 0.f);
        EXPECT_EQ(r[1], 0.f);
        EXPECT_EQ(r[2], 0.f);
      }
    }
  EXPECT_GT(detected, 20);
  EXPECT_EQ(in[3 * 4 + 2], 0.f) << "the dropped detection reads as none";
  // The ray's last two inputs: the camera-frame direction (x/z, y/z, 1) that projects to the
  // crop's centre.
  for (int b = 0; b < 2; ++b) {
    const Camera& cam = batch.cameras[size_t(b)];
    const Eigen::Vector3d ray(in[b * kLiftInputs + 75], in[b * kLiftInputs + 76], 1.0);
    const Eigen::Vector3d world = cam.R.transpose() * (3.0 * ray - cam.t);
    const Eigen::Vector2d uv = cam.project(world);
    EXPECT_NEAR(uv.x(), 32.0, 0.05);
    EXPECT_NEAR(uv.y(), 32.0, 0.05);
  }

  CaptureNetworks nets(ch, config, 7);
  ASSERT_TRUE(nets.pose_lift);
  nets.pose_net->train(false);
  weft::Tensor with_branch, image_only;
  {
    weft::NoGradGuard no_grad;
    with_branch = nets.pose(batch);
    image_only = nets.pose_net->forward(batch.images);
  }
  for (int64_t i = 0; i < with_branch.numel(); ++i)
    ASSERT_EQ(with_branch.data<float>()[i], image_only.data<float>()[i]) << "the branch starts at zero";

  std::vector<weft::nn::NamedTensor> params = nets.pose_parameters();
  int lift_params = 0;
  for (const auto& p : params) lift_params += p.name.rfind("pose_lift.", 0) == 0;
  EXPECT_EQ(lift_params, 6) << "three linear layers' weights and biases";
  weft::nn::AdamWOptions o;
  o.lr = 1e-3;
  weft::nn::AdamW opt(params, o);
  // Pull PoseNet's first output toward 1 for sample 0: only the detections tell the
  // branch's contribution apart between the two samples.
  double first = 0, last = 0;
  for (int step = 0; step < 20; ++step) {
    opt.zero_grad();
    const weft::Tensor out = nets.pose(batch);
    const weft::Tensor loss = weft::ops::sum(weft::ops::mul(weft::ops::add_scalar(weft::ops::slice(out, 1, 0, 1), -1.0),
                                                            weft::ops::add_scalar(weft::ops::slice(out, 1, 0, 1), -1.0)));
    const double value = loss.item();
    if (step == 0) first = value;
    last = value;
    loss.backward();
    opt.step();
  }
  EXPECT_LT(last, 0.5 * first) << "the loss falls";
  weft::Tensor learnt;
  {
    weft::NoGradGuard no_grad;
    learnt = nets.pose(batch);
  }
  const fs::path file = training_scratch_root() / "keypoint_branch.safetensors";
  fs::create_directories(file.parent_path());
  weft::nn::save_weights(file.string(), nets);
  CaptureNetworks read_back(ch, config, 99);
  weft::nn::load_weights(file.string(), read_back);
  read_back.pose_net->train(false);
  weft::NoGradGuard no_grad;
  const weft::Tensor again = read_back.pose(batch);
  for (int64_t i = 0; i < learnt.numel(); ++i)
    ASSERT_EQ(again.data<float>()[i], learnt.data<float>()[i]) << "output " << i << " after save and load";
  // The branch changed the output: without it the networks read back differ.
  const weft::Tensor without = read_back.pose_net->forward(batch.images);
  double moved = 0;
  for (int64_t i = 0; i < learnt.numel(); ++i)
    moved = std::max(moved, double(std::abs(learnt.data<float>()[i] - without.data<float>()[i])));
  EXPECT_GT(moved, 1e-4);

  // network.lift_width and lift_layers shape the branch: 4 hidden layers of 32 units.
  NetworkConfig narrow = config;
  narrow.lift_width = 32;
  narrow.lift_layers = 4;
  CaptureNetworks deep(ch, narrow, 7);
  std::vector<weft::Shape> shapes;
  for (const auto& p : deep.pose_parameters())
    if (p.name.rfind("pose_lift.", 0) == 0) shapes.push_back(p.tensor.shape());
  ASSERT_EQ(shapes.size(), 10u) << "five linear layers' weights and biases";
  int64_t inputs = kLiftInputs;
  for (size_t i = 0; i < shapes.size(); i += 2) {
    const int64_t outputs = i + 2 < shapes.size() ? 32 : deep.pose_outputs();
    const weft::Shape& w = shapes[i];
    ASSERT_EQ(w.size(), 2u);
    EXPECT_EQ(w[0] * w[1], inputs * outputs) << "layer " << i / 2;
    EXPECT_TRUE(w[0] == outputs || w[1] == outputs) << "layer " << i / 2;
    inputs = outputs;
  }
  // A model saved with the default branch does not load into the deep one: the error says so.
  EXPECT_THROW(weft::nn::load_weights(file.string(), deep), std::exception);
}

// The detector stage (network.detector, stages.detector) trains the person detector alone on
// the dataset's crops: its loss falls, losses.csv has its terms and figures, the other
// networks are untouched, and the model folder's detector finds the person in the dataset's
// own frames with `weft detect`'s entry point (OpenPose JSON and masks, measured against the
// dataset).
TEST(Training, TheDetectorStageTrainsTheDetectorAndWeftDetectUsesIt) {
  REQUIRE_HUMAN();
  const fs::path root = training_scratch_root() / "detector";
  fs::create_directories(root);
  const fs::path config = root / "detector.yaml";
  std::ofstream(config) << "seed: 5\n"
                           "network: {backbone: resnet18, input_size: 64, detector: {input_size: 64, width: 8}}\n"
                           "stages:\n"
                           "  detector: {steps: 12, batch_size: 8, lr: 3.0e-3, final_lr_fraction: 1, heatmaps: 1, mask: 1}\n"
                           "detector_augmentation: {shift: 0.05, brightness: 0.1}\n"
                           "loader_threads: 0\nlog_every: 6\nvalidate_every: 0\nvalidation_samples: 2\n"
                           "checkpoint_every: 6\nkeep_checkpoints: 1\n";
  TrainOptions o;
  o.config = config.string();
  o.data = tiny_data().string();
  o.run = (root / "run").string();
  train(o);
  const auto rows = read_loss_log((root / "run" / "losses.csv").string());
  ASSERT_EQ(rows.size(), 12u);
  for (const LossRow& r : rows) {
    EXPECT_EQ(r.stage, "detector");
    for (const char* term : {"heatmaps", "mask", "detector_px", "detector_iou"}) EXPECT_TRUE(r.terms.count(term)) << term;
  }
  EXPECT_LT(mean_total(rows, 9, 3), mean_total(rows, 0, 3));

  // Killed inside the detector stage (after its checkpoint at step 6) and resumed, the run
  // logs the same losses as the uninterrupted one.
  ASSERT_TRUE(fs::exists(weft_binary())) << weft_binary();
  const fs::path killed = root / "killed";
  fs::remove_all(killed);
  const int64_t logged = run_and_kill(killed, 7, false, config.string());
  ASSERT_GE(logged, 7) << "the run ended or stalled before step 7";
  ASSERT_LT(logged, 12) << "killed after the stage ended";
  TrainOptions resumed = o;
  resumed.run = killed.string();
  resumed.resume = true;
  EXPECT_GT(train(resumed).first_step, 1) << "resumed from the start";
  EXPECT_EQ(slurp(killed / "losses.csv"), slurp(root / "run" / "losses.csv"));

  // Only the detector learnt: PoseNet is as initialised with the same seed.
  const TrainingConfig cfg = load_training_config(config.string());
  const Character ch = load_character(read_dataset_info(tiny_data().string()).character);
  CaptureNetworks fresh(ch, cfg.network, cfg.seed), trained(ch, cfg.network, cfg.seed);
  weft::nn::load_weights((root / "run" / "model.safetensors").string(), trained);
  auto identical = [](const weft::Tensor& a, const weft::Tensor& b) {
    return a.numel() == b.numel() && std::equal(a.data<float>(), a.data<float>() + a.numel(), b.data<float>());
  };
  EXPECT_TRUE(identical(trained.pose_net->fc->weight, fresh.pose_net->fc->weight));
  EXPECT_FALSE(identical(trained.detector->named_parameters()[0].tensor, fresh.detector->named_parameters()[0].tensor));

  // Added to a trained model without a detector (--init of a tiny.yaml run, the same networks
  // but the detector): PoseNet and PADefNet stay that model's, the detector learns.
  TrainOptions added = o;
  added.run = (root / "added").string();
  added.init_weights = (fixture().reference / "model.safetensors").string();
  train(added);
  const TrainingConfig tiny = load_training_config(repo_file("configs/train/tiny.yaml"));
  CaptureNetworks base(ch, tiny.network, tiny.seed), with_detector(ch, cfg.network, cfg.seed);
  weft::nn::load_weights(added.init_weights, base);
  weft::nn::load_weights((root / "added" / "model.safetensors").string(), with_detector);
  EXPECT_TRUE(identical(with_detector.pose_net->fc->weight, base.pose_net->fc->weight));
  EXPECT_FALSE(identical(with_detector.pose_net->fc->weight, fresh.pose_net->fc->weight));
  const auto base_deformation = base.deformation_net->named_parameters();
  const auto added_deformation = with_detector.deformation_net->named_parameters();
  ASSERT_EQ(base_deformation.size(), added_deformation.size());
  for (size_t k = 0; k < base_deformation.size(); ++k)
    EXPECT_TRUE(identical(added_deformation[k].tensor, base_deformation[k].tensor)) << added_deformation[k].name;
  EXPECT_FALSE(identical(with_detector.detector->named_parameters()[0].tensor,
                         fresh.detector->named_parameters()[0].tensor));

  DetectOptions d;
  d.model = (root / "run").string();
  d.input = (tiny_data() / "images" / "cam02").string();
  d.out = (root / "detect").string();
  const DetectSummary s = detect_sequence(d);
  EXPECT_EQ(s.frames, read_dataset_info(tiny_data().string()).frames);
  EXPECT_TRUE(fs::exists(root / "detect" / "detect.json"));
  EXPECT_TRUE(fs::exists(root / "detect" / "masks" / "0000.png"));
  const OpenPoseFrame first = read_openpose_json((root / "detect" / "keypoints" / "0000_keypoints.json").string());
  EXPECT_LE(first.people.size(), 1u);
  const DetectionAccuracy a = measure_detections((root / "detect").string(), tiny_data().string(), "cam02");
  EXPECT_EQ(a.iou.size(), size_t(s.frames));
  for (double iou : a.iou) EXPECT_TRUE(iou >= 0 && iou <= 1) << iou;

  // `weft infer` from the pixels alone keeps what the detector gave it (the same as `weft
  // detect`'s), records it in capture.json, and `weft eval` measures those inputs and shows
  // them beside the capture in the report's overlays.
  CaptureOptions c;
  c.model = d.model;
  c.input = d.input;
  c.camera = (tiny_data() / "cameras.yaml").string();
  c.camera_name = "cam02";
  c.out = (root / "capture").string();
  capture_sequence(c);
  const nlohmann::json cap = nlohmann::json::parse(std::ifstream(root / "capture" / "capture.json"));
  EXPECT_EQ(cap["masks_from"], "detector");
  EXPECT_EQ(cap["keypoints_from"], "detector");
  EXPECT_EQ(cap["detections"], "detections");
  for (const char* name : {"0000", "0005"}) {
    const cv::Mat by_infer = cv::imread((root / "capture" / "detections" / "masks" / (name + std::string(".png"))).string(),
                                        cv::IMREAD_GRAYSCALE);
    const cv::Mat by_detect = cv::imread((root / "detect" / "masks" / (name + std::string(".png"))).string(),
                                         cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(by_infer.empty()) << name;
    EXPECT_EQ(cv::countNonZero(by_infer != by_detect), 0) << name;
    const std::string kp = name + std::string("_keypoints.json");
    EXPECT_EQ(read_openpose_json((root / "capture" / "detections" / "keypoints" / kp).string()).people.size(),
              read_openpose_json((root / "detect" / "keypoints" / kp).string()).people.size());
  }
  EvaluationOptions eo;
  eo.prediction = c.out;
  eo.data = tiny_data().string();
  const CaptureEvaluation ev = evaluate_capture(eo);
  ASSERT_TRUE(ev.detections.has_value());
  EXPECT_EQ(ev.detections->iou, a.iou);  // every frame captured: the same figures as `weft detect --truth`
  write_evaluation_report(ev, (root / "report").string());
  ASSERT_FALSE(ev.overlays.empty());
  const int width = read_dataset_info(tiny_data().string()).image_width;
  EXPECT_EQ(ev.overlays[0].image.cols, 3 * width) << "the detector's inputs, the prediction, the ground truth";
  const nlohmann::json metrics = nlohmann::json::parse(std::ifstream(root / "report" / "metrics.json"));
  EXPECT_TRUE(metrics["detections"]["mask_iou"]["median"].is_number());
  std::ifstream html(root / "report" / "report.html");
  const std::string page((std::istreambuf_iterator<char>(html)), std::istreambuf_iterator<char>());
  EXPECT_NE(page.find("the person detector"), std::string::npos);
  // A detections folder that misses a frame leaves the rest of the evaluation standing.
  fs::remove(root / "capture" / "detections" / "masks" / "0003.png");
  const CaptureEvaluation without = evaluate_capture(eo);
  EXPECT_FALSE(without.detections.has_value());
  ASSERT_FALSE(without.notes.empty());
  EXPECT_NE(without.notes.back().find("0003.png"), std::string::npos) << without.notes.back();
  EXPECT_TRUE(std::isfinite(without.sv_iou));
}
