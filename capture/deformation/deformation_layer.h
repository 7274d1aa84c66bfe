#pragma once
// The deformation layer V, K = f(θ, A, T) of the method (../shared/DESIGN.md): embedded
// deformation of a template mesh in the bind pose by per-node rotations A (Euler angles)
// and translations T, then dual quaternion skinning by the pose θ (the skeleton's dofs).
// Every step is a differentiable op, so gradients reach θ, A and T. Batched over frames.
// Lengths are in the character's units (ddc: millimetres).
#include "capture/character/character.h"
#include "graph/tensor.h"
#include "ops/geometry.h"

namespace weft::capture {

// The constant tensors of one deformable mesh (body or cloth).
struct DeformableSurface {
  Tensor rest;            // [V,3] bind-pose vertices
  Tensor nodes;           // [K,3] embedded-graph nodes
  Tensor node_index;      // int64 [V,n] graph nodes per vertex
  Tensor node_weights;    // [V,n]
  Tensor skin_index;      // int64 [V,m] joints per vertex, reference bone first
  Tensor skin_weights;    // [V,m]
  int64_t num_nodes() const { return nodes.size(0); }
};

struct PosedJoints {
  Tensor global;    // [B,J,3,4] G(θ)
  Tensor skinning;  // [B,J,3,4] G(θ)·G(bind)⁻¹
  Tensor markers;   // [B,M,3] marker positions (empty when the skeleton has none)
};

class DeformationLayer {
 public:
  // dtype: F32 for training and inference, F64 for gradient checks.
  explicit DeformationLayer(const Character& character, DType dtype = DType::F32);

  // dofs [B,D] → joint and marker transforms.
  PosedJoints pose(const Tensor& dofs) const;

  // Deformed and posed vertices [B,V,3] of a surface. node_angles and
  // node_translations are [B,K,3]; pass undefined tensors for no embedded deformation.
  Tensor deform(const DeformableSurface& surface, const PosedJoints& joints,
                const Tensor& node_angles, const Tensor& node_translations) const;

  // BODY_25 keypoints [B,25,3] from posed joints: each the mean of its joint origins
  // and markers (character.body25). Unmapped keypoints are 0; body25_mask() is 1 for
  // mapped ones and 0 otherwise ([25]), to multiply into detection confidences.
  Tensor body25(const PosedJoints& joints) const;
  const Tensor& body25_mask() const { return body25_mask_; }

  const DeformableSurface& body() const { return body_; }
  const DeformableSurface* cloth() const { return has_cloth_ ? &cloth_ : nullptr; }
  int64_t num_dofs() const { return dof_to_joint_.size(0); }
  DType dtype() const { return dtype_; }

 private:
  DType dtype_;
  Tensor dof_to_joint_;              // [D,J]: joint parameters = dofs · this
  ops::KinematicChain global_chain_; // G(θ)
  ops::KinematicChain skin_chain_;   // G(θ)·G(bind)⁻¹
  ops::KinematicChain marker_chain_; // G(θ)·G(0)⁻¹
  Tensor marker_offsets_;            // [M,3] in the zero-pose model frame
  Tensor marker_index_, marker_weights_;  // int64 [M,1], [M,1]
  Tensor body25_index_;    // int64 [25·S]: rows of [joint origins; markers]
  Tensor body25_weights_;  // [25,S,1]
  Tensor body25_mask_;     // [25]
  int64_t body25_sources_ = 1;  // S
  DeformableSurface body_, cloth_;
  bool has_cloth_ = false;
};

}  // namespace weft::capture
