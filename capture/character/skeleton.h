#pragma once
// Kinematic skeletons with Skeletool semantics, and forward kinematics in plain Eigen.
//
// A skeleton is a list of 1-dof joints, parents before children. Each joint has one
// scalar parameter p_j = Σ_d weight_dj × dof_d. Its local transform is
//   L_j = T(offset_j · scale_j) · M_j(p_j),
// M_j = rotation by p_j radians about the unit axis (revolute) or translation by p_j
// units along the unit axis (prismatic); the global transform is G_j = G_parent · L_j.
// Lengths are in the character's units (ddc: millimetres), angles in radians.
// Markers are points fixed to a joint; see marker_positions for their convention.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace weft::capture {

enum class JointType { revolute, prismatic };

struct Joint {
  std::string name;
  JointType type = JointType::revolute;
  int parent = -1;         // index of the parent joint, smaller than this joint's; -1: root
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // from the parent's frame, before `scale` (character units)
  // Unit rotation / translation axis in the joint's frame; left zero, the skeleton's check fails.
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  double scale = 1.0;      // multiplies offset
};

// A point rigidly attached to a joint. `offset` is given in the skeleton's model frame
// at the zero pose (all dofs 0), as Skeletool stores it (see marker_positions).
struct Marker {
  std::string name;
  int joint = -1;
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  double size = 0;          // display radius (character units)
  Eigen::Vector3d color{1, 1, 1};
};

struct DofInfluence {
  int joint = -1;
  double weight = 1.0;
};

struct Dof {
  std::string name;
  std::vector<DofInfluence> joints;  // the joints this dof drives and with what weight
  bool limited = false;
  double lower = 0, upper = 0;       // valid when limited (radians or units)
};

struct Skeleton {
  std::vector<Joint> joints;
  std::vector<Marker> markers;
  std::vector<Dof> dofs;

  int num_joints() const { return static_cast<int>(joints.size()); }
  int num_markers() const { return static_cast<int>(markers.size()); }
  int num_dofs() const { return static_cast<int>(dofs.size()); }
  // Index by exact name, or -1.
  int joint_index(const std::string& name) const;
  int marker_index(const std::string& name) const;
  int dof_index(const std::string& name) const;

  // The dense J×D matrix W with p = W · dofs (173×107 for ddc: small, dense is simplest).
  Eigen::MatrixXd dof_to_joint_matrix() const;
  // Parents as a vector (-1 for roots), for ops that want a contiguous array.
  Eigen::VectorXi parents() const;
};

// Throws weft::Error (prefixed by `what`) unless parents precede children, axes are unit
// length, and every dof/marker joint index is valid.
void validate_skeleton(const Skeleton& skeleton, const std::string& what);

using Transforms = std::vector<Eigen::Isometry3d>;

// p = W · dofs (J values).
Eigen::VectorXd joint_parameters(const Skeleton& skeleton, const Eigen::VectorXd& dofs);
// Local transform of one joint for parameter p.
Eigen::Isometry3d joint_local_transform(const Joint& joint, double parameter);
// Global joint transforms G_j for the given dof values (D).
Transforms forward_kinematics(const Skeleton& skeleton, const Eigen::VectorXd& dofs);
// Joint origins (J×3) of a set of global transforms.
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> joint_positions(const Transforms& global);

// Skinning transforms S_j = G_j(θ) · G_j(bind)⁻¹: they move bind-pose geometry to pose θ.
Transforms skinning_transforms(const Transforms& posed, const Transforms& bind);

// Marker positions (M×3) for posed transforms: marker m on joint j sits at
//   G_j(θ) · G_j(0)⁻¹ · offset_m,
// i.e. its offset is a model-frame point at the zero pose, carried along by its joint.
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> marker_positions(
    const Skeleton& skeleton, const Transforms& posed, const Transforms& zero_pose);

// Clamps dof values to the limits of limited dofs.
Eigen::VectorXd clamp_to_limits(const Skeleton& skeleton, const Eigen::VectorXd& dofs);

}  // namespace weft::capture
