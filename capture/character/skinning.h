#pragma once
// Skinning weights and the reference (plain Eigen, double) skinning methods: linear
// blend skinning and dual quaternion skinning. The differentiable ops in ops/ must match
// these; `weft pose` uses them directly.
#include <Eigen/Core>
#include <vector>

#include "geometry/mesh.h"
#include "capture/character/skeleton.h"

namespace weft::capture {

struct SkinInfluence {
  int joint = -1;     // skeleton joint index
  double weight = 0;  // > 0
};

// Per-vertex sparse weights. The first influence of a vertex is its reference bone for
// dual-quaternion sign alignment (Skeletool lists the largest weight first; generated
// weights are sorted by decreasing weight). Each vertex's weights sum to 1.
struct SkinningWeights {
  int num_joints = 0;
  std::vector<std::vector<SkinInfluence>> vertices;

  int num_vertices() const { return static_cast<int>(vertices.size()); }
  int max_influences() const;
  // Dense V×J matrix.
  Eigen::MatrixXd dense() const;
  // Compressed rows: influences of vertex v are [offsets[v], offsets[v+1]) in
  // joints/weights, in the stored order (reference bone first).
  struct Csr {
    std::vector<int> offsets, joints;
    std::vector<double> weights;
  };
  Csr csr() const;
  // Fixed-width padded arrays (V×k, unused slots: joint 0 with weight 0), k = max_influences.
  void padded(Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& joints,
              Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& weights) const;
};

// Divides each vertex's weights by their sum; throws weft::Error (prefixed by `what`) for a
// vertex with no positive weight, a bad joint index or a non-finite weight.
void normalize_weights(SkinningWeights& weights, const std::string& what);

// Both are single-threaded on purpose: a frame of ddc takes ~0.3 ms, less than an
// OpenMP fork/join costs on a busy machine; parallelise over frames instead.

// v' = Σ w_j S_j v.
Vertices linear_blend_skinning(const Vertices& rest, const SkinningWeights& weights,
                               const Transforms& skinning);

// Unit dual quaternion of a rigid transform: real part q0 (w,x,y,z), dual part qe with
// qe = ½ (0, t) q0.
struct DualQuaternion {
  Eigen::Quaterniond real, dual;
};
DualQuaternion to_dual_quaternion(const Eigen::Isometry3d& T);

// Dual quaternion skinning: b = Σ w_j s_j q̂_j with s_j = −1 where ⟨q0_j, q0_ref⟩ < 0,
// q0_ref the vertex's first listed bone; normalised by ‖b0‖; v' = R(b0) v + 2 vec(be b0*).
Vertices dual_quaternion_skinning(const Vertices& rest, const SkinningWeights& weights,
                                  const Transforms& skinning);
// The same from per-joint unit dual quaternions (either sign of each is fine).
Vertices dual_quaternion_skinning(const Vertices& rest, const SkinningWeights& weights,
                                  const std::vector<DualQuaternion>& joints);

}  // namespace weft::capture
