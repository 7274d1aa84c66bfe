#pragma once
// `weft eval`: a captured sequence (a `weft infer` capture folder, capture_folder.h)
// measured against a dataset with 3D ground truth (a `weft synth` dataset,
// docs/DATASET.md) by the paper's metrics (docs/EVALUATION.md):
// - out-of-balance force of every three consecutive predicted frames of one clip, mean
//   and max over vertices and frames, in N and relative to a vertex's weight (needs the
//   cloth material: a synth config's simulation section), over the vertices the
//   attachment does not hold and, for reference, over all of them;
// - penetration of cloth vertices into the body: mean over the penetrating vertices and
//   max, and the fraction of cloth vertices inside;
// - silhouette IoU of the rendered body + cloth against the dataset's masks on every N-th
//   frame: over all views (AMVIoU), all but the input view (RVIoU), the input view (SVIoU);
// - 3D error: cloth and body vertex distance (mean and 95th percentile, mm), the cloth's
//   Chamfer distance (a surface distance that a garment turned about its axis does not
//   inflate), MPJPE over the mapped BODY_25 keypoints of the posed skeleton (mm), also
//   root-relative (both pivots at the origin), the pivot joint's distance (the global
//   translation's error, mm) and the root orientation's error (the pivot joint's global
//   rotation, degrees: median, p95 and the fraction of frames above 45°).
// With gt_translation every predicted frame (meshes and joints) is first moved by the
// ground truth's pivot minus the predicted pivot (the paper applies the true global
// translation to every method); every metric then measures the moved frames. The ground
// truth's own penetration and out-of-balance force, measured the same way, are reported
// beside the prediction's as the floor the data allows.
#include <opencv2/core.hpp>

#include <Eigen/Core>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "capture/evaluation/frame_measures.h"
#include "capture/evaluation/detection_accuracy.h"
#include "capture/evaluation/training_set_comparison.h"

namespace weft::capture {

struct EvaluationOptions {
  std::string prediction;    // the capture folder
  std::string data;          // the dataset folder
  std::string view;          // the input view; "" → capture.json's "view"
  bool gt_translation = false;
  int iou_every = 1;         // IoU on every N-th captured frame (in frame-id order), N ≥ 1
  std::string synth_config;  // a synth config whose simulation section overrides the dataset's ("" keeps it)
  std::string training_data;            // a dataset to compare the test poses with ("" none; training_set_comparison.h)
  std::string training_split = "train";  // its split
};


// One captured frame's measures (NaN where not measured).
struct FrameEvaluation {
  int id = 0;
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();  // applied to the prediction (character units)
  FrameMeasures measures;      // the prediction against the ground truth (pivot error: before the shift)
  FrameMeasures ground_truth;  // the ground truth's own penetration and out-of-balance force
  std::vector<double> iou;     // IoU per dataset view (empty: not an IoU frame)
  // The BODY_25 keypoints measured (world, character units; NaN rows unmapped): the
  // prediction's as measured (after the shift) and the ground truth's. joints.csv.
  Vertices predicted_body25, true_body25;
};

// A side-by-side image: the input view with the prediction drawn on it (left) and the
// ground truth drawn on it (right).
struct EvaluationOverlay {
  std::string label;  // "worst", "median"
  int id = 0;
  std::string ranked_by;  // the metric that chose the frame and its value, for captions
  cv::Mat image;          // CV_8UC3 BGR
};

struct CaptureEvaluation {
  EvaluationOptions options;
  std::string view;                // the input view used
  std::vector<std::string> views;  // the dataset's views (the order of FrameEvaluation::iou)
  std::string character;           // character.yaml
  std::string synth_config;        // the file whose simulation section gave the out-of-balance force's
                                   // material: DATA/dataset.yaml or --synth-config ("" none)
  double metres_per_unit = 1, fps = 30;
  bool has_cloth = false;
  std::vector<std::string> notes;  // what could not be measured and why
  std::vector<FrameEvaluation> frames;  // in frame-id order

