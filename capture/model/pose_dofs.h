#pragma once
// What PoseNet's outputs mean: the skeleton's dofs, each limited dof kept inside its
// limits (character/skeleton.h: Dof::limited, lower, upper; the generated skeleton's
// limits are in character/joint_limits.h, a Skeletool character's in its .skeleton).
//
// For PoseNet's raw output x of free dof d (s = NetworkConfig::dof_scale, r = rest value):
//   unlimited:  θ = r + s·x
//   limited:    θ = lo + (hi − lo)·σ(k·x + b),   σ the logistic sigmoid, with
//               b = logit(ρ), ρ = (r − lo)/(hi − lo) clamped to [0.01, 0.99], and
//               k = s / ((hi − lo)·ρ(1 − ρ)).
// So θ stays in [lo, hi] for any x; x = 0 gives the rest value (when it lies inside the
// limits' inner 98 %, else the nearest point of it); and dθ/dx at x = 0 is s, as for an
// unlimited dof, so a network starts training as it did before limits. A rest pose need
// not be the middle of the range: the offset b puts it where it is. Locked dofs (lo = hi)
// give lo. The ops (matmul, mul, add, sigmoid) have float64 gradient checks.
//
// Model folders trained before limits (weft < this change) load as before, but their
// limited dofs now read through the sigmoid: identical near the rest pose (same value
// and slope at x = 0), different far from it. Retrain for exact results.
#include <Eigen/Core>
#include <vector>

#include "capture/character/skeleton.h"
#include "graph/tensor.h"

namespace weft::capture {

class PoseDofs {
 public:
  // free_dofs: the dofs PoseNet regresses, in its output order; the others stay at rest.
  PoseDofs(const Skeleton& skeleton, const Eigen::VectorXd& rest_dofs, const std::vector<int>& free_dofs,
           double dof_scale, DType dtype = DType::F32);
  // PoseNet's outputs [B, F] → dofs [B, D] (differentiable).
  Tensor dofs(const Tensor& outputs) const;
  // The outputs (F) that give these dofs (D) (their free dofs, moved inside the limits by
  // 1e-6 of the range where they are on or beyond them): the inverse of dofs().
  Eigen::VectorXd outputs_for(const Eigen::VectorXd& dofs) const;
  int free_count() const { return static_cast<int>(free_.size()); }
  int limited_count() const;

 private:
  struct Free {
    int dof;
    bool limited;
    double lo, hi, k, b;  // limited: θ = lo + (hi − lo)·σ(k·x + b)
    double s;             // unlimited: θ = r + s·x
  };
  std::vector<Free> free_;
  Eigen::VectorXd rest_;
  Tensor free_to_dofs_;  // [F, D] 0/1
  Tensor rest_tensor_;   // [D]
  Tensor linear_;        // [F] s for unlimited dofs, 0 for limited
  Tensor slope_, bias_;  // [F] k and b for limited dofs, 0 for unlimited
  Tensor span_, offset_; // [F] (hi − lo) and (lo − r) for limited dofs, 0 for unlimited
};

}  // namespace weft::capture
