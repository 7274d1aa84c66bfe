#include "capture/training/split_evaluation.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>

#include "capture/character/skeletool_io.h"
#include "capture/io/mesh_io.h"
#include "capture/studio/garment_simulator.h"
#include "capture/studio/garment_windows.h"
#include "capture/training/capture_networks.h"
#include "capture/training/model_folder.h"
#include "capture/training/multiview_losses.h"
#include "graph/autograd.h"
#include "graph/error.h"
#include "nn/checkpoint.h"
#include "nn/safetensors.h"
#include "physics/cloth_metrics.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

struct Mean {
  double sum = 0;
  int64_t n = 0;
  void add(double x, int64_t count = 1) { sum += x * count, n += count; }
  double value(double none = 0) const { return n ? sum / n : none; }
};

// Mean distance (character units) between corresponding rows.
double mean_distance(const Vertices& a, const Vertices& b) { return (a - b).rowwise().norm().mean(); }

}  // namespace

std::string SplitEvaluation::to_json() const {
  return fmt::format(
      "{{\n  \"split\": \"{}\",\n  \"frames\": {},\n  \"views\": {},\n  \"predictions\": {},\n"
      "  \"keypoint_error_px\": {:.4f},\n  \"mean_pose_keypoint_error_px\": {:.4f},\n"
      "  \"joint_error_mm\": {:.3f},\n  \"joint_error_root_relative_mm\": {:.3f},\n  \"root_rotation_error_deg\": {:.3f},\n"
      "  \"mean_pose_joint_error_root_relative_mm\": {:.3f},\n  \"silhouette_iou\": {:.5f},\n"
      "  \"template_silhouette_iou\": {:.5f},\n  \"cloth_error_mm\": {:.3f},\n  \"template_cloth_error_mm\": {:.3f},\n  \"skinned_true_pose_cloth_error_mm\": {:.3f},\n  \"body_error_mm\": {:.3f},\n"
      "  \"penetration_mean_mm\": {:.4f},\n  \"penetration_max_mm\": {:.4f},\n  \"penetrating_fraction\": {:.6f},\n"
      "  \"oob_frames\": {},\n  \"oob_force_mean_n\": {:.6g},\n  \"oob_force_max_n\": {:.6g},\n"
      "  \"oob_force_mean_rel\": {:.6g},\n  \"oob_force_max_rel\": {:.6g},\n  \"seconds\": {:.1f}\n}}\n",
      split, frames, views, predictions, keypoint_error_px, mean_pose_keypoint_error_px, joint_error_mm,
      joint_error_root_relative_mm, root_rotation_error_deg, mean_pose_joint_error_root_relative_mm, silhouette_iou, template_silhouette_iou,
      cloth_error_mm, template_cloth_error_mm, skinned_true_pose_cloth_error_mm, body_error_mm, penetration_mean_mm, penetration_max_mm, penetrating_fraction, oob_frames,
      oob_force_mean_n, oob_force_max_n, oob_force_mean_rel, oob_force_max_rel, seconds);
}

