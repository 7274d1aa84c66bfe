#pragma once
// A trained model measured on every frame of one split of a dataset with 3D ground truth
// (a `weft synth` dataset): each frame is read from every view in turn, so each view gives
// a sequence of predictions over the split's consecutive frames. The per-frame measures
// are `weft eval`'s (frame_measures.h); NaN (null in JSON) where not measured. Reported
// (means over frames × input views unless said):
// - keypoints: 2D error over all views (px) with the root translation solved from the
//   frame's detections; the 3D BODY_25 error against gt/pose.motion (mm), absolute and
//   root-relative (both skeletons' pivot joint at the origin, rotations kept), and the
//   root rotation's error (degrees; only indicative: hips and spine can turn the body
//   too). The floor to beat is the mean training pose (gt/pose.motion's regressed dofs
//   averaged over the train split) given the true root rotation (an oracle).
// - silhouette IoU of the rendered body + cloth against the masks, over all views, and
//   the same for the skinned template (PADefNet off) in the predicted pose.
// - cloth and body vertex error against gt/cloth_*.ply and gt/body_*.ply (mm), the cloth's
//   Chamfer distance (mm), and for reference the cloth error of the template skinned by
//   the predicted pose (PADefNet off) and by the true pose.
// - penetration of cloth vertices into the body: mean depth over the vertices inside and
//   over all cloth vertices (mm), max, and the fraction of cloth vertices inside.
// - out-of-balance force of each three consecutive predicted frames of one input view,
//   with the simulator of the config's physics.synth_config, the predicted body as the
//   obstacle and the anchors pinned where they are predicted (frame_measures.h
//   cloth_out_of_balance), over the vertices the attachment does not hold and pooled over
//   frames: mean, p95, p99 and max in N and relative to a vertex's weight; the same over
//   the free vertices outside the body (the collision penalty of a vertex inside restates
//   its depth); and the mean size of each term the residual balances (inertia, elastic,
//   collision, friction).
// - PoseNet's error per regressed dof (predicted − true, the dof's own units): its RMS,
//   mean and standard deviation about the mean over predictions, and the lag-1
//   autocorrelation of the error about its mean over consecutive frames of one input view,
//   pooled over the dofs, as a correlation time τ = −1/ln ρ₁ (frames): what
//   oracle_pose_noise (capture/training/pose_noise.h) draws from.
// With the config's oracle_pose the skeleton is posed by gt/pose.motion (the root
// rotation error is then not measured), isolating the garment from pose error; with
// oracle_pose_noise by that motion perturbed, every joint error still against the truth.
// `per_frame` lists each prediction's measures, in (view, frame) order, for paired
// comparisons of two models on the same split; each row is {frame, view, then every
// metric of frame_metrics() by its name}.
#include <string>
#include <vector>

#include "capture/evaluation/frame_measures.h"

namespace weft::capture {

// One prediction's measures (NaN where not measured): frame_measures.h's, the same as
// `weft eval`'s. Its JSON row carries every metric of frame_metrics() by name.
struct SplitFrameEvaluation {
  int frame = 0, view = 0;
  FrameMeasures measures;
};

struct SplitEvaluation {
  std::string split;
  bool oracle_pose = false;
  int frames = 0, views = 0, predictions = 0;
  double keypoint_error_px = kNotMeasured, mean_pose_keypoint_error_px = kNotMeasured;
  double joint_error_mm = kNotMeasured, joint_error_root_relative_mm = kNotMeasured, mean_pose_joint_error_root_relative_mm = kNotMeasured;
  double root_rotation_error_deg = kNotMeasured;  // mean
  double root_rotation_median_deg = kNotMeasured, root_rotation_p95_deg = kNotMeasured,
         root_rotation_above_45 = kNotMeasured;  // the fraction of predictions above 45°
  double root_heading_median_deg = kNotMeasured, root_heading_above_45 = kNotMeasured;  // heading_error_deg's
  double silhouette_iou = kNotMeasured, template_silhouette_iou = kNotMeasured;
  double cloth_error_mm = kNotMeasured, chamfer_mm = kNotMeasured, template_cloth_error_mm = kNotMeasured,
         skinned_true_pose_cloth_error_mm = kNotMeasured, body_error_mm = kNotMeasured;
  double penetration_mean_mm = kNotMeasured, penetration_mean_all_mm = kNotMeasured, penetration_max_mm = kNotMeasured,
         penetrating_fraction = kNotMeasured;
  int oob_frames = 0;
  Distribution oob_n, oob_rel, oob_outside_n;  // pooled over the free vertices of every measured frame
  double inertia_mean_n = kNotMeasured, elastic_mean_n = kNotMeasured, collision_mean_n = kNotMeasured, friction_mean_n = kNotMeasured;
  struct DofError {
    std::string name;
    double rms = kNotMeasured, mean = kNotMeasured, std = kNotMeasured;  // std: about the mean
  };
  std::vector<DofError> dof_errors;  // PoseNet's (empty under the oracle pose)
  double dof_error_lag1 = kNotMeasured, dof_error_correlation_frames = kNotMeasured;
  double seconds = 0;
  std::vector<SplitFrameEvaluation> per_frame;
  std::string to_json() const;
};

// weights: a checkpoint or model.safetensors of `weft train` with this config.
SplitEvaluation evaluate_split(const std::string& config, const std::string& data, const std::string& weights,
                               const std::string& split);

}  // namespace weft::capture
