#pragma once
// Fitting PoseNet's output to the input view's detections at capture time (weft's own, not
// the paper's: DeepCap regresses the pose and stops). A network that reads the detections
// still misses them (on unseen motion its root-relative error across the image is larger
// than along the camera's axis, docs/RESULTS.md), so each frame's output o (pose and root
// rotation, in PoseNet's units) moves from the network's o_net to lower
//   L_lm(o) over the input view + prior · ‖o − o_net‖² / P          (P outputs per frame)
//     + depth_prior · mean_k (z_k(o) − z_k(o_net))²   (z: depth relative to MidHip, metres)
// by Adam, the root translation re-solved from the keypoint rays at every step as in
// training. The view constrains the image plane; the prior keeps the rest (depth, what no
// detection sees) near the network's. Frames with fewer than two mapped detections keep o_net.
#include <Eigen/Core>
#include <vector>

#include "capture/model/global_pose.h"

namespace weft::capture {

class CaptureModel;

// The capture config's `refine` section (docs/CAPTURE.md).
struct PoseRefinementConfig {
  int iterations = 300; // Adam steps per frame; 0: off (the network's output as it is)
  double prior = 1e-4;  // weight of ‖o − o_net‖² / P against L_lm (in view widths²: about 1e-4 at 2.5 px of 256)
  double lr = 0.05;     // Adam's step on o (PoseNet's units: dof_scale radians per unit for most dofs)
  int batch_size = 32;  // frames optimised together (independent: the losses are sums over frames)
  // Weight of the mean squared change (m²) of each keypoint's depth along the input camera's
  // axis, relative to MidHip, from the network's: the fit moves what the view sees and
  // leaves the depth no detection measures. 0: off.
  double depth_prior = 10;
};

struct PoseRefinementSummary {
  int frames = 0;                  // frames refined
  double error_before_px = 0;      // mean ‖Π(K) − d‖ over their detections (conf ≥ 0.1), input view px
  double error_after_px = 0;
  double seconds = 0;
};

// outputs[i]: frame i's PoseNet output, replaced by the fitted one; views[i]: its input view
// (camera and detections in full-image pixels).
PoseRefinementSummary refine_pose_outputs(const CaptureModel& model, const std::vector<KeypointView>& views,
                                          std::vector<Eigen::VectorXd>& outputs, const PoseRefinementConfig& config);

}  // namespace weft::capture
