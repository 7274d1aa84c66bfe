#pragma once
// The root chain's dofs of a capture. CaptureModel (capture/model/capture_networks.h)
// keeps the root chain at rest and places the posed skeleton rigidly:
//   X_world = R (X − p0) + t.
// A .motion file or BVH needs that placement as dofs. It is the root chain's pose whose
// last joint (the pivot) has the global transform M · G_pivot(rest), M = (R, t − R p0):
// every other joint hangs below the pivot, so the whole skeleton then equals the rigidly
// placed one. Solved by damped Gauss–Newton over the root chain's dofs (any chain of
// prismatic and revolute joints, any dof weights), from the previous frame's solution,
// or from several starts when there is none or it does not converge.
#include <Eigen/Core>

#include "capture/character/character.h"
#include "capture/model/capture_networks.h"

namespace weft::capture {

class RootPlacement {
 public:
  explicit RootPlacement(const Character& character);
  // dofs: D values with the root chain at rest (CapturePrediction::dofs); returns them with
  // the root chain's dofs solved. `previous` (optional): the last frame's result.
  // The residual (pivot position error in character units + rotation Frobenius error) is
  // left in *residual when given.
  Eigen::VectorXd place(const Eigen::VectorXd& dofs, const Eigen::Matrix3d& rotation,
                        const Eigen::Vector3d& translation, const Eigen::VectorXd* previous = nullptr,
                        double* residual = nullptr) const;

 private:
  Eigen::Isometry3d pivot_transform(const Eigen::VectorXd& dofs) const;
  Eigen::VectorXd solve(Eigen::VectorXd dofs, const Eigen::Isometry3d& target, double* residual) const;

  const Character& character_;
  PoseParametrisation param_;
  std::vector<int> chain_;  // joints from the root to the pivot
  Eigen::Isometry3d rest_pivot_;
  double length_ = 1;       // character units in a metre: weighs position against rotation
};

}  // namespace weft::capture
