#pragma once
// Differentiable geometry ops of the deformation layer (see ../shared/DESIGN.md):
// rotations, embedded deformation, skinning and camera projection. All are batched over
// frames B, float32 or float64, with hand-written backward passes.
#include <vector>

#include "graph/tensor.h"

namespace weft::ops {

// Euler angles (a, b, c) in radians about x, y, z → R = Rz(c)·Ry(b)·Rx(a).
// angles [..., 3] → [..., 3, 3].
Tensor euler_to_rotation(const Tensor& angles);

// Embedded deformation (Sumner et al.): each vertex v moves with its graph nodes k,
//   v' = Σ_j w_vj [R_k (v − g_k) + g_k + t_k],  k = index[v, j].
// rest [V,3], nodes g [K,3], rotations R [B,K,3,3], translations t [B,K,3],
// index int64 [V,n], weights [V,n] → [B,V,3]. Gradients to all float inputs.
Tensor embedded_deformation(const Tensor& rest, const Tensor& nodes, const Tensor& rotations,
                            const Tensor& translations, const Tensor& index,
                            const Tensor& weights);

// Linear blend skinning: v' = Σ_j w_vj (A_k v + b_k), k = index[v, j].
// vertices [V,3] (shared by all frames) or [B,V,3]; transforms [B,J,3,4] (A | b);
// index int64 [V,m]; weights [V,m] → [B,V,3].
Tensor linear_blend_skinning(const Tensor& vertices, const Tensor& transforms,
                             const Tensor& index, const Tensor& weights);

// Dual quaternion skinning (Kavan et al.). dual_quaternions [B,J,8] holds per joint the
// unit dual quaternion (q0 = w,x,y,z | qe = w,x,y,z) with qe = ½ (0, t) q0. Per vertex the
// blend b = Σ_j s_j w_vj q̂_k, s_j = −1 where ⟨q0_k, q0_ref⟩ < 0 with ref = the vertex's
// first listed joint (antipodality), is normalised by ‖b0‖ and applied:
// v' = R(c0) v + 2 vec(ce c0*). Shapes as linear_blend_skinning.
Tensor dual_quaternion_skinning(const Tensor& vertices, const Tensor& dual_quaternions,
                                const Tensor& index, const Tensor& weights);

// Rigid transforms [..., 3, 4] (rotation | translation) → unit dual quaternions [..., 8]
// (w ≥ 0 on the real part), differentiable.
Tensor rigid_to_dual_quaternion(const Tensor& transforms);

// A kinematic chain of 1-dof joints, parents before children (Skeletool semantics):
// L_j = T(offset_j) · M_j(p_j), M_j a rotation by p_j radians about axis_j (revolute) or
// a translation by p_j along it (prismatic); G_j = G_parent · L_j. Offsets are already
// multiplied by the joint's scale, in the character's units.
struct KinematicChain {
  std::vector<int64_t> parents;     // J, −1 for roots
  std::vector<int64_t> prismatic;   // J, 1 for prismatic joints, 0 for revolute
  std::vector<double> offsets;      // J×3
  std::vector<double> axes;         // J×3, unit length
  std::vector<double> bind_inverse; // optional J×12 (3×4 row-major): output G_j · B_j⁻¹
};

// Joint parameters [B, J] → global joint transforms [B, J, 3, 4] (rotation | translation),
// times the inverse bind transforms when the chain has them (skinning transforms).
// Gradient to the joint parameters.
Tensor forward_kinematics(const Tensor& joint_parameters, const KinematicChain& chain);

// A calibrated pinhole camera: world → camera by x_c = R X + t (metres or the data's
// units), then OpenCV's distortion model (k1, k2, p1, p2, k3) and intrinsics → pixels.
struct PinholeCamera {
  double fx = 1, fy = 1, cx = 0, cy = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};  // row-major
  double t[3] = {0, 0, 0};
};

// points [..., 3] in world coordinates → pixels [..., 2]. Gradient to the points.
// Points at or behind the camera plane (z ≤ 1e-9) are an error.
Tensor project_points(const Tensor& points, const PinholeCamera& camera);

// Bilinear sampling of images [B,H,W] at points [B,N,2] (x = column, y = row, in pixels,
// pixel centres at integers); points outside are clamped to the border. → [B,N].
// Gradients to the image and the points.
Tensor image_sample_bilinear(const Tensor& image, const Tensor& points);

// As-rigid-as-possible energy of an embedded graph (summed over frames, both directions
// of each edge): Σ_b Σ_(j,k) w_jk ‖R_j (g_k − g_j) + g_j + t_j − (g_k + t_k)‖².
// nodes g [K,3], rotations [B,K,3,3], translations [B,K,3], edges int64 [E,2],
// edge_weights [E] → scalar. Gradients to rotations, translations and nodes.
Tensor arap_energy(const Tensor& nodes, const Tensor& rotations, const Tensor& translations,
                   const Tensor& edges, const Tensor& edge_weights);

}  // namespace weft::ops
