#pragma once
// `weft adapt`: the paper's domain adaptation before testing (../shared/DESIGN.md,
// "Testing"): both networks of a trained model refined on the test sequence itself with
// the losses one camera gives: L_lm on the sequence's OpenPose detections, L_sil on its
// masks (given, or green-screen keyed), L_att, and L_arap or L_sim as in the model's last
// stage (the physics-aware stage when the model was trained with one).
//
// How: the sequence becomes a one-view dataset in OUT/sequence/ (docs/DATASET.md's layout:
// images, masks, keypoints, cameras.yaml, dataset.yaml with every frame in the train
// split, the model's character), and the staged trainer (capture/training/trainer.h) runs
// on it from the model's weights with OUT/adapt_config.yaml: PoseNet for `iterations`
// steps on L_lm, then PADefNet for `iterations` steps with the weights of the model's last
// stage, both at the learning rate the model's stage ended with. OUT is then a model
// folder like any run (capture/model/model_folder.h): `weft infer --model OUT`.
#include <functional>
#include <string>

#include "capture/training/trainer.h"

namespace weft::capture {

struct AdaptOptions {
  std::string model;        // the model folder to adapt
  std::string input;        // the test sequence: a video or an image folder
  std::string camera;       // its camera(s), as for weft infer
  std::string camera_name;
  std::string masks;        // optional: "" keys the green screen
  std::string keypoints;    // OpenPose detections: required (L_lm and the root translation)
  std::string config;       // optional capture settings (keying), configs/infer/*.yaml
  std::string out;          // the adapted model folder
  int iterations = 300;     // steps per network
  double fps = 0;           // the sequence's frame rate (0: the video's, else 30)
  int max_frames = -1;
  bool resume = false;      // continue an interrupted adaptation in OUT
  int64_t stop_after = -1;  // stop after this step (tests)
};

struct AdaptSummary {
  int frames = 0;
  std::string sequence;     // the one-view dataset written for the trainer
  TrainSummary training;
};

AdaptSummary adapt_model(const AdaptOptions& options,
                         const std::function<void(const TrainProgress&)>& progress = {});

}  // namespace weft::capture
