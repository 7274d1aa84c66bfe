#pragma once
// Where a capture's pose error comes from, measured against the training set (`weft eval
// --training-data`): how far each test pose lies from the nearest training pose, and two
// baselines scored on the same frames as the capture.
// - nearest training pose: the smallest PA-MPJPE (frame_measures.h procrustes_aligned) of
//   a training frame's true BODY_25 keypoints to the test frame's: what the data covers.
// - mean training pose: the mean of the training keypoints relative to the pivot joint in
//   its heading frame (the turn about the vertical taken out, so that a tilted pelvis does
//   not lean the mean), placed with the test frame's true heading and pivot: what knowing
//   nothing of the image but the heading scores.
// - nearest 2D retrieval: the training frame and view whose true 2D keypoints, centred and
//   scaled, lie nearest to the test frame's detections in the input view (the keypoints
//   the capture read), its 3D pose carried from that training camera into the input
//   camera (the same pose relative to the camera): what a lookup of the training set by
//   the detections alone scores. Below the network's error, the network is short; at or
//   above it, the data is.
#include <Eigen/Core>

#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/io/camera.h"
#include "capture/io/openpose.h"

namespace weft::capture {

// One test frame, as the comparison sees it (character units).
struct TestFramePose {
  int id = 0;
  Vertices body25;  // the true BODY_25 keypoints (25×3; NaN rows unmapped)
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();
  Eigen::Matrix3d root_rotation = Eigen::Matrix3d::Identity();  // the pivot joint's global rotation
  Camera camera;                                                 // the input view's camera
  Body25 detections = Body25::Zero();                            // the input view's keypoints (pixels, confidence)
};

// The training split of a dataset: every frame's true keypoints, pivot and root rotation,
// and the cameras of every view.
struct TrainingPoses {
  std::string data;                            // the dataset folder
  std::string split;                           // the split read
  std::vector<int> frames;                     // frame ids
  std::vector<Vertices> body25;                // per frame, 25×3
  std::vector<Eigen::Vector3d> pivot;          // per frame
  std::vector<Eigen::Matrix3d> root_rotation;  // per frame
  std::vector<std::string> views;
  std::vector<std::vector<Camera>> cameras;    // [frame][view]
};

// Reads DATA/dataset.yaml's split `split`, DATA/gt/pose.motion and DATA/cameras.yaml, and
// poses `character` (the captured one: the poses are measured on its skeleton) by each
// frame's dofs. Errors name the file: a dataset without that split, a motion of another
// dof count, a camera the file does not have, units that differ from the character's.
TrainingPoses read_training_poses(const std::string& data, const std::string& split, const Character& character);

struct TrainingSetFrame {
  int id = 0;
  double nearest_pose_pa_mm = 0;  // PA-MPJPE of the nearest training pose
  int nearest_pose_frame = -1;
  double mean_pose_root_relative_mm = 0, mean_pose_pa_mm = 0;
  double nearest_2d_root_relative_mm = 0, nearest_2d_pa_mm = 0;
  int nearest_2d_frame = -1;
  std::string nearest_2d_view;
};

struct TrainingSetComparison {
  std::string data, split;
  int training_frames = 0, training_views = 0;
  std::vector<TrainingSetFrame> frames;  // in the order of the test frames given
  // Means over the frames.
  double nearest_pose_pa_mm = 0, mean_pose_root_relative_mm = 0, mean_pose_pa_mm = 0,
         nearest_2d_root_relative_mm = 0, nearest_2d_pa_mm = 0;
};

// The comparison of every test frame with the training poses (see the top of this file).
// A test frame with fewer than 3 detected keypoints that are mapped in the skeleton has no
// 2D retrieval (its nearest_2d_* are NaN and left out of the means).
TrainingSetComparison compare_with_training_set(const TrainingPoses& training, const std::vector<TestFramePose>& test,
                                                double metres_per_unit);

// A set of 2D points centred on their mean and scaled to unit root-mean-square radius,
// over the rows where `use` is true (the others are left as they are): the normalisation of
// the 2D retrieval, which makes it blind to where the person is in the image and how big.
Eigen::MatrixX2d normalized_points_2d(const Eigen::MatrixX2d& points, const std::vector<char>& use);

}  // namespace weft::capture
