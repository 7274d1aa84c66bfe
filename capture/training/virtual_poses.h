#pragma once
// Poses no camera filmed, for PoseNet's lifting branch (docs/TRAINING.md, "Virtual poses").
// The branch is an MLP on the input view's detections, so it can learn from far more
// poses than the studio renders: procedural motions (configs/motions/*.yaml, e.g. random
// poses with seeds the training set did not use) are retargeted onto the character; each
// sample takes one of their frames, turns it to a random heading about its own vertical
// axis, stands it where the cameras of a random training frame look (the floor point
// nearest their optical axes; a studio's rig, or a moving camera's pose at that frame),
// give or take floor_shift_m, and sees it in those cameras. Every chosen view is
// rendered to a mask and a depth image (no shading, no image reaches a network) for the
// detector error model's occlusion and person scale (synthetic_keypoints.h) and for the
// input view's crop, chosen as the dataset reader chooses it (choose_crop, and the
// augmentation's shift and scale when they are on). Supervision is the method's own:
// L_lm against the detections of every chosen view, no 3D truth, no simulation.
//
// Deterministic: the batch of step s is a function of (seed, s) alone, so a resumed run
// draws the same poses, views and detections.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/dataset/augmentation.h"
#include "capture/dataset/multiview_supervision.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/model/global_pose.h"
#include "capture/studio/synthetic_keypoints.h"
#include "files/strict_yaml.h"

namespace weft::capture {

struct VirtualPoseConfig {
  std::vector<std::string> motions;  // procedural motion specs (configs/motions/*.yaml); empty: off
  std::string mapping;               // their retarget mapping onto the character (configs/retarget/*.yaml)
  double fps = 10;                   // frames per second the motions are sampled at (one pose each)
  int batch_size = 16;               // virtual samples per step
  int views = 4;                     // cameras per sample, drawn from the frame's views; the first is the input
  double floor_shift_m = 0.5;        // m: the person stands uniformly within a disc of this radius around where the cameras look
  KeypointNoiseConfig keypoints = KeypointNoiseConfig::openpose();  // the detector error model
  bool enabled() const { return !motions.empty(); }
};

// A `virtual_poses:` section of a training config: motions (a list of paths), mapping
// (a path), fps, batch_size, views, floor_shift_m, keypoints (synthetic_studio.h's
// section; default model openpose). Errors name the file, line and key.
VirtualPoseConfig parse_virtual_pose_config(const StrictYaml& y, const YAML::Node& section);

struct VirtualBatch {
  // What the lifting branch reads (keypoint_lift_input): keypoints [B,25,3] F32 in crop
  // pixels and the crop cameras; no images. frames are −1 (no dataset frame).
  Batch input;
  // Per sample, every chosen view's full camera and detections (the input view first):
  // the root translation solve and L_lm read these.
  std::vector<std::vector<KeypointView>> views;
};

class VirtualPoses {
 public:
  // Retargets the motions onto `character` once (progress: frames done, total). Cameras
  // come from `supervision`'s frames `camera_frames` (the train split). input_size and
  // margin: the dataset reader's (DatasetOptions); `augmentation`'s shift and scale move
  // the input crop as they move an image's. Errors name the config's file and key.
  VirtualPoses(const Character& character, const VirtualPoseConfig& config, const MultiviewSupervision& supervision,
               std::vector<int> camera_frames, int input_size, double margin, const AugmentationOptions& augmentation,
               const std::function<void(int, int)>& progress = {});

  int poses() const { return static_cast<int>(dofs_.rows()); }
  const VirtualPoseConfig& config() const { return config_; }
  // The batch of `step`, a function of (seed, step); samples are made in parallel.
  VirtualBatch batch(uint64_t seed, int64_t step) const;

 private:
  const Character& character_;
  VirtualPoseConfig config_;
  const MultiviewSupervision& supervision_;
  std::vector<int> camera_frames_;
  int input_size_;
  double margin_;
  AugmentationOptions augmentation_;
  Eigen::MatrixXd dofs_;  // poses × the skeleton's dofs
};

}  // namespace weft::capture
