#pragma once
// L_lm over given views (the method's landmark loss; capture/training/multiview_losses.h has
// it over a dataset's views): training reads it over a frame's studio cameras and virtual
// views, inference over the input view when it fits a pose to the detections.
//   L_lm = Σ_{b,v,m} c_bvm ‖(Π_v(K_bm) − d_bvm) / W_v‖² / Σ c          (W_v: the view's width, px)
// c: detection confidence times the character's keypoint mask.
#include <vector>

#include "capture/model/global_pose.h"
#include "graph/tensor.h"

namespace weft::capture {

struct LandmarkStatistics {
  double mean_error_px = 0;  // mean ‖Π(K) − d‖ over detections with confidence ≥ 0.1 (full-image px)
  int detections = 0;
};

// keypoints [B,25,3] world; views[b] are sample b's cameras and detections (any number; a
// view with a keypoint behind its camera is skipped); keypoint_mask: 25 values (0/1).
Tensor landmark_loss_over_views(const Tensor& keypoints, const std::vector<std::vector<KeypointView>>& views,
                                const std::vector<double>& keypoint_mask, LandmarkStatistics* statistics = nullptr);

}  // namespace weft::capture
