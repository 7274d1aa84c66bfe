// `weft eval`: the paper's metrics on a captured sequence against a dataset with 3D ground
// truth (capture/evaluation/; docs/EVALUATION.md), with a progress bar, a log summary,
// REPORT_DIR/metrics.json, report.html and the overlays.
#include <spdlog/spdlog.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "capture/evaluation/capture_evaluation.h"
#include "capture/evaluation/evaluation_report.h"

namespace weft::apps {

namespace {

void run_eval(const capture::EvaluationOptions& o, const std::string& out) {
  spdlog::info("weft eval --prediction {} --data {} --out {}{}{}", o.prediction, o.data, out,
               o.view.empty() ? "" : " --view " + o.view, o.gt_translation ? " --gt-translation" : "");
  ProgressBar bar("frames");
  const capture::CaptureEvaluation e =
      capture::evaluate_capture(o, [&](int done, int total) { bar.update(done, total); });
  spdlog::info("{} frames, input view {} of {}, {} ({:.1f} s)", e.frames.size(), e.view, e.views.size(),
               o.gt_translation ? "ground-truth global translation" : "predicted global translation", e.seconds);
  if (e.oob_frames)
    spdlog::info("out-of-balance force over {} frames: mean {:.4g} N ({:.3g} m g), max {:.4g} N ({:.3g} m g); "
                 "ground truth mean {:.4g} N, max {:.4g} N",
                 e.oob_frames, e.oob_n.mean, e.oob_rel.mean, e.oob_n.max, e.oob_rel.max, e.gt_oob_n.mean,
                 e.gt_oob_n.max);
  if (e.has_cloth)
    spdlog::info("penetration: mean {:.3f} cm over penetrating vertices, max {:.2f} mm, {:.2f} % of cloth vertices "
                 "inside (ground truth {:.3f} cm, {:.2f} mm, {:.2f} %)",
                 e.penetration_mean_mm / 10, e.penetration_max_mm, 100 * e.penetrating_fraction,
                 e.gt_penetration_mean_mm / 10, e.gt_penetration_max_mm, 100 * e.gt_penetrating_fraction);
  spdlog::info("silhouette IoU over {} frames: AMVIoU {:.4f}, RVIoU {}, SVIoU {:.4f}", e.iou_frames, e.amv_iou,
               std::isfinite(e.rv_iou) ? fmt::format("{:.4f}", e.rv_iou) : "undefined (one view)", e.sv_iou);
  spdlog::info("3D error: cloth {:.2f} mm mean, {:.2f} mm p95, Chamfer {:.2f} mm; body {:.2f} mm mean, {:.2f} mm p95; "
               "MPJPE {:.2f} mm ({:.2f} mm root-relative); pivot {:.2f} mm",
               e.cloth_error_mean_mm, e.cloth_error_p95_mm, e.cloth_chamfer_mm, e.body_error_mean_mm,
               e.body_error_p95_mm, e.mpjpe_mm, e.mpjpe_root_relative_mm, e.pivot_error_mm);
  spdlog::info("root rotation error: median {:.1f}°, p95 {:.1f}°, {:.1f} % of frames above 45°; heading (about the "
               "vertical): median {:.1f}°, {:.1f} % above 45°; tilt (pelvis pitch and roll): median {:.1f}°; trunk "
               "direction (MidHip → Neck): median {:.1f}°",
               e.root_rotation_median_deg, e.root_rotation_p95_deg, 100 * e.root_rotation_above_45,
               e.root_heading_median_deg, 100 * e.root_heading_above_45, e.root_tilt_median_deg,
               e.trunk_direction_median_deg);
  spdlog::info("joint error: PA-MPJPE {:.2f} mm; root-relative split along the input camera: depth {:.2f} mm, image "
               "plane {:.2f} mm (mean sizes)",
               e.pa_mpjpe_mm, e.mpjpe_depth_mm, e.mpjpe_image_plane_mm);
  if (e.training_set)
    spdlog::info("against the training set ({} frames × {} views): nearest training pose {:.1f} mm PA; mean training "
                 "pose {:.1f} mm root-relative ({:.1f} PA); 2D retrieval {:.1f} mm root-relative ({:.1f} PA); this "
                 "capture {:.1f} ({:.1f} PA)",
                 e.training_set->training_frames, e.training_set->training_views, e.training_set->nearest_pose_pa_mm,
                 e.training_set->mean_pose_root_relative_mm, e.training_set->mean_pose_pa_mm,
                 e.training_set->nearest_2d_root_relative_mm, e.training_set->nearest_2d_pa_mm,
                 e.mpjpe_root_relative_mm, e.pa_mpjpe_mm);
  for (const std::string& n : e.notes) spdlog::info("note: {}", n);
  capture::write_evaluation_report(e, out);
  spdlog::info("report: {}", (std::filesystem::path(out) / "report.html").string());
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto o = std::make_shared<capture::EvaluationOptions>();
  auto out = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "eval",
      "Measure a captured sequence (the --out folder of `weft infer`) against a dataset with 3D\n"
      "ground truth (a `weft synth` dataset) by the paper's metrics: out-of-balance force of the\n"
      "predicted cloth, penetration of cloth into the body, silhouette IoU over all views / the\n"
      "other views / the input view (AMVIoU, RVIoU, SVIoU), cloth and body vertex error and MPJPE.\n"
      "Writes metrics.json, report.html (viewable offline), joints.csv (predicted and true\n"
      "BODY_25 keypoints per frame) and overlays of the worst\n"
      "and median frames into --out. Definitions and units: docs/EVALUATION.md.");
  cmd->add_option("--prediction", o->prediction,
                  "Capture folder written by `weft infer` (capture.json, meshes/, pose.motion)")
      ->required();
  cmd->add_option("--data", o->data,
                  "Dataset with ground truth (a `weft synth` folder holding dataset.yaml, gt/, masks/, cameras.yaml); "
                  "capture.json's frame ids are its frames")
      ->required();
  cmd->add_option("--out", *out, "Report folder (created if missing): metrics.json, report.html, joints.csv, overlay_*.png")
      ->required();
  cmd->add_option("--view", o->view,
                  "The input view (one of the dataset's views, e.g. cam03): SVIoU is measured in it, RVIoU in the "
                  "others, and the overlays show it (default: capture.json's \"view\")");
  cmd->add_flag("--gt-translation", o->gt_translation,
                "Move each predicted frame (meshes and joints) by the ground-truth pivot joint minus the predicted "
                "one before measuring, as the paper does for every method's 3D comparison");
  cmd->add_option("--iou-every", o->iou_every,
                  "Render the silhouettes for IoU on every N-th captured frame (in frame order; 1: all)")
      ->check(CLI::PositiveNumber)
      ->default_val(1);
  cmd->add_option("--synth-config", o->synth_config,
                  "Synth config whose simulation section gives the cloth material for the out-of-balance force "
                  "(default: the dataset's own, dataset.yaml's simulation section; without either the force is not "
                  "measured)");
  cmd->add_option("--training-data", o->training_data,
                  "A dataset the model trained on (a `weft synth` folder): measure how far each test pose lies from "
                  "the nearest training pose, and score two baselines on the same frames, the mean training pose and "
                  "the training pose whose 2D keypoints are nearest to the input view's detections "
                  "(docs/EVALUATION.md, \"Against the training set\")");
  cmd->add_option("--training-split", o->training_split, "The split of --training-data to compare with")
      ->default_val("train");
  cmd->callback([o, out] { run_eval(*o, *out); });
}

}  // namespace weft::apps
