#include "capture/character/skeleton.h"

#include <cmath>

#include "graph/error.h"

namespace weft::capture {

namespace {
template <class T>
int index_by_name(const std::vector<T>& items, const std::string& name) {
  for (size_t i = 0; i < items.size(); ++i)
    if (items[i].name == name) return static_cast<int>(i);
  return -1;
}
}  // namespace

int Skeleton::joint_index(const std::string& name) const { return index_by_name(joints, name); }
int Skeleton::marker_index(const std::string& name) const { return index_by_name(markers, name); }
int Skeleton::dof_index(const std::string& name) const { return index_by_name(dofs, name); }

Eigen::MatrixXd Skeleton::dof_to_joint_matrix() const {
  Eigen::MatrixXd W = Eigen::MatrixXd::Zero(num_joints(), num_dofs());
  for (int d = 0; d < num_dofs(); ++d)
    for (const DofInfluence& inf : dofs[d].joints) W(inf.joint, d) += inf.weight;
  return W;
}

Eigen::VectorXi Skeleton::parents() const {
  Eigen::VectorXi p(num_joints());
  for (int j = 0; j < num_joints(); ++j) p(j) = joints[j].parent;
  return p;
}

void validate_skeleton(const Skeleton& s, const std::string& what) {
  for (int j = 0; j < s.num_joints(); ++j) {
    const Joint& joint = s.joints[j];
    if (joint.parent >= j || joint.parent < -1)
      fail(what, ": joint '", joint.name, "' has parent index ", joint.parent,
           "; parents must come before their children");
    if (std::abs(joint.axis.norm() - 1.0) > 1e-9)
      fail(what, ": joint '", joint.name, "' axis is not unit length");
    if (!joint.offset.allFinite() || !std::isfinite(joint.scale))
      fail(what, ": joint '", joint.name, "' has a non-finite offset or scale");
  }
  for (const Marker& m : s.markers)
    if (m.joint < 0 || m.joint >= s.num_joints())
      fail(what, ": marker '", m.name, "' refers to joint index ", m.joint);
  for (const Dof& d : s.dofs)
    for (const DofInfluence& inf : d.joints)
      if (inf.joint < 0 || inf.joint >= s.num_joints())
        fail(what, ": dof '", d.name, "' refers to joint index ", inf.joint);
}

Eigen::VectorXd joint_parameters(const Skeleton& s, const Eigen::VectorXd& dofs) {
  if (dofs.size() != s.num_dofs())
    fail("forward kinematics: ", dofs.size(), " dof values for a skeleton with ", s.num_dofs(), " dofs");
  Eigen::VectorXd p = Eigen::VectorXd::Zero(s.num_joints());
  for (int d = 0; d < s.num_dofs(); ++d)
    for (const DofInfluence& inf : s.dofs[d].joints) p(inf.joint) += inf.weight * dofs(d);
  return p;
}

Eigen::Isometry3d joint_local_transform(const Joint& joint, double parameter) {
  Eigen::Isometry3d L = Eigen::Isometry3d::Identity();
  L.translation() = joint.offset * joint.scale;
  if (joint.type == JointType::revolute)
    L.linear() = Eigen::AngleAxisd(parameter, joint.axis).toRotationMatrix();
  else
    L.translation() += parameter * joint.axis;  // rotation part is identity
  return L;
}

Transforms forward_kinematics(const Skeleton& s, const Eigen::VectorXd& dofs) {
  const Eigen::VectorXd p = joint_parameters(s, dofs);
  Transforms G(s.num_joints());
  for (int j = 0; j < s.num_joints(); ++j) {
    const Eigen::Isometry3d L = joint_local_transform(s.joints[j], p(j));
    const int parent = s.joints[j].parent;
    G[j] = parent < 0 ? L : G[parent] * L;
  }
  return G;
}

Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> joint_positions(const Transforms& G) {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> P(G.size(), 3);
  for (size_t j = 0; j < G.size(); ++j) P.row(j) = G[j].translation().transpose();
  return P;
}

Transforms skinning_transforms(const Transforms& posed, const Transforms& bind) {
  if (posed.size() != bind.size()) fail("skinning_transforms: ", posed.size(), " posed vs ", bind.size(), " bind transforms");
  Transforms S(posed.size());
  for (size_t j = 0; j < posed.size(); ++j) S[j] = posed[j] * bind[j].inverse(Eigen::Isometry);
  return S;
}

Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> marker_positions(
    const Skeleton& s, const Transforms& posed, const Transforms& zero_pose) {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> P(s.num_markers(), 3);
  for (int m = 0; m < s.num_markers(); ++m) {
    const int j = s.markers[m].joint;
    P.row(m) = (posed[j] * (zero_pose[j].inverse(Eigen::Isometry) * s.markers[m].offset)).transpose();
  }
  return P;
}

Eigen::VectorXd clamp_to_limits(const Skeleton& s, const Eigen::VectorXd& dofs) {
  Eigen::VectorXd out = dofs;
  for (int d = 0; d < s.num_dofs() && d < out.size(); ++d)
    if (s.dofs[d].limited) out(d) = std::clamp(out(d), s.dofs[d].lower, s.dofs[d].upper);
  return out;
}

}  // namespace weft::capture
