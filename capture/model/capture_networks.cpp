#include "capture/model/capture_networks.h"

#include <algorithm>
#include <cmath>

#include "capture/character/skeleton.h"
#include "graph/autograd.h"
#include "graph/error.h"
#include "graph/random.h"
#include "nn/layers.h"
#include "ops/geometry.h"
#include "ops/ops.h"

namespace weft::capture {

Vertices sample_vertices(const Tensor& vertices, int64_t b) {
  WEFT_CHECK(vertices.dim() == 3 && vertices.size(2) == 3 && b >= 0 && b < vertices.size(0),
             "sample_vertices: expected [B,V,3] and b < B, got ", shape_str(vertices.shape()), " and ", b);
  const int64_t V = vertices.size(1);
  Vertices out(V, 3);
  if (vertices.dtype() == DType::F64) {
    const double* p = vertices.data<double>() + b * V * 3;
    for (int64_t i = 0; i < V * 3; ++i) out.data()[i] = p[i];
    return out;
  }
  const float* p = vertices.data<float>() + b * V * 3;
  for (int64_t i = 0; i < V * 3; ++i) out.data()[i] = p[i];
  return out;
}

PoseParametrisation pose_parametrisation(const Character& character) {
  const Skeleton& sk = character.skeleton;
  WEFT_CHECK(sk.num_joints() > 0, character.source, ": the skeleton has no joints");
  std::vector<int> children_count(sk.num_joints(), 0);
  for (const Joint& j : sk.joints)
    if (j.parent >= 0) ++children_count[j.parent];
  std::vector<int> chain = {0};
  for (;;) {
    const int last = chain.back();
    if (children_count[last] != 1) break;
    int child = -1;
    for (int j = last + 1; j < sk.num_joints(); ++j)
      if (sk.joints[j].parent == last) child = j;
    if (child < 0 || sk.joints[child].offset.norm() * sk.joints[child].scale > 1e-12) break;
    chain.push_back(child);
  }
  PoseParametrisation p;
  for (int d = 0; d < sk.num_dofs(); ++d) {
    bool root = false;
    for (const DofInfluence& inf : sk.dofs[d].joints)
      root |= std::find(chain.begin(), chain.end(), inf.joint) != chain.end();
    (root ? p.root_dofs : p.free_dofs).push_back(d);
  }
  p.pivot_joint = chain.back();
  p.pivot = forward_kinematics(sk, character.rest_dofs)[p.pivot_joint].translation();
  return p;
}

Eigen::Matrix3d root_rotation_world(const Character& character, const PoseParametrisation& param,
                                    const PosedCharacter& posed) {
  WEFT_CHECK(param.pivot_joint >= 0 && size_t(param.pivot_joint) < posed.joints.size(),
             "root_rotation_world: pivot joint ", param.pivot_joint, " of a skeleton with ", posed.joints.size(),
             " joints");
  const Eigen::Matrix3d rest = forward_kinematics(character.skeleton, character.rest_dofs)[param.pivot_joint].linear();
  return posed.joints[param.pivot_joint].linear() * rest.transpose();
}

CaptureNetworks::CaptureNetworks(const Character& character, const NetworkConfig& config, uint64_t seed)
    : nn::Module("CaptureNetworks") {
  pose_outputs_ = static_cast<int64_t>(pose_parametrisation(character).free_dofs.size()) + 6;
  int64_t nodes = character.body.graph.nodes.rows();
  if (character.has_cloth()) nodes += character.cloth->graph.nodes.rows();
  deformation_outputs_ = 6 * nodes;
  nn::ResNetOptions o;
  o.outputs = pose_outputs_;
  o.seed = seed;
  pose_net = register_module("pose_net", nn::make_resnet(config.backbone, o));
  o.outputs = deformation_outputs_;
  o.seed = seed + 1;
  deformation_net = register_module("deformation_net", nn::make_resnet(config.backbone, o));
  // Zero last layer: PADefNet starts at A = 0, T = 0, the skinned template.
  deformation_net->fc->weight.fill(0.0);
  deformation_net->fc->bias.fill(0.0);
  input_size_ = config.input_size;
  image_input_ = config.image_input;
  if (config.keypoint_input) {
    Generator gen(seed + 2);
    const int64_t hidden = config.lift_width;
    pose_lift = std::make_shared<nn::Sequential>();
    for (int layer = 0; layer < config.lift_layers; ++layer) {
      pose_lift->push_back(std::make_shared<nn::Linear>(layer == 0 ? kLiftInputs : hidden, hidden, gen));
      pose_lift->push_back(std::make_shared<nn::ReLU>());
    }
    // Zero last layer: the branch starts as no change to PoseNet's output.
    pose_lift->push_back(std::make_shared<nn::Linear>(hidden, pose_outputs_, gen, true, DType::F32, false));
    register_module("pose_lift", pose_lift);
  }
  if (config.detector.enabled) detector = register_module("detector", std::make_shared<PersonDetector>(config.detector, seed + 3));
}

PersonDetector& CaptureNetworks::require_detector(const std::string& model) const {
  if (!detector)
    fail(model, ": this model has no person detector (no detector.* weights; its config has no network.detector), so "
         "weft cannot find the person's keypoints and mask itself. Add one without retraining the rest (weft train "
         "--init MODEL/model.safetensors with the same networks plus network.detector and only stages.detector, e.g. "
         "configs/train/default_detector.yaml for a default.yaml model), retrain with a network.detector section and "
         "stages.detector.steps > 0 (configs/train/demo.yaml has one; docs/TRAINING.md, \"The person detector\"), or "
         "pass --keypoints and --masks");
  return *detector;
}

Tensor CaptureNetworks::pose(const Batch& batch) {
  if (!image_input_) return pose_from_keypoints(batch);
  const Tensor image_out = pose_net->forward(batch.images);
  if (!pose_lift) return image_out;
  return ops::add(image_out, pose_lift->forward(keypoint_lift_input(batch, input_size_)));
}

Tensor CaptureNetworks::pose_from_keypoints(const Batch& batch) const {
  WEFT_CHECK(pose_lift != nullptr, "CaptureNetworks: no lifting branch (network.keypoint_input is false)");
  return pose_lift->forward(keypoint_lift_input(batch, input_size_));
}

std::vector<nn::NamedTensor> CaptureNetworks::pose_parameters() const {
  std::vector<nn::NamedTensor> params;
  if (image_input_)
    for (nn::NamedTensor p : pose_net->named_parameters()) params.push_back({"pose_net." + p.name, p.tensor});
  if (pose_lift)
    for (nn::NamedTensor p : pose_lift->named_parameters()) params.push_back({"pose_lift." + p.name, p.tensor});
  return params;
}

Tensor keypoint_lift_input(const Batch& batch, int input_size) {
  const int64_t B = batch.size();
  WEFT_CHECK(batch.keypoints.dim() == 3 && batch.keypoints.size(0) == B && batch.keypoints.size(1) == kBody25Count &&
                 batch.keypoints.size(2) == 3 && int64_t(batch.cameras.size()) == B,
             "keypoint_lift_input: keypoints [B,25,3] and B crop cameras expected");
  const Tensor kp = batch.keypoints.to(DType::F64);
  const double* k = kp.data<double>();
  std::vector<double> x(size_t(B * kLiftInputs), 0.0);
  for (int64_t b = 0; b < B; ++b) {
    double* row = x.data() + b * kLiftInputs;
    for (int j = 0; j < kBody25Count; ++j) {
      const double* d = k + (b * kBody25Count + j) * 3;
      if (!(d[2] > 0) || !std::isfinite(d[0]) || !std::isfinite(d[1])) continue;
      row[3 * j] = d[0] / input_size - 0.5;
      row[3 * j + 1] = d[1] / input_size - 0.5;
      row[3 * j + 2] = d[2];
    }
    const Eigen::Matrix3d& K = batch.cameras[size_t(b)].K;
    row[3 * kBody25Count] = (0.5 * input_size - K(0, 2)) / K(0, 0);
    row[3 * kBody25Count + 1] = (0.5 * input_size - K(1, 2)) / K(1, 1);
  }
  return Tensor::from_data({B, kLiftInputs}, x, DType::F32);
}

Tensor CaptureNetworks::forward(const Tensor&) {
  fail("CaptureNetworks: call pose_net or deformation_net, not the container");
}

SampleViews sample_views(const std::vector<Camera>& input_cameras,
                         const std::vector<std::vector<KeypointView>>& frame_views,
                         const std::vector<double>& keypoint_mask, DType dtype) {
  WEFT_CHECK(input_cameras.size() == frame_views.size(), "sample_views: ", input_cameras.size(),
             " input cameras for ", frame_views.size(), " samples");
  SampleViews v;
  for (const Camera& c : input_cameras) v.input_rotations.push_back(c.R);
  v.translation = root_translation_terms(frame_views, keypoint_mask, dtype);
  return v;
}

CaptureModel::CaptureModel(const Character& character, const NetworkConfig& config)
    : character_(character), config_(config), layer_(character, DType::F32),
      param_(pose_parametrisation(character)),
      pose_dofs_(character.skeleton, character.rest_dofs, param_.free_dofs, config.dof_scale) {
  const Tensor& m = layer_.body25_mask();
  for (int64_t i = 0; i < m.numel(); ++i) keypoint_mask_.push_back(m.data<float>()[i]);
  pivot_ = Tensor::from_data({1, 3}, {param_.pivot.x(), param_.pivot.y(), param_.pivot.z()}, DType::F32);
  canonical_ = Tensor::from_data({3, 3}, {1, 0, 0, 0, -1, 0, 0, 0, -1}, DType::F32);
  rotation_bias_ = Tensor::from_data({6}, {1, 0, 0, 0, 1, 0}, DType::F32);

  // Keypoints carried by the body's embedded graph: each rides on the graph nodes and
  // skinning weights of the body vertex nearest to it in the bind pose.
  const Vertices bind = pose_character(character, character.rest_dofs).body25;
  const Vertices& V = character.body.mesh.V;
  const EmbeddedGraph& g = character.body.graph;
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> skin_joints;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> skin_weights;
  character.body.weights.padded(skin_joints, skin_weights);
  const int64_t n = g.vertex_nodes.cols(), ns = skin_joints.cols();
  std::vector<double> points(kBody25Count * 3, 0.0), node_w(kBody25Count * n), skin_w(kBody25Count * ns);
  std::vector<int64_t> node_i(kBody25Count * n), skin_i(kBody25Count * ns);
  for (int k = 0; k < kBody25Count; ++k) {
    int nearest = 0;
    if (bind.row(k).allFinite()) {
      (V.rowwise() - bind.row(k)).rowwise().squaredNorm().minCoeff(&nearest);
      for (int a = 0; a < 3; ++a) points[3 * k + a] = bind(k, a);
    }
    for (int64_t j = 0; j < n; ++j) node_i[k * n + j] = g.vertex_nodes(nearest, j), node_w[k * n + j] = g.vertex_weights(nearest, j);
    for (int64_t j = 0; j < ns; ++j) skin_i[k * ns + j] = skin_joints(nearest, j), skin_w[k * ns + j] = skin_weights(nearest, j);
  }
  landmarks_.rest = Tensor::from_data({kBody25Count, 3}, points, DType::F32);
  landmarks_.nodes = layer_.body().nodes;
  landmarks_.node_index = Tensor::from_indices({kBody25Count, n}, node_i);
  landmarks_.node_weights = Tensor::from_data({kBody25Count, n}, node_w, DType::F32);
  landmarks_.skin_index = Tensor::from_indices({kBody25Count, ns}, skin_i);
  landmarks_.skin_weights = Tensor::from_data({kBody25Count, ns}, skin_w, DType::F32);
}

int64_t CaptureModel::pose_outputs() const { return static_cast<int64_t>(param_.free_dofs.size()) + 6; }

int64_t CaptureModel::deformation_outputs() const {
  int64_t k = layer_.body().num_nodes();
  if (layer_.cloth()) k += layer_.cloth()->num_nodes();
  return 6 * k;
}

Tensor CaptureModel::to_world(const Tensor& points, const Tensor& rotation_t, const Tensor& translation) const {
  const int64_t B = points.size(0);
  return ops::add(ops::matmul(ops::sub(points, pivot_), rotation_t), ops::reshape(translation, {B, 1, 3}));
}

CapturePrediction CaptureModel::predict(const Tensor& pose_output, const Tensor& deformation_output,
                                        const SampleViews& views, bool with_meshes) const {
  const int64_t B = pose_output.size(0), F = param_.free_dofs.size();
  WEFT_CHECK(pose_output.dim() == 2 && pose_output.size(1) == F + 6, "CaptureModel: PoseNet output ",
             shape_str(pose_output.shape()), ", expected [B, ", F + 6, "]");
  WEFT_CHECK(int64_t(views.input_rotations.size()) == B, "CaptureModel: ", views.input_rotations.size(),
             " input views for a batch of ", B);
  CapturePrediction p;
  p.dofs = pose_dofs_.dofs(ops::slice(pose_output, 1, 0, F));  // limited dofs within their limits
  const Tensor relative = rotation_from_6d(ops::add(ops::slice(pose_output, 1, F, F + 6), rotation_bias_));
  std::vector<double> rc(B * 9);
  for (int64_t b = 0; b < B; ++b)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rc[b * 9 + r * 3 + c] = views.input_rotations[b](c, r);  // R_cᵀ
  const Tensor camera_to_world = Tensor::from_data({B, 3, 3}, rc, DType::F32);
  p.rotation = ops::matmul(ops::matmul(camera_to_world, relative), canonical_);
  const Tensor rotation_t = ops::transpose(p.rotation, 1, 2);

  const PosedJoints joints = layer_.pose(p.dofs);
  Tensor keypoints = layer_.body25(joints);

  const GraphMotion g = graph_motion(deformation_output, B, p);
  // The keypoints move with the body's graph (as DeepCap's markers ride on the template).
  if (deformation_output.defined())
    keypoints = ops::add(keypoints, ops::sub(layer_.deform(landmarks_, joints, g.body_angles, g.body_translations),
                                             layer_.deform(landmarks_, joints, Tensor(), Tensor())));
  const Tensor oriented = ops::matmul(ops::sub(keypoints, pivot_), rotation_t);
  p.translation = solve_root_translation(views.translation, oriented);
  p.keypoints = ops::add(oriented, ops::reshape(p.translation, {B, 1, 3}));
  if (!with_meshes) return p;
  p.body = to_world(layer_.deform(layer_.body(), joints, g.body_angles, g.body_translations), rotation_t, p.translation);
  if (layer_.cloth())
    p.cloth = to_world(layer_.deform(*layer_.cloth(), joints, g.cloth_angles, g.cloth_translations), rotation_t,
                       p.translation);
  return p;
}

CaptureModel::GraphMotion CaptureModel::graph_motion(const Tensor& deformation_output, int64_t B,
                                                     CapturePrediction& p) const {
  GraphMotion g;
  if (!deformation_output.defined()) return g;
  WEFT_CHECK(deformation_output.dim() == 2 && deformation_output.size(0) == B &&
                 deformation_output.size(1) == deformation_outputs(),
             "CaptureModel: PADefNet output ", shape_str(deformation_output.shape()), ", expected [", B, ", ",
             deformation_outputs(), "]");
  const double to_units = config_.translation_scale_m / character_.metres_per_unit;
  int64_t at = 0;
  auto take = [&](int64_t k, double s) {
    Tensor t = ops::scale(ops::reshape(ops::slice(deformation_output, 1, at, at + 3 * k), {B, k, 3}), s);
    at += 3 * k;
    return t;
  };
  const int64_t kb = layer_.body().num_nodes();
  g.body_angles = take(kb, config_.angle_scale);
  g.body_translations = take(kb, to_units);
  p.body_rotations = ops::euler_to_rotation(g.body_angles);
  p.body_translations = g.body_translations;
  if (layer_.cloth()) {
    const int64_t kc = layer_.cloth()->num_nodes();
    g.cloth_angles = take(kc, config_.angle_scale);
    g.cloth_translations = take(kc, to_units);
    p.cloth_rotations = ops::euler_to_rotation(g.cloth_angles);
    p.cloth_translations = g.cloth_translations;
  }
  return g;
}

CapturePrediction CaptureModel::predict_posed(const Tensor& dofs, const Tensor& deformation_output,
                                              bool with_meshes) const {
  const int64_t B = dofs.size(0), D = int64_t(character_.rest_dofs.size());
  WEFT_CHECK(dofs.dim() == 2 && dofs.size(1) == D, "CaptureModel: given dofs ", shape_str(dofs.shape()),
             ", expected [B, ", D, "]");
  CapturePrediction p;
  p.dofs = dofs;
  std::vector<double> eye(B * 9, 0.0);
  for (int64_t b = 0; b < B; ++b) eye[b * 9] = eye[b * 9 + 4] = eye[b * 9 + 8] = 1;
  p.rotation = Tensor::from_data({B, 3, 3}, eye, dofs.dtype());
  p.translation = Tensor::from_data({B, 3}, std::vector<double>(B * 3, 0.0), dofs.dtype());
  const PosedJoints joints = layer_.pose(dofs);
  p.keypoints = layer_.body25(joints);
  const GraphMotion g = graph_motion(deformation_output, B, p);
  if (deformation_output.defined())
    p.keypoints = ops::add(p.keypoints, ops::sub(layer_.deform(landmarks_, joints, g.body_angles, g.body_translations),
                                                 layer_.deform(landmarks_, joints, Tensor(), Tensor())));
  if (!with_meshes) return p;
  p.body = layer_.deform(layer_.body(), joints, g.body_angles, g.body_translations);
  if (layer_.cloth()) p.cloth = layer_.deform(*layer_.cloth(), joints, g.cloth_angles, g.cloth_translations);
  return p;
}

SampleViews batch_views(const Batch& batch, const MultiviewSupervision& sup, const CaptureModel& model) {
  std::vector<std::vector<KeypointView>> views(batch.frames.size());
  for (size_t b = 0; b < batch.frames.size(); ++b)
    for (int v = 0; v < sup.views(); ++v)
      views[b].push_back({sup.camera(batch.frames[b], v), sup.detections(batch.frames[b], v)});
  return sample_views(batch.cameras, views, model.keypoint_mask(), DType::F32);
}

CapturePrediction predict_batch(CaptureNetworks& nets, const CaptureModel& model, const Batch& batch,
                                const MultiviewSupervision& sup, Learning learning, bool deformation,
                                bool with_meshes, const Tensor& oracle_dofs) {
  auto run = [&](nn::ResNet& net, bool learns, bool batch_statistics) {
    net.train(learns && batch_statistics);
    if (learns) return net.forward(batch.images);
    NoGradGuard no_grad;
    return net.forward(batch.images);
  };
  const bool deformation_learns =
      learning == Learning::deformation || learning == Learning::deformation_frozen_statistics;
  const Tensor def_out = deformation ? run(*nets.deformation_net, deformation_learns,
                                           learning == Learning::deformation)
                                     : Tensor();
  if (oracle_dofs.defined()) return model.predict_posed(oracle_dofs, def_out, with_meshes);
  nets.pose_net->train(learning == Learning::pose);
  const Tensor pose_out = [&] {
    if (learning == Learning::pose) return nets.pose(batch);
    NoGradGuard no_grad;
    return nets.pose(batch);
  }();
  return model.predict(pose_out, def_out, batch_views(batch, sup, model), with_meshes);
}

}  // namespace weft::capture
