// `weft eval` on the tiny dataset (configs/synth/tiny.yaml): a capture folder built from
// the dataset's own ground truth (a perfect prediction) has zero vertex and joint error,
// the ground truth's penetration and out-of-balance force, and a high IoU; the same
// prediction moved sideways is wrong by the move unless --gt-translation takes it back;
// the report holds every metric; bad capture folders are errors naming the file.
#include <gtest/gtest.h>

#include <sstream>

#include <numbers>
#include <fmt/format.h>
#include <sys/wait.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/evaluation/capture_evaluation.h"
#include "capture/evaluation/detection_accuracy.h"
#include "capture/evaluation/evaluation_report.h"
#include "geometry/mesh_io.h"
#include "capture/studio/synthetic_studio.h"
#include "capture/model/capture_networks.h"
#include "tests/capture/shared_fixture.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
namespace fs = std::filesystem;
using weft::capture::testing::expect_error;
using weft::capture::testing::repo_file;
using weft::capture::testing::slurp;

namespace {

fs::path eval_scratch_root() { return weft::capture::testing::process_scratch("eval"); }

// The tiny dataset (shared_fixture.h).
fs::path tiny() { return weft::capture::testing::tiny_dataset(); }

// How a capture built from the ground truth is made wrong. Every field has its default:
// a brace-initialised Eigen vector (`{}`) is left uninitialised, which is how a call with
// `{}` for two offsets once read garbage and made this file's results vary from run to run.
struct Perturbation {
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();        // every mesh, joint and pivot (character units)
  Eigen::Vector3d cloth_offset = Eigen::Vector3d::Zero();  // the cloth alone (character units)
  double root_turn_rad = 0;   // added to the root chain's rotation about y (the meshes stay)
  double cloth_turn_rad = 0;  // turns the cloth about the vertical through its centroid
};

// A capture folder holding the dataset's ground truth for `frames`, changed by `change`.
fs::path perfect_capture(const std::string& name, const std::vector<int>& frames, const Perturbation& change = {}) {
  const auto& [offset, cloth_offset, root_turn_rad, cloth_turn_rad] = change;
  const DatasetInfo info = read_dataset_info(tiny().string());
  const Character ch = load_character(info.character);
  const Motion gt = read_motion((tiny() / "gt" / "pose.motion").string(), int(ch.rest_dofs.size()));
  const PoseParametrisation param = pose_parametrisation(ch);
  const fs::path dir = eval_scratch_root() / name;
  fs::remove_all(dir);
  fs::create_directories(dir / "meshes");
  nlohmann::json j = {{"format", "weft-capture/1"},  {"model", "/nowhere/model"},
                      {"character", info.character}, {"metres_per_unit", info.metres_per_unit},
                      {"synth_config", repo_file("configs/synth/tiny.yaml")},
                      {"input", (tiny() / "images" / "cam03").string()},
                      {"camera", (tiny() / "cameras.yaml").string()},
                      {"view", "cam03"},             {"fps", 30},
                      {"collisions_resolved", false}, {"timing", {{"total_s", 0.0}}}};
  Motion m;
  m.dofs.resize(frames.size(), ch.rest_dofs.size());
  const auto pivot_of = [&](const Eigen::VectorXd& dofs) {
    return Eigen::Vector3d(pose_character(ch, dofs).joints[param.pivot_joint].translation());
  };
  for (size_t i = 0; i < frames.size(); ++i) {
    const int f = frames[i];
    m.frame_ids.push_back(f);
    Eigen::VectorXd dofs = gt.dofs.row(f).transpose();
    if (!offset.isZero()) {
      // The root chain's translation moves the pivot linearly: solve for the dofs' change.
      Eigen::MatrixXd J(3, param.root_dofs.size());
      for (size_t k = 0; k < param.root_dofs.size(); ++k) {
        Eigen::VectorXd d = dofs;
        d[param.root_dofs[k]] += 1e-3;
        J.col(k) = (pivot_of(d) - pivot_of(dofs)) / 1e-3;
      }
      const Eigen::VectorXd step = J.completeOrthogonalDecomposition().solve(offset);
      const Eigen::Vector3d before = pivot_of(dofs);
      for (size_t k = 0; k < param.root_dofs.size(); ++k) dofs[param.root_dofs[k]] += step[k];
      EXPECT_LT((pivot_of(dofs) - before - offset).norm(), 1e-9);
    }
    if (root_turn_rad != 0) {
      const int ry = ch.skeleton.dof_index("hips_ry");
      EXPECT_GE(ry, 0);
      dofs[ry] += root_turn_rad;
    }
    m.dofs.row(i) = dofs.transpose();
    const Eigen::Vector3d pivot = pivot_of(dofs);
    j["frames"].push_back(nlohmann::json::object({{"id", f},
                                                  {"source", fmt::format("{:04d}.png", f)},
                                                  {"pivot", {pivot.x(), pivot.y(), pivot.z()}},
                                                  {"translation_from", "ground truth"}}));
    for (const char* part : {"body", "cloth"}) {
      TriangleMesh mesh = read_ply((tiny() / "gt" / fmt::format("{}_{:04d}.ply", part, f)).string());
      mesh.V.rowwise() += offset.transpose();
      if (std::string(part) == "cloth") {
        mesh.V.rowwise() += cloth_offset.transpose();
        if (cloth_turn_rad != 0) {
          const Eigen::RowVector3d c = mesh.V.colwise().mean();
          const Eigen::Matrix3d turn = Eigen::AngleAxisd(cloth_turn_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
          mesh.V = ((mesh.V.rowwise() - c) * turn.transpose()).rowwise() + c;
        }
      }
      write_ply((dir / "meshes" / fmt::format("{}_{:04d}.ply", part, f)).string(), mesh);
    }
  }
  write_motion((dir / "pose.motion").string(), m);
  std::ofstream(dir / "capture.json") << j.dump(1);
  return dir;
}

std::vector<int> all_frames() {
  const DatasetInfo info = read_dataset_info(tiny().string());
  std::vector<int> frames;
  for (int f = 0; f < info.frames; ++f)
    if (!std::count(info.failed_frames.begin(), info.failed_frames.end(), f)) frames.push_back(f);
  return frames;
}

EvaluationOptions options(const fs::path& capture) {
  EvaluationOptions o;
  o.prediction = capture.string();
  o.data = tiny().string();
  return o;
}

}  // namespace

TEST(CaptureEvaluationIntegration, PerfectPredictionHasNoErrorAndTheGroundTruthsPhysics) {
  const std::vector<int> frames = all_frames();
  ASSERT_EQ(frames.size(), 6u);
  const fs::path capture = perfect_capture("perfect", frames);
  const CaptureEvaluation e = evaluate_capture(options(capture));
  ASSERT_EQ(e.frames.size(), frames.size());
  EXPECT_EQ(e.view, "cam03");
  EXPECT_EQ(e.cloth_error_mean_mm, 0.0);
  EXPECT_EQ(e.cloth_error_p95_mm, 0.0);
  EXPECT_EQ(e.body_error_mean_mm, 0.0);
  EXPECT_EQ(e.body_error_p95_mm, 0.0);
  EXPECT_NEAR(e.mpjpe_mm, 0.0, 1e-9);
  EXPECT_NEAR(e.pivot_error_mm, 0.0, 1e-9);
  // The dataset's masks are renders of these meshes at the same cameras: measured 1.000000
  // in every view (the renderer is deterministic), asserted with a margin for the edges.
  EXPECT_GT(e.amv_iou, 0.999);
  EXPECT_GT(e.rv_iou, 0.999);
  EXPECT_GT(e.sv_iou, 0.999);
  EXPECT_EQ(e.iou_frames, 6);
  // Penetration and out-of-balance force are the ground truth's, frame by frame.
  EXPECT_EQ(e.penetration_mean_mm, e.gt_penetration_mean_mm);
  EXPECT_EQ(e.penetration_max_mm, e.gt_penetration_max_mm);
  EXPECT_EQ(e.penetrating_fraction, e.gt_penetrating_fraction);
  EXPECT_EQ(e.oob_frames, 4);  // frames 2..5 have their two predecessors
  EXPECT_EQ(e.oob_n.mean, e.gt_oob_n.mean);
  EXPECT_EQ(e.oob_n.max, e.gt_oob_n.max);
  std::printf("perfect prediction: AMVIoU %.6f RVIoU %.6f SVIoU %.6f; penetration %.4f mm mean, %.4f mm max, %.4f %%; "
              "out-of-balance (free vertices) %.4g m g mean, %.4g m g max, %.4g N max; all vertices %.4g m g mean, "
              "%.4g m g max\n",
              e.amv_iou, e.rv_iou, e.sv_iou, e.penetration_mean_mm, e.penetration_max_mm, 100 * e.penetrating_fraction,
              e.oob_rel.mean, e.oob_rel.max, e.oob_n.max, e.oob_all_rel.mean, e.oob_all_rel.max);
  EXPECT_EQ(e.oob_all_n.mean, e.gt_oob_all_n.mean);
  // Every vertex the attachment does not hold is within the synth's Newton tolerance (10⁻³
  // of its weight) of balance; the anchors carry the hanging skirt (4.8 m g on average
  // over all vertices, measured).
  EXPECT_GT(e.oob_n.max, 0.0);
  EXPECT_LT(e.oob_rel.max, 1e-3);
  EXPECT_GT(e.oob_all_rel.mean, 1.0);
  EXPECT_TRUE(e.notes.empty()) << e.notes.front();
  ASSERT_EQ(e.overlays.size(), 2u);
  EXPECT_EQ(e.overlays[0].label, "worst");
  EXPECT_EQ(e.overlays[0].image.cols, 2 * 256);

  // The report: every metric present.
  const fs::path report = eval_scratch_root() / "report_perfect";
  fs::create_directories(report);
  std::ofstream(report / "overlay_worst_0099.png") << "an earlier report's";
  const std::vector<std::string> written = write_evaluation_report(e, report.string());
  EXPECT_FALSE(fs::exists(report / "overlay_worst_0099.png"));
  EXPECT_EQ(written.size(), 5u);  // two overlays, metrics.json, joints.csv, report.html
  const nlohmann::json j = nlohmann::json::parse(slurp(report / "metrics.json"));
  const nlohmann::json& s = j["summary"];
  for (const char* key : {"mean_n", "max_n", "mean_rel", "max_rel"}) {
    EXPECT_TRUE(s["out_of_balance_force"][key].is_number()) << key;
    EXPECT_TRUE(s["out_of_balance_force"]["ground_truth"][key].is_number()) << key;
  }
  for (const char* key : {"mean_cm", "mean_mm", "max_mm", "fraction_inside"})
    EXPECT_TRUE(s["penetration"][key].is_number()) << key;
  for (const char* key : {"amv", "rv", "sv"}) EXPECT_TRUE(s["iou"][key].is_number()) << key;
  for (const char* key : {"root_rotation_deg", "root_heading_deg", "root_tilt_deg", "trunk_direction_deg"})
    EXPECT_TRUE(s[key]["median"].is_number()) << key;
  EXPECT_TRUE(s["cloth_error_mm"]["p95"].is_number());
  EXPECT_TRUE(s["body_error_mm"]["mean"].is_number());
  EXPECT_TRUE(s["mpjpe_mm"].is_number());
  EXPECT_TRUE(s["mpjpe_root_relative_mm"].is_number());
  EXPECT_TRUE(s["cloth_chamfer_mm"].is_number());
  for (const char* key : {"median", "p95", "fraction_above_45"}) EXPECT_TRUE(s["root_rotation_deg"][key].is_number()) << key;
  EXPECT_TRUE(j["per_frame"]["root_rotation_error_deg"][0].is_number());
  EXPECT_EQ(j["per_frame"]["id"].size(), 6u);
  EXPECT_TRUE(j["per_frame"]["oob_force_mean_n"][0].is_null());  // frame 0 has no predecessors
  EXPECT_TRUE(j["per_frame"]["oob_force_mean_n"][2].is_number());
  EXPECT_EQ(j["per_frame"]["iou_per_view"][0].size(), 8u);
  const std::string html = slurp(report / "report.html");
  for (const char* part : {"AMVIoU", "RVIoU", "SVIoU", "MPJPE", "out-of-balance force, max", "penetration depth",
                           "tilt error", "trunk direction error",
                           "<svg", "overlay_worst_", "overlay_median_"})
    EXPECT_NE(html.find(part), std::string::npos) << part;
  for (const auto& o : j["overlays"]) EXPECT_TRUE(fs::exists(report / o["file"].get<std::string>()));
}

TEST(CaptureEvaluationIntegration, GroundTruthTranslationTakesBackAGlobalShift) {
  const fs::path capture = perfect_capture("shifted", {1, 2, 3}, {.offset = Eigen::Vector3d(0.1, 0, -0.05)});
  EvaluationOptions o = options(capture);
  o.view = "cam01";
  o.iou_every = 2;
  const CaptureEvaluation moved = evaluate_capture(o);
  const double shift_mm = std::hypot(100.0, 50.0);
  EXPECT_NEAR(moved.cloth_error_mean_mm, shift_mm, 1e-6);
  EXPECT_NEAR(moved.body_error_p95_mm, shift_mm, 1e-6);
  EXPECT_NEAR(moved.mpjpe_mm, shift_mm, 1e-6);
  EXPECT_NEAR(moved.pivot_error_mm, shift_mm, 1e-6);
  EXPECT_LT(moved.amv_iou, 0.9);
  EXPECT_EQ(moved.iou_frames, 2);  // frames 1 and 3
  EXPECT_EQ(moved.oob_frames, 1);  // frame 3
  // joints.csv holds the keypoints as measured: their distances average to the MPJPE.
  const fs::path report = eval_scratch_root() / "report_shifted";
  write_evaluation_report(moved, report.string());
  std::istringstream csv(slurp(report / "joints.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "frame,keypoint,predicted_x_m,predicted_y_m,predicted_z_m,true_x_m,true_y_m,true_z_m");
  double sum_mm = 0;
  int rows = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream cells(line);
    for (std::string c; std::getline(cells, c, ',');) f.push_back(c);
    ASSERT_EQ(f.size(), 8u) << line;
    const Eigen::Vector3d p(std::stod(f[2]), std::stod(f[3]), std::stod(f[4])), t(std::stod(f[5]), std::stod(f[6]), std::stod(f[7]));
    sum_mm += (p - t).norm() * 1e3;
    ++rows;
  }
  EXPECT_EQ(rows % int(moved.frames.size()), 0);
  EXPECT_GT(rows, 0);
  EXPECT_NEAR(sum_mm / rows, moved.mpjpe_mm, 1e-2);
  o.gt_translation = true;
  const CaptureEvaluation back = evaluate_capture(o);
  EXPECT_NEAR(back.cloth_error_mean_mm, 0.0, 1e-6);
  EXPECT_NEAR(back.mpjpe_mm, 0.0, 1e-6);
  EXPECT_NEAR(back.pivot_error_mm, shift_mm, 1e-6);  // the error the shift took away
  EXPECT_GT(back.amv_iou, 0.99);
}

TEST(CaptureEvaluationIntegration, RootRotationAndChamferTellATurnedPoseAndATurnedSkirt) {
  const CaptureEvaluation perfect = evaluate_capture(options(perfect_capture("perfect_turn", {1, 2, 3})));
  EXPECT_NEAR(perfect.root_rotation_median_deg, 0.0, 1e-6);
  EXPECT_EQ(perfect.root_rotation_above_45, 0.0);
  EXPECT_NEAR(perfect.mpjpe_root_relative_mm, 0.0, 1e-6);
  EXPECT_NEAR(perfect.cloth_chamfer_mm, 0.0, 1e-9);
  EXPECT_NEAR(perfect.root_tilt_median_deg, 0.0, 1e-6);
  EXPECT_NEAR(perfect.trunk_direction_median_deg, 0.0, 1e-6);
  // The root turned by 1 rad about y: a 57.3° root error in every frame, which a
  // root-relative MPJPE sees too; a skirt turned by 0.2 rad about its axis: a large vertex
  // error but a small surface (Chamfer) distance.
  const CaptureEvaluation turned = evaluate_capture(options(perfect_capture("turned", {1, 2, 3}, {.root_turn_rad = 1.0, .cloth_turn_rad = 0.2})));
  EXPECT_NEAR(turned.root_rotation_median_deg, 180 / std::numbers::pi, 1e-6);
  EXPECT_NEAR(turned.root_rotation_p95_deg, 180 / std::numbers::pi, 1e-6);
  EXPECT_EQ(turned.root_rotation_above_45, 1.0);
  // The turn is about the pelvis's own y axis, which the ground truth's pose leans a little
  // off the vertical: nearly all heading, a little tilt (measured 57.294° and 0.49°).
  EXPECT_NEAR(turned.root_heading_median_deg, 180 / std::numbers::pi, 0.01);
  EXPECT_LT(turned.root_tilt_median_deg, 1.0);
  EXPECT_GT(turned.trunk_direction_median_deg, 0.0);
  EXPECT_GT(turned.mpjpe_root_relative_mm, 100);
  EXPECT_NEAR(turned.body_error_mean_mm, 0.0, 1e-9);  // the meshes did not move
  EXPECT_GT(turned.cloth_error_mean_mm, 20);
  EXPECT_LT(turned.cloth_chamfer_mm, 0.5 * turned.cloth_error_mean_mm);
  std::printf("skirt turned by 0.2 rad: vertex error %.2f mm, Chamfer %.2f mm; root turned 1 rad: MPJPE root-relative "
              "%.1f mm\n",
              turned.cloth_error_mean_mm, turned.cloth_chamfer_mm, turned.mpjpe_root_relative_mm);
}

TEST(CaptureEvaluationIntegration, SkirtMovedIntoTheBodyPenetrates) {
  // The skirt alone moved 3 cm sideways: its vertices on that side go into the hips and legs.
  const fs::path capture = perfect_capture("into_body", {3, 4}, {.cloth_offset = Eigen::Vector3d(0.03, 0, 0)});
  const CaptureEvaluation e = evaluate_capture(options(capture));
  EXPECT_NEAR(e.cloth_error_mean_mm, 30.0, 1e-6);
  EXPECT_EQ(e.body_error_mean_mm, 0.0);
  EXPECT_EQ(e.gt_penetration_max_mm, 0.0);
  EXPECT_GT(e.penetrating_fraction, 0.01);
  EXPECT_GT(e.penetration_mean_mm, 0.0);
  EXPECT_LE(e.penetration_mean_mm, e.penetration_max_mm);
  EXPECT_LT(e.penetration_max_mm, 30.0);  // no deeper than the move
  std::printf("skirt moved 3 cm sideways: %.2f %% of its vertices inside, %.2f mm mean, %.2f mm max\n",
              100 * e.penetrating_fraction, e.penetration_mean_mm, e.penetration_max_mm);
}

TEST(CaptureEvaluationIntegration, WithoutSimulationSettingsTheForceIsSkippedAndSaidSo) {
  const fs::path capture = perfect_capture("no_synth", {0, 1, 2});
  // A dataset from before datasets carried their simulation settings: the tiny dataset's
  // files, its dataset.yaml without the simulation section.
  const fs::path old = eval_scratch_root() / "dataset_without_simulation";
  fs::remove_all(old);
  fs::create_directories(old);
  for (const auto& entry : fs::directory_iterator(tiny()))
    if (entry.path().filename() != "dataset.yaml") fs::create_symlink(entry.path(), old / entry.path().filename());
  const std::string yaml = slurp(tiny() / "dataset.yaml");
  ASSERT_NE(yaml.find("\nsimulation:"), std::string::npos);
  std::ofstream(old / "dataset.yaml") << yaml.substr(0, yaml.find("\nsimulation:") + 1);
  EvaluationOptions o = options(capture);
  o.data = old.string();
  const CaptureEvaluation e = evaluate_capture(o);
  EXPECT_EQ(e.oob_frames, 0);
  EXPECT_TRUE(std::isnan(e.oob_n.mean));
  ASSERT_FALSE(e.notes.empty());
  EXPECT_NE(e.notes.front().find("--synth-config"), std::string::npos);
  // --synth-config supplies it.
  o.synth_config = repo_file("configs/synth/tiny.yaml");
  EXPECT_EQ(evaluate_capture(o).oob_frames, 1);
  // The dataset's own settings are the default.
  EXPECT_EQ(evaluate_capture(options(capture)).oob_frames, 1);
}

TEST(CaptureEvaluationIntegration, BadCaptureFoldersAreErrorsNamingTheFile) {
  const fs::path capture = perfect_capture("bad", {2, 3});
  // A frame the dataset does not have.
  {
    nlohmann::json j = nlohmann::json::parse(slurp(capture / "capture.json"));
    const std::string good = j.dump();
    j["frames"][1]["id"] = 99;
    std::ofstream(capture / "capture.json") << j.dump();
    expect_error([&] { evaluate_capture(options(capture)); },
                 {"capture.json", "frames[1]", "id 99 is not a frame of the dataset", "0..5"});
    std::ofstream(capture / "capture.json") << good;
  }
  // A view the dataset does not have.
  EvaluationOptions o = options(capture);
  o.view = "wild";
  expect_error([&] { evaluate_capture(o); }, {"'wild'", "--view", "dataset.yaml", "cam00"});
  // A mesh of the wrong vertex count.
  const fs::path cloth = capture / "meshes" / "cloth_0003.ply";
  TriangleMesh mesh = read_ply(cloth.string());
  const TriangleMesh original = mesh;
  mesh.V.conservativeResize(mesh.V.rows() - 1, 3);
  mesh.F.resize(0, 3);
  write_ply(cloth.string(), mesh);
  expect_error([&] { evaluate_capture(options(capture)); },
               {"cloth_0003.ply", std::to_string(original.V.rows() - 1) + " vertices, expected " +
                                      std::to_string(original.V.rows())});
  // A missing mesh.
  fs::remove(cloth);
  expect_error([&] { evaluate_capture(options(capture)); }, {"cloth_0003.ply", "missing", "frame 3"});
  write_ply(cloth.string(), original);
  // pose.motion with a row too few.
  Motion m = read_motion((capture / "pose.motion").string());
  m.dofs.conservativeResize(1, m.dofs.cols());
  m.frame_ids.resize(1);
  write_motion((capture / "pose.motion").string(), m);
  expect_error([&] { evaluate_capture(options(capture)); }, {"pose.motion", "1 rows, expected 2"});
  // No capture.json.
  fs::remove(capture / "capture.json");
  expect_error([&] { evaluate_capture(options(capture)); }, {"capture.json", "missing"});
}

TEST(CaptureEvaluationIntegration, TrainingSetComparisonFindsATrainingFrameItself) {
  // A perfect capture of two of the tiny dataset's training frames, compared with that
  // training split: each test pose is a training pose (nearest at 0 mm, itself), the
  // capture has no error, and the mean training pose does not fit exactly.
  const DatasetInfo info = read_dataset_info(tiny().string());
  const std::vector<int>& train = info.splits.at("train");
  ASSERT_GE(train.size(), 2u);
  const std::vector<int> frames = {train[0], train[1]};
  EvaluationOptions o = options(perfect_capture("train_frames", frames));
  o.training_data = tiny().string();
  const CaptureEvaluation e = evaluate_capture(o);
  ASSERT_TRUE(e.training_set);
  ASSERT_EQ(e.training_set->frames.size(), 2u);
  EXPECT_EQ(e.training_set->training_frames, int(train.size()));
  for (size_t k = 0; k < 2; ++k) {
    EXPECT_NEAR(e.training_set->frames[k].nearest_pose_pa_mm, 0, 1e-6);
    EXPECT_EQ(e.training_set->frames[k].nearest_pose_frame, frames[k]);
  }
  EXPECT_NEAR(e.pa_mpjpe_mm, 0, 1e-6);
  EXPECT_NEAR(e.mpjpe_depth_mm, 0, 1e-9);
  ASSERT_EQ(e.joint_error_pa_mm.size(), size_t(kBody25Count));
  EXPECT_GT(e.training_set->mean_pose_root_relative_mm, 1);
  EXPECT_TRUE(std::isfinite(e.training_set->nearest_2d_root_relative_mm));
  // A split the training data does not have: one error naming the file and the split.
  o.training_split = "nope";
  expect_error([&] { evaluate_capture(o); }, {"dataset.yaml", "no split 'nope'"});
}

TEST(CaptureEvaluationIntegration, CommandWritesTheReport) {
  const fs::path capture = perfect_capture("command", {0, 1, 2, 3});
  const fs::path report = eval_scratch_root() / "report_command";
  const std::string cmd = std::string(WEFT_BINARY_DIR) + "/apps/weft eval --prediction " + capture.string() +
                          " --data " + tiny().string() + " --out " + report.string() +
                          " --view cam05 --iou-every 2 --training-data " + tiny().string() + " > " +
                          (eval_scratch_root() / "eval.out").string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << slurp(eval_scratch_root() / "eval.out");
  const nlohmann::json j = nlohmann::json::parse(slurp(report / "metrics.json"));
  EXPECT_EQ(j["view"], "cam05");
  EXPECT_EQ(j["summary"]["iou"]["frames"], 2);
  EXPECT_TRUE(fs::exists(report / "report.html"));
  EXPECT_TRUE(j["summary"]["pa_mpjpe_mm"].is_number());
  EXPECT_EQ(j["summary"]["per_joint"].size(), size_t(kBody25Count));
  EXPECT_EQ(j["training_set"]["per_frame"]["nearest_pose_pa_mm"].size(), 4u);
  EXPECT_NE(slurp(report / "report.html").find("Against the training set"), std::string::npos);
  const std::string log = slurp(eval_scratch_root() / "eval.out");
  EXPECT_NE(log.find("AMVIoU"), std::string::npos) << log;
  EXPECT_NE(log.find("against the training set"), std::string::npos) << log;
  // A missing prediction folder: one error naming it, and no report written.
  const fs::path nothing = eval_scratch_root() / "report_nothing";
  const std::string bad = std::string(WEFT_BINARY_DIR) + "/apps/weft eval --prediction " +
                          (eval_scratch_root() / "no_capture").string() + " --data " + tiny().string() + " --out " +
                          nothing.string() + " > " + (eval_scratch_root() / "bad.out").string() + " 2>&1";
  const int bad_status = std::system(bad.c_str());
  EXPECT_TRUE(WIFEXITED(bad_status) && WEXITSTATUS(bad_status) == 1);
  EXPECT_NE(slurp(eval_scratch_root() / "bad.out").find("no_capture: no such capture folder"), std::string::npos);
  EXPECT_FALSE(fs::exists(nothing / "report.html"));
}

// `weft detect --truth` and `weft eval` count the keypoints hidden behind the body apart:
// detections that are right wherever the studio saw a keypoint and 200 px off wherever it
// hid one (the dataset's own detections tell which: tiny.yaml's gaussian model gives a
// hidden joint confidence 0.3 ± 0.05, a seen one 0.9 ± 0.05) score 100 % over the visible
// keypoints, and over all keypoints only the seen ones' share.
TEST(CaptureEvaluationIntegration, DetectionAccuracyCountsTheHiddenKeypointsApart) {
  const DatasetInfo info = read_dataset_info(tiny().string());
  const Character ch = load_character(info.character);
  const Motion gt = read_motion((tiny() / "gt" / "pose.motion").string(), int(ch.rest_dofs.size()));
  std::map<std::string, Camera> cameras;
  for (Camera& c : read_cameras_yaml((tiny() / "cameras.yaml").string())) cameras[c.name] = c;
  const std::string view = "cam02";  // a side view: one arm and leg behind the body
  const fs::path dir = eval_scratch_root() / "hidden_keypoints";
  fs::create_directories(dir / "masks");
  fs::create_directories(dir / "keypoints");
  size_t hidden = 0, seen = 0;
  for (int f = 0; f < info.frames; ++f) {
    const std::string name = dataset_frame_name(f);
    cv::imwrite((dir / "masks" / (name + ".png")).string(), read_dataset_mask(info, f, view));
    const Body25 labels = read_dataset_keypoints(dataset_keypoints_path(info, f, view));
    const Camera& cam = cameras.at(dataset_camera_name(info, f, view));
    const Vertices body25 = pose_character(ch, gt.dofs.row(f).transpose()).body25;
    Body25 predicted = Body25::Zero();
    for (int m = 0; m < kBody25Count; ++m) {
      if (!body25.row(m).allFinite()) continue;
      const Eigen::Vector2d p = cam.project(body25.row(m).transpose());
      const bool is_hidden = labels(m, 2) > 0 && labels(m, 2) < 0.6;
      hidden += is_hidden;
      seen += labels(m, 2) >= 0.6;
      predicted.row(m) << p.x() + (is_hidden ? 200.0 : 0.0), p.y(), 0.9;
    }
    OpenPoseFrame frame;
    frame.people.push_back(predicted);
    write_openpose_json((dir / "keypoints" / (name + "_keypoints.json")).string(), frame);
  }
  ASSERT_GT(hidden, 0u) << "the side view hides some keypoints";
  const DetectionAccuracy a = measure_detections(dir.string(), tiny().string(), view);
  const DetectionFigures d = detection_figures(a);
  EXPECT_DOUBLE_EQ(d.visible_pck, 1.0) << "every keypoint the camera sees is right";
  EXPECT_GE(d.visible_keypoints, seen);
  EXPECT_LE(d.visible_keypoints + hidden, d.truth_keypoints);
  EXPECT_NEAR(d.truth_pck, double(d.truth_keypoints - hidden) / d.truth_keypoints, 1e-12)
      << "over all keypoints the hidden ones count as wrong";
  EXPECT_LT(d.truth_pck, d.visible_pck);
  const nlohmann::json j = nlohmann::json::parse(detection_accuracy_json(a));
  EXPECT_EQ(j["against_truth"]["visible"]["keypoints"], d.visible_keypoints);
  EXPECT_EQ(j["against_truth"]["visible"]["pck"], 1.0);
}