  // Summary (NaN where not measured).
  int oob_frames = 0, gt_oob_frames = 0;
  // Pooled over the free vertices of every measured frame: mean, p95, p99, max.
  Distribution oob_n, oob_rel, gt_oob_n, gt_oob_rel;
  Distribution oob_all_n, oob_all_rel, gt_oob_all_n, gt_oob_all_rel;  // the same, anchors included
  Distribution oob_outside_n;  // over the free vertices outside the body
  double inertia_mean_n = kNotMeasured, elastic_mean_n = kNotMeasured, collision_mean_n = kNotMeasured,
         friction_mean_n = kNotMeasured;  // the terms the residual balances, mean over free vertices
  double penetration_mean_mm = kNotMeasured, penetration_mean_all_mm = kNotMeasured,
         penetration_max_mm = kNotMeasured, penetrating_fraction = kNotMeasured;
  double gt_penetration_mean_mm = kNotMeasured, gt_penetration_max_mm = kNotMeasured,
         gt_penetrating_fraction = kNotMeasured;
  int iou_frames = 0;
  double amv_iou = kNotMeasured, rv_iou = kNotMeasured, sv_iou = kNotMeasured;
  double cloth_error_mean_mm = kNotMeasured, cloth_error_p95_mm = kNotMeasured;
  double body_error_mean_mm = kNotMeasured, body_error_p95_mm = kNotMeasured;
  double mpjpe_mm = kNotMeasured, pivot_error_mm = kNotMeasured;
  double mpjpe_root_relative_mm = kNotMeasured, cloth_chamfer_mm = kNotMeasured;
  // PA-MPJPE, and the root-relative joint error split into the input camera's depth and
  // its image plane (mean sizes of the components), means over frames.
  double pa_mpjpe_mm = kNotMeasured, mpjpe_depth_mm = kNotMeasured, mpjpe_image_plane_mm = kNotMeasured;
  // Per BODY_25 keypoint (kBody25Names order; NaN: unmapped): the mean over frames of its
  // root-relative error and its error after the Procrustes alignment.
  std::vector<double> joint_error_root_relative_mm, joint_error_pa_mm;
  // The root (pivot joint) orientation's error over frames: median, 95th percentile, and
  // the fraction of frames above 45° (front/back or side confusions).
  double root_rotation_median_deg = kNotMeasured, root_rotation_p95_deg = kNotMeasured,
         root_rotation_above_45 = kNotMeasured;
  // The same of the heading error (heading_error_deg: the turn about the vertical alone).
  double root_heading_median_deg = kNotMeasured, root_heading_p95_deg = kNotMeasured,
         root_heading_above_45 = kNotMeasured;
  // The tilt error (tilt_error_deg: the rest of the rotation error, the pelvis's pitch and
  // roll) and the trunk direction error (MidHip → Neck): median and 95th percentile.
  double root_tilt_median_deg = kNotMeasured, root_tilt_p95_deg = kNotMeasured;
  double trunk_direction_median_deg = kNotMeasured, trunk_direction_p95_deg = kNotMeasured;
  double seconds = 0;

  std::vector<EvaluationOverlay> overlays;

  // With options.training_data: the test poses against the training set and the baselines
  // (frames in the order of `frames`).
  std::optional<TrainingSetComparison> training_set;

  // When the capture read the model's own detections (capture.json: masks and keypoints
  // from the detector, kept in its detections/ folder): those inputs measured against the
  // dataset over the captured frames (capture/evaluation/detection_accuracy.h).
  std::optional<DetectionAccuracy> detections;

  // metrics.json: the options, the summary and per-frame arrays (null where not measured).
  std::string to_json() const;
};

// Reads both folders and measures every captured frame; progress(done, total) after each
// frame. Errors (weft::Error) name the file and what was expected: a missing or malformed
// capture folder, a frame id the dataset does not have, a mesh of the wrong vertex count,
// a view the dataset does not have.
CaptureEvaluation evaluate_capture(const EvaluationOptions& options,
                                   const std::function<void(int done, int total)>& progress = {});

}  // namespace weft::capture
