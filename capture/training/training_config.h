#pragma once
// The config of `weft train` (configs/train/*.yaml, every key in docs/TRAINING.md): the
// networks, the three stages of the method with their loss weights, validation,
// checkpoints and the simulator of the physics-aware stage. Read strictly: an unknown
// key, a wrong type or a value out of range is one weft::Error naming the file, line and key.
#include <cstdint>
#include <string>
#include <vector>

#include "capture/dataset/augmentation.h"
#include "capture/training/pose_noise.h"
#include "capture/training/virtual_poses.h"
#include "capture/model/model_folder.h"
#include "capture/model/network_config.h"

namespace weft::capture {

// The loss weights β of one stage (0: the term is not computed).
struct LossWeights {
  double landmarks = 0;   // L_lm, over all views of the frame
  double keypoints_3d = 0;  // L_3d: the keypoints against those triangulated from every view's detections
  double silhouette = 0;  // L_sil, over all views of the frame
  double arap = 0;        // L_arap of the body's embedded graph
  double cloth_arap = -1; // L_arap of the garment's graph (< 0: the same as `arap`)
  double attachment = 0;  // L_att
  double simulation = 0;  // L_sim
  double lumbopelvic = 0; // L_lp: the pelvis's share of the trunk's lean (a prior; deformation/losses.h)
  double virtual_landmarks = 0;  // L_lm of the lifting branch alone on virtual poses (virtual_poses.h)
  double heatmaps = 0;    // L_hm: the person detector's keypoint heatmaps (capture/detection/detection_losses.h)
  double mask = 0;        // L_mask: the person detector's mask (binary cross-entropy)
};

// The loss terms of training, one entry each: `name` is the key of its weight under
// stages.<stage> in a config and its column in RUN/losses.csv; `weight` is where
// LossWeights holds it. A new loss is a LossWeights field, its entry here and its
// computation in the trainer; tests/gradcheck/loss_terms_gradcheck_test.cpp fails until
// it has a gradient check. (cloth_arap, which weighs the garment's part of `arap`, is the
// one weight key that is not a term of its own.)
struct LossTerm {
  const char* name;
  double LossWeights::*weight;
  const char* meaning;
};
const std::vector<LossTerm>& loss_terms();

// The stages, in the order they run: (a) PoseNet on L_lm (and L_3d); (b) PADefNet's warm start with
// PoseNet frozen; (c) the physics-aware stage (PoseNet frozen); then the person detector
// (network.detector) on L_hm + L_mask, which none of the others reads.
enum class StageKind { pose, warmup, physics, detector };
const char* stage_name(StageKind kind);  // "pose", "warmup", "physics", "detector"

struct StageConfig {
  StageKind kind = StageKind::pose;
  int steps = 0;          // 0 skips the stage
  int batch_size = 8;     // images per step (physics: windows × window_frames, at least one window)
  double lr = 1e-3;       // AdamW
  double weight_decay = 0;
  double final_lr_fraction = 0.1;  // cosine decay of the rate to this fraction at the stage's end
  LossWeights weights;
};

// The simulation loss L_sim (the paper's Eq. 8): a window of F consecutive predicted frames
// t' … t'+F−1 starts the simulator at the prediction of t' (cleared of penetration first)
// with the forward-difference velocity to t'+1, simulates t'+1 … t'+F−1 following the
// predicted bodies, with the silhouette constraint E_cons from each frame's views, and
// pulls each of those predictions toward its simulated state.
struct PhysicsConfig {
  int window_frames = 4;     // F: the first frame starts the simulator, the other F − 1 get targets
  int max_iterations = 30;   // Newton iterations per step in training windows
  double tolerance = 1e-2;   // looser than ground truth's 1e-3 (relative to a vertex's weight)
  // E_cons: stiffness (N/m) pulling each garment vertex on the predicted silhouette toward
  // the camera ray through the nearest mask contour pixel, in every view; 0 switches it off.
  double ray_stiffness = 100;
  // A boundary vertex whose projection lies farther than this from the mask's contour
  // (pixels at silhouette_size) gets no ray: its nearest contour pixel is not its own.
  double ray_max_pixels = 6;
  bool resolve_start = true;      // the collision-resolution pass on each window's start state
  bool freeze_batch_norm = true;  // PADefNet normalises with its running statistics in this stage
};

struct TrainingConfig {
  std::string file;
  uint64_t seed = 0;
  NetworkConfig network;
  std::vector<StageConfig> stages;  // pose, warmup, physics, detector (all four, steps may be 0)
  int silhouette_size = 128;   // distance transforms of every view at this size (longest side, px)
  int loader_threads = 1;      // TBB threads loading batches ahead
  int log_every = 10;          // steps between log lines
  int validate_every = 100;    // steps between validations (0: only at the end)
  int validation_samples = 32; // val samples (frame, view) per validation, spread over the split
  int checkpoint_every = 50;   // steps between checkpoints (and one at the end)
  int keep_checkpoints = 3;    // the last K are kept
  // Data parallelism (nn/data_parallel.h, `mpirun`): every global batch is cut into this
  // many shards, each with its own forward, backward and batch-norm statistics, spread
  // over the ranks (a multiple of their number); 0: one shard per rank. A fixed value
  // makes the run the same computation on any number of ranks that divides it.
  int shards = 0;
  // The warm start and the physics stage (and validation) pose the character by the
  // dataset's ground truth, gt/pose.motion, instead of PoseNet: the oracle pose, which
  // isolates what the deformation stages do to the garment from pose error (the paper
  // assumes PoseNet fixed in its section 3.3.2). The pose stage is then not needed.
  bool oracle_pose = false;
  // The oracle pose perturbed as PoseNet errs (capture/training/pose_noise.h): the same
  // perturbed poses in training and evaluation; the joint errors are still measured
  // against the truth. Off without an oracle_pose_noise key; needs oracle_pose.
  PoseNoiseConfig oracle_pose_noise;
  // The lumbar spine's share of the trunk's lean (MidHip → Neck turned from rest) that the
  // lumbopelvic prior (stages.<stage>.lumbopelvic) leaves to it; the pelvis takes the rest.
  // Forward bending: about 0.7 early, 0.57 late (Tafazzol et al. 2014); CMU 01_03: 0.6.
  double lumbar_share = 0.6;
  // The train split's samples, augmented (capture/dataset/augmentation.h); validation and
  // evaluation read the images as they are.
  AugmentationOptions augmentation;
  // The detector stage's samples (`detector_augmentation`, the same keys): wider shifts and
  // scales (its coarse pass sees the whole frame) and photos behind the person, from the
  // training share of the photos (background_photos) only.
  AugmentationOptions detector_augmentation;
  PhysicsConfig physics;
  // Poses no camera filmed, for the lifting branch (stages.pose.virtual_landmarks weighs
  // their L_lm; capture/training/virtual_poses.h). Off without a virtual_poses section.
  VirtualPoseConfig virtual_poses;

  int total_steps() const;
  // The stage of global step `step` (1-based) and the step it starts after.
  const StageConfig& stage_of(int64_t step, int64_t* stage_start = nullptr) const;
};

TrainingConfig load_training_config(const std::string& path);
// The physics section as YAML flow text, every key written: parse_training_config reads it
// back to the same settings (weft adapt writes the model's own into its config).
std::string physics_config_yaml(const PhysicsConfig& c);
// The training config a model folder was trained with (its config.yaml, whose relative
// paths resolve against the folder it came from).
TrainingConfig model_training_config(const ModelFolder& model);
// name: the file's path for messages; relative paths resolve against base_dir, or name's
// folder when empty.
TrainingConfig parse_training_config(const std::string& yaml_text, const std::string& name,
                                     const std::string& base_dir = "");

}  // namespace weft::capture
