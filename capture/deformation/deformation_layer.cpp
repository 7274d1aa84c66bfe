#include "capture/deformation/deformation_layer.h"

#include "ops/ops.h"

namespace weft::capture {
namespace {

Tensor rows_to_tensor(const Eigen::Ref<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>& m,
                      DType dtype) {
  std::vector<double> v(m.data(), m.data() + m.size());
  return Tensor::from_data({m.rows(), m.cols()}, v, dtype);
}

Tensor index_tensor(const Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>& m) {
  std::vector<int64_t> v(m.data(), m.data() + m.size());
  return Tensor::from_indices({m.rows(), m.cols()}, v);
}

std::vector<double> inverse_rows(const Transforms& transforms) {
  std::vector<double> out;
  for (const Eigen::Isometry3d& t : transforms) {
    const Eigen::Matrix4d inv = t.inverse().matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) out.push_back(inv(r, c));
  }
  return out;
}

DeformableSurface make_surface(const CharacterMesh& m, DType dtype) {
  DeformableSurface s;
  s.rest = rows_to_tensor(m.mesh.V, dtype);
  s.nodes = rows_to_tensor(m.graph.nodes, dtype);
  s.node_index = index_tensor(m.graph.vertex_nodes);
  s.node_weights = rows_to_tensor(m.graph.vertex_weights, dtype);
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> joints;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> weights;
  m.weights.padded(joints, weights);
  s.skin_index = index_tensor(joints);
  s.skin_weights = rows_to_tensor(weights, dtype);
  return s;
}

}  // namespace

DeformationLayer::DeformationLayer(const Character& character, DType dtype) : dtype_(dtype) {
  const Skeleton& sk = character.skeleton;
  const Eigen::MatrixXd W = sk.dof_to_joint_matrix();  // J×D
  const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> Wt = W.transpose();
  dof_to_joint_ = rows_to_tensor(Wt, dtype);
  for (const Joint& j : sk.joints) {
    global_chain_.parents.push_back(j.parent);
    global_chain_.prismatic.push_back(j.type == JointType::prismatic ? 1 : 0);
    for (int a = 0; a < 3; ++a) {
      global_chain_.offsets.push_back(j.offset[a] * j.scale);
      global_chain_.axes.push_back(j.axis[a]);
    }
  }
  skin_chain_ = global_chain_;
  skin_chain_.bind_inverse = inverse_rows(character.bind);
  marker_chain_ = global_chain_;
  marker_chain_.bind_inverse = inverse_rows(character.zero_pose);
  if (sk.num_markers() > 0) {
    std::vector<double> offsets;
    std::vector<int64_t> joints;
    for (const Marker& m : sk.markers) {
      for (int a = 0; a < 3; ++a) offsets.push_back(m.offset[a]);
      joints.push_back(m.joint);
    }
    const int64_t M = sk.num_markers();
    marker_offsets_ = Tensor::from_data({M, 3}, offsets, dtype);
    marker_index_ = Tensor::from_indices({M, 1}, joints);
    marker_weights_ = Tensor::ones({M, 1}, dtype);
  }
  // BODY_25: padded source lists over the rows [joint origins (J); markers (M)].
  const int64_t J = sk.num_joints();
  for (const LandmarkSource& src : character.body25)
    body25_sources_ = std::max<int64_t>(body25_sources_, src.joints.size() + src.markers.size());
  std::vector<int64_t> idx;
  std::vector<double> w, mask;
  for (const LandmarkSource& src : character.body25) {
    std::vector<int64_t> rows(src.joints.begin(), src.joints.end());
    for (int m : src.markers) rows.push_back(J + m);
    for (int64_t s = 0; s < body25_sources_; ++s) {
      const bool used = s < static_cast<int64_t>(rows.size());
      idx.push_back(used ? rows[s] : 0);
      w.push_back(used ? 1.0 / static_cast<double>(rows.size()) : 0.0);
    }
    mask.push_back(rows.empty() ? 0.0 : 1.0);
  }
  body25_index_ = Tensor::from_indices({25 * body25_sources_}, idx);
  body25_weights_ = Tensor::from_data({25, body25_sources_, 1}, w, dtype);
  body25_mask_ = Tensor::from_data({25}, mask, dtype);

  body_ = make_surface(character.body, dtype);
  if (character.has_cloth()) {
    cloth_ = make_surface(*character.cloth, dtype);
    has_cloth_ = true;
  }
}

PosedJoints DeformationLayer::pose(const Tensor& dofs) const {
  if (dofs.dim() != 2 || dofs.size(1) != num_dofs())
    fail("DeformationLayer::pose: dofs must be [B, ", num_dofs(), "], got ",
         shape_str(dofs.shape()));
  const Tensor params = ops::matmul(dofs, dof_to_joint_);
  PosedJoints out;
  out.global = ops::forward_kinematics(params, global_chain_);
  out.skinning = ops::forward_kinematics(params, skin_chain_);
  if (marker_offsets_.defined())
    out.markers = ops::linear_blend_skinning(
        marker_offsets_, ops::forward_kinematics(params, marker_chain_), marker_index_,
        marker_weights_);
  return out;
}

Tensor DeformationLayer::body25(const PosedJoints& joints) const {
  const int64_t B = joints.global.size(0), J = joints.global.size(1);
  Tensor points = ops::reshape(ops::slice(joints.global, 3, 3, 4), {B, J, 3});  // origins
  if (joints.markers.defined()) points = ops::concat({points, joints.markers}, 1);
  const Tensor picked = ops::reshape(ops::index_select(points, 1, body25_index_),
                                     {B, 25, body25_sources_, 3});
  return ops::sum(ops::mul(picked, body25_weights_), {2});
}

Tensor DeformationLayer::deform(const DeformableSurface& s, const PosedJoints& joints,
                                const Tensor& node_angles,
                                const Tensor& node_translations) const {
  const Tensor dq = ops::rigid_to_dual_quaternion(joints.skinning);
  if (!node_angles.defined())
    return ops::dual_quaternion_skinning(s.rest, dq, s.skin_index, s.skin_weights);
  const Tensor rotations = ops::euler_to_rotation(node_angles);
  const Tensor deformed = ops::embedded_deformation(s.rest, s.nodes, rotations,
                                                    node_translations, s.node_index,
                                                    s.node_weights);
  return ops::dual_quaternion_skinning(deformed, dq, s.skin_index, s.skin_weights);
}

}  // namespace weft::capture
