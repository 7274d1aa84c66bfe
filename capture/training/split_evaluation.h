#pragma once
// A trained model measured on every frame of one split of a dataset with 3D ground truth
// (a `weft synth` dataset): each frame is read from every view in turn, so each view gives
// a sequence of predictions over the split's consecutive frames. Reported (means over
// frames × input views unless said):
// - keypoints: 2D error over all views (px) with the root translation solved from the
//   frame's detections; the 3D BODY_25 error against gt/pose.motion (mm), absolute and
//   root-relative (both skeletons' pivot joint at the origin, rotations kept), and the
//   root rotation's error (degrees; only indicative: hips and spine can turn the body
//   too, so how a pose splits into root rotation and articulation is not unique). The
//   floor to beat is the mean training pose (gt/pose.motion's regressed dofs averaged
//   over the train split) given the true root rotation (an oracle), root-relative and in 2D.
// - silhouette IoU of the rendered body + cloth against the masks, over all views, and
//   the same for the skinned template (PADefNet off) in the predicted pose.
// - cloth and body vertex error against gt/cloth_*.ply and gt/body_*.ply (mm), and for
//   reference the cloth error of the template skinned by the predicted pose (PADefNet
//   off) and by the true pose (what a perfect PoseNet with no PADefNet would leave).
// - penetration of cloth vertices into the body (mm, over penetrating vertices) and the
//   fraction of cloth vertices inside.
// - out-of-balance force of each three consecutive predicted frames of one input view
//   (physics/cloth_metrics.h, the simulator of the config's physics.synth_config with the
//   predicted body as obstacle and the anchors pinned where they are predicted): mean and
//   max over the vertices the attachment does not hold (counted, the anchors show the
//   hanging garment's weight: 4.75 m·g on the tiny ground truth) and frames, in N and
//   relative to a vertex's weight.
#include <string>

namespace weft::capture {

struct SplitEvaluation {
  std::string split;
  int frames = 0, views = 0, predictions = 0;
  double keypoint_error_px = 0, mean_pose_keypoint_error_px = 0;
  double joint_error_mm = -1, joint_error_root_relative_mm = -1, mean_pose_joint_error_root_relative_mm = -1;
  double root_rotation_error_deg = -1;
  double silhouette_iou = 0, template_silhouette_iou = 0;
  double cloth_error_mm = -1, template_cloth_error_mm = -1, skinned_true_pose_cloth_error_mm = -1,
         body_error_mm = -1;
  double penetration_mean_mm = 0, penetration_max_mm = 0, penetrating_fraction = 0;
  int oob_frames = 0;
  double oob_force_mean_n = 0, oob_force_max_n = 0, oob_force_mean_rel = 0, oob_force_max_rel = 0;
  double seconds = 0;
  std::string to_json() const;
};

// weights: a checkpoint or model.safetensors of `weft train` with this config.
SplitEvaluation evaluate_split(const std::string& config, const std::string& data, const std::string& weights,
                               const std::string& split);

}  // namespace weft::capture
