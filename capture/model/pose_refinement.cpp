#include "capture/model/pose_refinement.h"

#include <algorithm>
#include <chrono>

#include "capture/model/capture_networks.h"
#include "capture/model/view_landmark_loss.h"
#include "graph/autograd.h"
#include "graph/error.h"
#include "nn/optim.h"
#include "ops/ops.h"

namespace weft::capture {

PoseRefinementSummary refine_pose_outputs(const CaptureModel& model, const std::vector<KeypointView>& views,
                                          std::vector<Eigen::VectorXd>& outputs, const PoseRefinementConfig& config) {
  WEFT_CHECK(views.size() == outputs.size(), "refine_pose_outputs: ", views.size(), " views for ", outputs.size(),
             " frames");
  PoseRefinementSummary s;
  if (config.iterations <= 0 || outputs.empty()) return s;
  const auto start_time = std::chrono::steady_clock::now();
  const std::vector<double>& mask = model.keypoint_mask();
  std::vector<size_t> fitted;
  for (size_t i = 0; i < views.size(); ++i)
    if (mapped_detection_count(views[i].detections, mask) >= 2) fitted.push_back(i);
  const int64_t P = outputs[0].size();
  const double metres_per_unit = model.character().metres_per_unit;
  constexpr int kMidHip = 8;  // BODY_25
  double mapped_keypoints = 0;
  for (double m : mask) mapped_keypoints += m > 0;
  const Tensor depth_mask = Tensor::from_data({1, kBody25Count}, mask, DType::F32);
  double before_sum = 0, after_sum = 0;
  int detections = 0;
  for (size_t first = 0; first < fitted.size(); first += size_t(config.batch_size)) {
    const int64_t B = int64_t(std::min(fitted.size() - first, size_t(config.batch_size)));
    std::vector<double> start;
    std::vector<std::vector<KeypointView>> batch_views(static_cast<size_t>(B));
    SampleViews placed;
    for (int64_t b = 0; b < B; ++b) {
      const size_t i = fitted[first + size_t(b)];
      WEFT_CHECK(outputs[i].size() == P, "refine_pose_outputs: frame ", i, " has ", outputs[i].size(), " outputs, not ", P);
      start.insert(start.end(), outputs[i].data(), outputs[i].data() + P);
      batch_views[size_t(b)].push_back(views[i]);
      placed.input_rotations.push_back(views[i].camera.R);
    }
    placed.translation = root_translation_terms(batch_views, mask, DType::F32);
    const Tensor network = Tensor::from_data({B, P}, start, DType::F32);
    Tensor o = Tensor::from_data({B, P}, start, DType::F32);
    o.set_requires_grad(true);
    // Each keypoint's depth along its frame's input camera axis, relative to MidHip (metres).
    std::vector<double> axis_values;
    for (int64_t b = 0; b < B; ++b)
      for (int j = 0; j < 3; ++j) axis_values.push_back(placed.input_rotations[size_t(b)](2, j) * metres_per_unit);
    const Tensor axis = Tensor::from_data({B, 1, 3}, axis_values, DType::F32);
    const auto relative_depth = [&](const Tensor& keypoints) {
      const Tensor z = ops::sum(ops::mul(keypoints, axis), {2});  // [B,25]
      return ops::sub(z, ops::slice(z, 1, kMidHip, kMidHip + 1));
    };
    Tensor network_depth;
    if (config.depth_prior > 0) {
      NoGradGuard no_grad;
      network_depth = relative_depth(model.predict(network, Tensor(), placed, false).keypoints);
    }
    nn::AdamOptions ao;
    ao.lr = config.lr;
    nn::Adam adam({{"outputs", o}}, ao);
    LandmarkStatistics before;
    for (int it = 0; it < config.iterations; ++it) {
      adam.zero_grad();
      const CapturePrediction p = model.predict(o, Tensor(), placed, false);
      const Tensor fit = landmark_loss_over_views(p.keypoints, batch_views, mask, it == 0 ? &before : nullptr);
      const Tensor d = ops::sub(o, network);
      Tensor loss = ops::add(fit, ops::scale(ops::sum(ops::mul(d, d)), config.prior / double(B * P)));
      if (config.depth_prior > 0) {
        const Tensor dz = ops::mul(ops::sub(relative_depth(p.keypoints), network_depth), depth_mask);
        loss = ops::add(loss, ops::scale(ops::sum(ops::mul(dz, dz)), config.depth_prior / (double(B) * mapped_keypoints)));
      }
      loss.backward();
      adam.step();
    }
    LandmarkStatistics after;
    {
      NoGradGuard no_grad;
      landmark_loss_over_views(model.predict(o, Tensor(), placed, false).keypoints, batch_views, mask, &after);
    }
    before_sum += before.mean_error_px * before.detections;
    after_sum += after.mean_error_px * after.detections;
    detections += before.detections;
    const float* fitted_o = o.data<float>();
    for (int64_t b = 0; b < B; ++b)
      outputs[fitted[first + size_t(b)]] = Eigen::Map<const Eigen::VectorXf>(fitted_o + b * P, P).cast<double>();
  }
  s.frames = int(fitted.size());
  s.error_before_px = detections ? before_sum / detections : 0;
  s.error_after_px = detections ? after_sum / detections : 0;
  s.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return s;
}

}  // namespace weft::capture