SplitEvaluation evaluate_split(const std::string& config, const std::string& data, const std::string& weights,
                               const std::string& split) {
  const auto t0 = std::chrono::steady_clock::now();
  const TrainingConfig cfg = load_training_config(config);
  const DatasetInfo info = read_dataset_info(data);
  const Character ch = load_character(info.character);
  const CaptureModel model(ch, cfg.network);
  CaptureNetworks nets(ch, cfg.network, cfg.seed);
  load_capture_networks(weights, nets);
  DatasetOptions d;
  d.split = split;
  d.input_size = cfg.network.input_size;
  d.margin = cfg.network.margin;
  const SyntheticDataset ds(data, d);
  const std::vector<int>& frames = ds.frames();
  WEFT_CHECK(!frames.empty(), data, "/dataset.yaml: the split '", split, "' is empty");
  const MultiviewSupervision sup(info, frames, cfg.silhouette_size);
  const int V = sup.views();
  const double mpu = ch.metres_per_unit;
  const PoseParametrisation& param = model.parametrisation();

  const fs::path gt_dir = fs::path(data) / "gt";
  const Motion motion = read_motion((gt_dir / "pose.motion").string(), int(ch.rest_dofs.size()));
  // The mean training pose (regressed dofs averaged, the root chain at rest).
  Eigen::VectorXd mean_dofs = ch.rest_dofs;
  if (info.splits.count("train") && !info.splits.at("train").empty()) {
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(ch.rest_dofs.size());
    for (int f : info.splits.at("train")) sum += motion.dofs.row(f).transpose();
    sum /= double(info.splits.at("train").size());
    for (int dof : param.free_dofs) mean_dofs[dof] = sum[dof];
  }
  const Vertices mean_keypoints = pose_character(ch, mean_dofs).body25;

  // Ground truth, and the floor: the mean pose given the true root rotation, placed like
  // PoseNet's (the translation from the frame's detections).
  Mean mean_kp, mean_joint_aligned;
  std::map<int, Vertices> gt_keypoints, gt_cloth, gt_body;
  Mean skinned_cloth_err;  // the template skinned by the true pose against the simulated garment
  Mean template_cloth_err;  // the template skinned by the predicted pose (PADefNet off)
  std::map<int, Eigen::Vector3d> gt_pivot;
  std::map<int, Eigen::Matrix3d> gt_rotation;
  const Eigen::Matrix3d rest_rotation = forward_kinematics(ch.skeleton, ch.rest_dofs)[param.pivot_joint].linear();
  for (int f : frames) {
    WEFT_CHECK(f < motion.num_frames(), gt_dir.string(), "/pose.motion: no frame ", f);
    const PosedCharacter posed = pose_character(ch, motion.dofs.row(f).transpose());
    gt_keypoints[f] = posed.body25;
    gt_pivot[f] = posed.joints[param.pivot_joint].translation();
    gt_rotation[f] = posed.joints[param.pivot_joint].linear() * rest_rotation.transpose();
    gt_body[f] = read_ply((gt_dir / fmt::format("body_{:04d}.ply", f)).string()).V;
    if (ch.has_cloth()) {
      gt_cloth[f] = read_ply((gt_dir / fmt::format("cloth_{:04d}.ply", f)).string()).V;
      skinned_cloth_err.add(mean_distance(posed.cloth, gt_cloth[f]) * ch.metres_per_unit * 1e3);
    }
    Vertices oriented = (mean_keypoints.rowwise() - param.pivot.transpose()) * gt_rotation[f].transpose();
    for (int m = 0; m < kBody25Count; ++m) {
      if (!oriented.row(m).allFinite()) {
        oriented.row(m).setZero();
        continue;
      }
      if (model.keypoint_mask()[m] > 0)
        mean_joint_aligned.add((oriented.row(m).transpose() - (posed.body25.row(m).transpose() - gt_pivot[f])).norm() *
                               mpu * 1e3);
    }
    std::vector<std::vector<KeypointView>> kv(1);
    for (int w = 0; w < V; ++w) kv[0].push_back({sup.camera(f, w), sup.detections(f, w)});
    const RootTranslationTerms terms = root_translation_terms(kv, model.keypoint_mask(), DType::F64);
    std::vector<double> flat(oriented.data(), oriented.data() + oriented.size());
    const Tensor t_mean = solve_root_translation(terms, Tensor::from_data({1, kBody25Count, 3}, flat, DType::F64));
    for (int m = 0; m < kBody25Count; ++m)
      for (int a = 0; a < 3; ++a) flat[3 * m + a] += t_mean.data<double>()[a];
    LandmarkStatistics mean_stats;
    multiview_landmark_loss(Tensor::from_data({1, kBody25Count, 3}, flat, DType::F32), {f}, sup, model.keypoint_mask(),
                            &mean_stats);
    mean_kp.add(mean_stats.mean_error_px, mean_stats.detections);
  }

  physics::SimulatorFactory simulator;
  if (ch.has_cloth() && !cfg.physics.synth_config.empty())
    simulator = garment_simulator_factory(ch, load_synth_config(cfg.physics.synth_config).simulation, info.fps);
  const std::vector<int> pins = ch.has_cloth() ? garment_pin_vertices(ch) : std::vector<int>{};

  SplitEvaluation e;
  e.split = split;
  e.frames = int(frames.size());
  e.views = V;
  Mean rotation_err, kp, joint, joint_aligned, iou, tmpl_iou, cloth_err, body_err, pen, inside, oob,
      oob_rel;
  for (int v = 0; v < V; ++v) {
    std::map<int, physics::Positions> cloth_seq;
    std::map<int, Eigen::MatrixX3d> body_seq;
    for (size_t first = 0; first < frames.size(); first += 8) {
      std::vector<Sample> samples(std::min<size_t>(8, frames.size() - first));
      tbb::parallel_for(size_t(0), samples.size(),
                        [&](size_t i) { samples[i] = ds.load(frames[first + i], info.views[v]); });
      const Batch batch = make_batch(samples);
      NoGradGuard no_grad;
      // One pass of each network: the prediction, and the same pose with PADefNet off.
      const SampleViews views = batch_views(batch, sup, model);
      nets.pose_net->eval();
      nets.deformation_net->eval();
      const Tensor pose_out = nets.pose_net->forward(batch.images);
      const CapturePrediction p = model.predict(pose_out, nets.deformation_net->forward(batch.images), views);
      const CapturePrediction t = model.predict(pose_out, Tensor(), views);
      LandmarkStatistics stats;
      multiview_landmark_loss(p.keypoints, batch.frames, sup, model.keypoint_mask(), &stats);
      kp.add(stats.mean_error_px, stats.detections);
      for (int b = 0; b < batch.size(); ++b) {
        const int f = batch.frames[b];
        ++e.predictions;
        const Vertices K = sample_vertices(p.keypoints, b);
        const Eigen::RowVector3d t_pred(p.translation.data<float>()[3 * b], p.translation.data<float>()[3 * b + 1],
                                        p.translation.data<float>()[3 * b + 2]);
        const Vertices& G = gt_keypoints[f];
        Eigen::Matrix3d R_pred;
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) R_pred(r, c) = p.rotation.data<float>()[9 * b + 3 * r + c];
        const Eigen::Matrix3d& R_gt = gt_rotation[f];
        rotation_err.add(Eigen::AngleAxisd(R_pred.transpose() * R_gt).angle() * 180 / M_PI);
        for (int m = 0; m < kBody25Count; ++m) {
          if (model.keypoint_mask()[m] <= 0 || !G.row(m).allFinite()) continue;
          joint.add((K.row(m) - G.row(m)).norm() * mpu * 1e3);
          // Root-relative (the pivot joint at the origin, rotations kept): how the root
          // rotation and the articulation split a pose is not unique (hips and spine can
          // turn the body too), the posed skeleton is.
          const Eigen::Vector3d g_rel = G.row(m).transpose() - gt_pivot[f];
          joint_aligned.add(((K.row(m) - t_pred).transpose() - g_rel).norm() * mpu * 1e3);
        }
        const Vertices body = sample_vertices(p.body, b), body_t = sample_vertices(t.body, b);
        body_err.add(mean_distance(body, gt_body[f]) * mpu * 1e3);
        Vertices cloth, cloth_t;
        if (p.cloth.defined()) {
          cloth = sample_vertices(p.cloth, b), cloth_t = sample_vertices(t.cloth, b);
          cloth_err.add(mean_distance(cloth, gt_cloth[f]) * mpu * 1e3);
          template_cloth_err.add(mean_distance(cloth_t, gt_cloth[f]) * mpu * 1e3);
        }
        std::vector<double> ious(V), tmpl(V);
        tbb::parallel_for(0, V, [&](int w) {
          const Camera& cam = sup.silhouette_camera(f, w);
          ious[w] = rendered_silhouette_iou(cam, ch, body, p.cloth.defined() ? &cloth : nullptr, sup.mask(f, w));
          tmpl[w] = rendered_silhouette_iou(cam, ch, body_t, p.cloth.defined() ? &cloth_t : nullptr, sup.mask(f, w));
        });
        for (int w = 0; w < V; ++w) iou.add(ious[w]), tmpl_iou.add(tmpl[w]);
        if (p.cloth.defined()) {
          cloth_seq[f] = to_positions(cloth, mpu);
          body_seq[f] = Eigen::MatrixX3d(body * mpu);
          const Penetration in = body_penetration(body_obstacle(ch, body_seq[f]), cloth_seq[f]);
          pen.sum += in.depth_sum * 1e3, pen.n += in.vertices_inside;
          inside.sum += in.vertices_inside, inside.n += cloth.rows();
          e.penetration_max_mm = std::max(e.penetration_max_mm, in.max_depth * 1e3);
        }
      }
    }
    // Out-of-balance force of each three consecutive frames of this input view.
    if (!simulator) continue;
    for (int f : frames) {
      if (!cloth_seq.count(f - 1) || !cloth_seq.count(f - 2) || !same_segment(info, f - 2, f)) continue;
      auto sim = simulator();
      sim->body(0).set_vertices(body_seq[f - 1]);
      sim->body(0).set_vertices(body_seq[f]);
      std::vector<physics::Vec3> targets;
      for (int a : pins) targets.push_back(cloth_seq[f].segment<3>(3 * a));
      sim->set_pins(pins, targets);
      // Over the vertices the attachment does not hold: pinned where they are predicted, the
      // anchors would show the weight of the garment hanging from them as imbalance (the
      // body's holding force is not part of the garment model).
      physics::FrameMetrics m;
      physics::measure_out_of_balance(*sim, cloth_seq[f - 2], cloth_seq[f - 1], cloth_seq[f], 1.0 / info.fps, m, pins);
      const int n = int(cloth_seq[f].size() / 3) - int(pins.size());
      oob.add(m.oob_force_mean, n);
      oob_rel.add(m.oob_force_mean_rel, n);
      e.oob_force_max_n = std::max(e.oob_force_max_n, m.oob_force_max);
      e.oob_force_max_rel = std::max(e.oob_force_max_rel, m.oob_force_max_rel);
      ++e.oob_frames;
    }
  }
  e.keypoint_error_px = kp.value();
  e.mean_pose_keypoint_error_px = mean_kp.value();
  e.joint_error_mm = joint.value(-1);
  e.joint_error_root_relative_mm = joint_aligned.value(-1);
  e.root_rotation_error_deg = rotation_err.value(-1);
  e.mean_pose_joint_error_root_relative_mm = mean_joint_aligned.value(-1);
  e.silhouette_iou = iou.value();
  e.template_silhouette_iou = tmpl_iou.value();
  e.cloth_error_mm = cloth_err.value(-1);
  e.skinned_true_pose_cloth_error_mm = skinned_cloth_err.value(-1);
  e.template_cloth_error_mm = template_cloth_err.value(-1);
  e.body_error_mm = body_err.value(-1);
  e.penetration_mean_mm = pen.value();
  e.penetrating_fraction = inside.value();
  e.oob_force_mean_n = oob.value();
  e.oob_force_mean_rel = oob_rel.value();
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

}  // namespace weft::capture
