#pragma once
// The training losses of the method (../shared/DESIGN.md), built from differentiable ops
// so gradients reach the pose and the embedded-graph parameters. Batched over frames B.
// Positions in the character's units, image quantities in pixels.
#include <opencv2/core.hpp>
#include <vector>

#include "capture/character/attachment.h"
#include "capture/io/camera.h"
#include "capture/character/embedded_graph.h"
#include "geometry/mesh.h"
#include "graph/tensor.h"
#include "ops/geometry.h"

namespace weft::capture {

// The op-level camera of a capture camera.
ops::PinholeCamera pinhole(const Camera& camera);

// L_lm = Σ_b Σ_m c_bm ‖p_bm − d_bm‖² / B: projected landmarks [B,M,2], detections
// [B,M,2], confidences [B,M] (0 for undetected keypoints) → scalar (pixels²).
Tensor landmark_loss(const Tensor& projected, const Tensor& detections, const Tensor& confidence);

// L_3d = Σ_b Σ_m w_bm ‖p_bm − q_bm‖² / B: points [B,M,3], their targets [B,M,3] (any finite
// value where w is 0), weights [B,M] → scalar (units²).
Tensor keypoint_3d_loss(const Tensor& points, const Tensor& targets, const Tensor& weights);

// L_lp, the lumbopelvic prior = Σ_b ‖R_b ŷ − t_b‖² / B: root rotations [B,3,3] (the root
// chain's world rotation, identity at rest), targets [B,3] (lumbopelvic_target) → scalar.
// R ŷ is the pelvis's up axis: keypoints fix the trunk but not how its lean is shared
// between the pelvis and the lumbar spine (BODY_25's MidHip and hips lie on the pelvis's
// left–right axis), so the prior states the human share.
Tensor lumbopelvic_loss(const Tensor& rotations, const Tensor& targets);

// Where the pelvis's up axis points when it takes (1 − lumbar_share) of the trunk's turn
// from its rest direction: the minimal rotation taking `rest_trunk` to `trunk` (both
// MidHip → Neck, any length), scaled to that fraction of its angle, applied to +y. In
// forward bending the lumbar spine takes about 70 % of the trunk's flexion early and 57 %
// late (Tafazzol et al., Clinical Biomechanics 2014; CMU 01_03: 60 %, docs/MOTIONS.md).
// A trunk turned by 180° from rest (no unique axis) or of zero length gives +y.
Eigen::Vector3d lumbopelvic_target(const Eigen::Vector3d& trunk, const Eigen::Vector3d& rest_trunk,
                                   double lumbar_share);

// Vertices of a mesh on its silhouette as seen by `camera`: the normal is nearly
// perpendicular to the viewing ray (|cos| ≤ max_cos) and the vertex is visible (no
// closer surface point within a pixel neighbourhood of a point z-buffer).
std::vector<int> boundary_vertices(const Camera& camera, const Vertices& V, const Faces& F,
                                   double max_cos = 0.3);

// ρ per boundary vertex: 1 where the vertex normal, projected into the image, agrees
// with the gradient of the distance-transform image (both point away from the person),
// 0 elsewhere. dt: CV_32F, the camera's image size.
std::vector<double> silhouette_weights(const Camera& camera, const Vertices& V,
                                       const Vertices& normals, const std::vector<int>& boundary,
                                       const cv::Mat& dt);

// L_sil = Σ_b Σ_n ρ_bn D_b(p_bn)²: projected boundary vertices [B,N,2], distance
// transforms [B,H,W] (pixels), ρ [B,N] (0 pads frames with fewer boundary vertices).
Tensor silhouette_loss(const Tensor& projected, const Tensor& distance_transforms,
                       const Tensor& rho);

// Rows `index` (int64 [B,N]) of per-frame vertices [B,V,3] → [B,N,3], differentiable.
Tensor select_vertices(const Tensor& vertices, const Tensor& index);

// The constant inputs of the ARAP regulariser of one embedded graph: edge weights are
// the mean rigidity of their two nodes (skin stiff, skirt free).
struct ArapTerms {
  Tensor nodes;         // [K,3]
  Tensor edges;         // int64 [E,2]
  Tensor edge_weights;  // [E]
};
ArapTerms arap_terms(const EmbeddedGraph& graph, DType dtype);
// L_arap for node rotations [B,K,3,3] and translations [B,K,3], averaged over frames.
Tensor arap_loss(const ArapTerms& terms, const Tensor& rotations, const Tensor& translations);

// L_att = Σ_b Σ_i ‖V_cloth,i − Σ_j γ_ij V_body,C(i)_j‖² / B.
struct AttachmentTerms {
  Tensor anchors;        // int64 [A] cloth vertices
  Tensor body_vertices;  // int64 [3A] the closest body triangle's vertices, row by row
  Tensor barycentric;    // [A,3,1]
};
AttachmentTerms attachment_terms(const Attachment& attachment, DType dtype);
Tensor attachment_loss(const AttachmentTerms& terms, const Tensor& cloth, const Tensor& body);

}  // namespace weft::capture
