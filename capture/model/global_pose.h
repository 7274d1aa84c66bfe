#pragma once
// The global pose of the capture: the root rotation PoseNet regresses (6D representation)
// and the root translation, which is not regressed but solved in closed form from the
// multi-view 2D keypoints (DeepCap's global alignment), so the network only has to get
// the articulated, root-relative pose right. Batched over frames B; positions in the
// character's units, detections in pixels.
#include <vector>

#include "capture/io/camera.h"
#include "capture/io/openpose.h"
#include "graph/tensor.h"

namespace weft::capture {

// The continuous 6D rotation representation (Zhou et al. 2019): x [B,6] = (a1 | a2) →
// R [B,3,3] with columns b1 = a1/‖a1‖, b2 = the normalised part of a2 orthogonal to b1,
// b3 = b1 × b2. Unlike Euler angles or quaternions it has no discontinuity for a network
// to straddle. Built from differentiable ops; the norms carry an ε of 1e-12 under the
// square root, so a zero vector gives zeros, not NaN. (1,0,0, 0,1,0) is the identity.
Tensor rotation_from_6d(const Tensor& x);

// The root translation t that puts root-relative keypoints P_m (world orientation,
// character units) onto the rays of their detections in every view c:
//   t = argmin Σ_c Σ_m w_cm ‖(I − d_cm d_cmᵀ)(P_m + t − o_c)‖²,
// o_c the camera centre, d_cm the unit world direction of the undistorted detection's
// ray, w_cm = confidence × keypoint mask (0 for undetected or unmapped keypoints).
// The normal equations give, with A = w (I − d dᵀ) and S = Σ_cm A_cm + λI,
//   t = S⁻¹ Σ_cm A_cm o_c − Σ_m C_m P_m,   C_m = S⁻¹ Σ_c A_cm,
// linear in P, so the terms depend on the detections only and the gradient flows to P.
// λ = 1e-9 · max(trace(S)/3, 1) (S is dimensionless) keeps a rank-deficient system
// (one ray, or nothing detected) finite: t is 0 along the directions no ray constrains.
// Detections are undistorted exactly (Newton on OpenCV's distortion model).
struct RootTranslationTerms {
  Tensor offset;   // [B,3]      S⁻¹ Σ A o (character units)
  Tensor weights;  // [B,M,3,3]  C_m (dimensionless; Σ_m C_m = I up to λ)
};

// The cameras of one frame and their BODY_25 detections (x px, y px, confidence).
struct KeypointView {
  Camera camera;
  Body25 detections;
};

// Detected keypoints (confidence > 0) the character maps (keypoint_mask > 0). A view with
// fewer than two places neither the root translation nor a fit of the pose.
int mapped_detection_count(const Body25& detections, const std::vector<double>& keypoint_mask);

// views[b]: the views of frame b (any number, possibly none). keypoint_mask: M = 25 weights,
// 1 for keypoints the character maps, 0 otherwise. Solved in double, stored as `dtype`.
// Throws weft::Error for a mask of the wrong size or a negative or non-finite weight.
RootTranslationTerms root_translation_terms(const std::vector<std::vector<KeypointView>>& views,
                                            const std::vector<double>& keypoint_mask, DType dtype);

// The BODY_25 keypoints of one frame triangulated from its views' detections: for each
// keypoint the point nearest to the detections' rays in the least-squares sense,
//   q_m = argmin Σ_c w_cm ‖(I − d_cm d_cmᵀ)(q − o_c)‖²,  w_cm = confidence × keypoint mask,
// over the views where it is detected with confidence ≥ min_confidence. Rows are NaN for
// an unmapped keypoint, one seen in fewer than two views, or rays too close to parallel
// (the smallest eigenvalue of Σ w (I − d dᵀ) below 1e-4 of the largest). World
// coordinates, the cameras' units. Multi-view supervision of the pose in 3D, no ground
// truth needed (DeepCap's studio has the same calibrated views).
Body25 triangulate_keypoints(const std::vector<KeypointView>& views, const std::vector<double>& keypoint_mask,
                             double min_confidence = 0.1);

// t [B,3] = offset − Σ_m C_m P_m for points [B,M,3] of the terms' dtype; differentiable in P.
Tensor solve_root_translation(const RootTranslationTerms& terms, const Tensor& points);

}  // namespace weft::capture
