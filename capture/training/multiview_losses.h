#pragma once
// The method's image losses over every view of a frame (the network reads one view; the
// losses look at all of them), normalised so that their weights do not depend on the
// image size or the character's units:
//   L_lm  = Σ_{b,v,m} c_bvm ‖(Π_v(K_bm) − d_bvm) / W_v‖² / Σ c          (W_v: the view's width, px)
//   L_sil = Σ_{b,v,n} ρ_bvn (D_bv(Π_v(V_bn)) / S)² / Σ ρ               (S: silhouette size, px)
// c: detection confidence times the character's keypoint mask; D: the distance transform
// of the view's mask (multiview_supervision.h); n runs over the vertices on the predicted
// mesh's silhouette in view v, and ρ keeps those whose normal agrees with D's gradient
// (capture/deformation/losses.h).
#include <vector>

#include "capture/character/character.h"
#include "geometry/mesh.h"
#include "capture/dataset/multiview_supervision.h"
#include "capture/model/global_pose.h"
#include "capture/model/view_landmark_loss.h"
#include "graph/tensor.h"

namespace weft::capture {

// keypoints [B,25,3] world; frames: each sample's frame; keypoint_mask: 25 values (0/1).
Tensor multiview_landmark_loss(const Tensor& keypoints, const std::vector<int>& frames,
                               const MultiviewSupervision& supervision, const std::vector<double>& keypoint_mask,
                               LandmarkStatistics* statistics = nullptr);
// The same over given views: landmark_loss_over_views (capture/model/view_landmark_loss.h).

// vertices [B,V,3] world (body and cloth together), faces of that mesh.
Tensor multiview_silhouette_loss(const Tensor& vertices, const Faces& faces, const std::vector<int>& frames,
                                 const MultiviewSupervision& supervision);


}  // namespace weft::capture
