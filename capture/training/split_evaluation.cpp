#include "capture/training/split_evaluation.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>

#include "capture/character/skeletool_io.h"
#include "geometry/mesh_io.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "capture/evaluation/frame_measures.h"
#include "capture/model/capture_networks.h"
#include "capture/model/model_folder.h"
#include "capture/render/silhouette_iou.h"
#include "capture/training/multiview_losses.h"
#include "capture/training/pose_noise.h"
#include "capture/training/training_config.h"
#include "graph/autograd.h"
#include "graph/error.h"
#include "nn/checkpoint.h"
#include "nn/safetensors.h"
#include "physics/cloth_metrics.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

// Mean distance (character units) between corresponding rows.
double mean_distance(const Vertices& a, const Vertices& b) { return (a - b).rowwise().norm().mean(); }

// PoseNet's error per regressed dof of every prediction, and which prediction precedes
// which in the same view: the mean, the RMS and the spread about the mean per dof, and the
// lag-1 autocorrelation of the error about its mean, pooled over dofs:
// Σ c(f)·c(f−1) / Σ (c(f)² + c(f−1)²)/2, c = e − mean.
struct DofErrorPool {
  std::vector<Eigen::VectorXd> errors;
  std::vector<std::pair<size_t, size_t>> pairs;  // (prediction, its predecessor)
  // Adds a prediction's error; previous: its predecessor's index in the same view, or -1.
  size_t add(const Eigen::VectorXd& e, long previous) {
    errors.push_back(e);
    if (previous >= 0) pairs.emplace_back(errors.size() - 1, size_t(previous));
    return errors.size() - 1;
  }
  // The statistics into e (names: the dofs' names in the errors' order); nothing when empty.
  void summarise(const std::vector<std::string>& names, SplitEvaluation& e) const {
    if (errors.empty()) return;
    const double n = double(errors.size());
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(Eigen::Index(names.size())), sq = sum;
    for (const Eigen::VectorXd& x : errors) sum += x, sq += x.cwiseAbs2();
    const Eigen::VectorXd mean = sum / n;
    for (size_t i = 0; i < names.size(); ++i)
      e.dof_errors.push_back(
          {names[i], std::sqrt(sq[i] / n), mean[i], std::sqrt(std::max(0.0, sq[i] / n - mean[i] * mean[i]))});
    double product = 0, norm = 0;
    for (const auto& [a, b] : pairs) {
      const Eigen::VectorXd ca = errors[a] - mean, cb = errors[b] - mean;
      product += ca.dot(cb), norm += 0.5 * (ca.squaredNorm() + cb.squaredNorm());
    }
    if (!(norm > 0)) return;
    e.dof_error_lag1 = product / norm;
    e.dof_error_correlation_frames = e.dof_error_lag1 >= 1 ? kNotMeasured
                                     : e.dof_error_lag1 > 0 ? -1.0 / std::log(e.dof_error_lag1)
                                                            : 0.0;
  }
};

nlohmann::json distribution_json(const Distribution& d) {
  return {{"mean", d.mean}, {"p95", d.p95}, {"p99", d.p99}, {"max", d.max}, {"count", d.count}};
}

}  // namespace

std::string SplitEvaluation::to_json() const {
  nlohmann::ordered_json j;  // NaN (not measured) is written as null
  j["split"] = split;
  j["oracle_pose"] = oracle_pose;
  j["frames"] = frames;
  j["views"] = views;
  j["predictions"] = predictions;
  j["keypoint_error_px"] = keypoint_error_px;
  j["mean_pose_keypoint_error_px"] = mean_pose_keypoint_error_px;
  j["joint_error_mm"] = joint_error_mm;
  j["joint_error_root_relative_mm"] = joint_error_root_relative_mm;
  j["root_rotation_error_deg"] = root_rotation_error_deg;
  j["root_rotation_median_deg"] = root_rotation_median_deg;
  j["root_rotation_p95_deg"] = root_rotation_p95_deg;
  j["root_rotation_above_45"] = root_rotation_above_45;
  j["root_heading_median_deg"] = root_heading_median_deg;
  j["root_heading_above_45"] = root_heading_above_45;
  j["mean_pose_joint_error_root_relative_mm"] = mean_pose_joint_error_root_relative_mm;
  j["silhouette_iou"] = silhouette_iou;
  j["template_silhouette_iou"] = template_silhouette_iou;
  j["cloth_error_mm"] = cloth_error_mm;
  j["chamfer_mm"] = chamfer_mm;
  j["template_cloth_error_mm"] = template_cloth_error_mm;
  j["skinned_true_pose_cloth_error_mm"] = skinned_true_pose_cloth_error_mm;
  j["body_error_mm"] = body_error_mm;
  j["penetration_mean_mm"] = penetration_mean_mm;
  j["penetration_mean_all_mm"] = penetration_mean_all_mm;
  j["penetration_max_mm"] = penetration_max_mm;
  j["penetrating_fraction"] = penetrating_fraction;
  j["oob_frames"] = oob_frames;
  j["oob_force_n"] = distribution_json(oob_n);
  j["oob_force_rel"] = distribution_json(oob_rel);
  j["oob_force_outside_n"] = distribution_json(oob_outside_n);
  j["oob_terms_mean_n"] = {{"inertia", inertia_mean_n},
                           {"elastic", elastic_mean_n},
                           {"collision", collision_mean_n},
                           {"friction", friction_mean_n}};
  nlohmann::ordered_json dofs = nlohmann::ordered_json::object();
  for (const DofError& d : dof_errors) dofs[d.name] = {{"rms", d.rms}, {"mean", d.mean}, {"std", d.std}};
  j["dof_errors"] = dofs;
  j["dof_error_lag1"] = dof_error_lag1;
  j["dof_error_correlation_frames"] = dof_error_correlation_frames;
  j["seconds"] = seconds;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const SplitFrameEvaluation& f : per_frame) {
    nlohmann::ordered_json row = {{"frame", f.frame}, {"view", f.view}};
    for (const FrameMetric& m : frame_metrics()) row[m.name] = f.measures.*m.value;
    rows.push_back(row);
  }
  j["per_frame"] = rows;
  return j.dump(2) + "\n";
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
  const Motion oracle = cfg.oracle_pose_noise.enabled() ? perturbed_motion(motion, ch.skeleton, cfg.oracle_pose_noise)
                                                        : motion;
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
  MeasuredMean mean_kp, mean_joint_aligned;
  std::map<int, Vertices> gt_keypoints, gt_cloth, gt_body;
  MeasuredMean skinned_cloth_err;  // the template skinned by the true pose against the simulated garment
  MeasuredMean template_cloth_err;  // the template skinned by the predicted pose (PADefNet off)
  std::map<int, Eigen::Vector3d> gt_pivot;
  std::map<int, Eigen::Matrix3d> gt_rotation;
  for (int f : frames) {
    WEFT_CHECK(f < motion.num_frames(), gt_dir.string(), "/pose.motion: no frame ", f);
    const PosedCharacter posed = pose_character(ch, motion.dofs.row(f).transpose());
    gt_keypoints[f] = posed.body25;
    gt_pivot[f] = posed.joints[param.pivot_joint].translation();
    gt_rotation[f] = root_rotation_world(ch, param, posed);
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

  // The garment's simulation as the dataset was made (dataset.yaml; none: not measured).
  const std::optional<SynthSimulationConfig> dataset_simulation =
      ch.has_cloth() ? find_dataset_simulation(data) : std::nullopt;
  const bool with_balance = dataset_simulation.has_value();
  const SynthSimulationConfig simulation = dataset_simulation.value_or(SynthSimulationConfig{});

  SplitEvaluation e;
  e.split = split;
  e.oracle_pose = cfg.oracle_pose;
  e.frames = int(frames.size());
  e.views = V;
  std::vector<double> rotation_errors, heading_errors;
  FrameMetricMeans means;
  MeasuredMean kp, iou, tmpl_iou;
  BalancePool balance;
  DofErrorPool dof_err;
  FrameMeasures penetration;  // sums over predictions (depth, vertices inside), and the max
  penetration.penetration_max_mm = 0;
  for (int v = 0; v < V; ++v) {
    std::map<int, Vertices> cloth_seq, body_seq;
    std::map<int, size_t> row_of;  // frame → its row of e.per_frame for this view
    std::map<int, size_t> view_err;  // frame → its PoseNet error in dof_err, this view
    for (size_t first = 0; first < frames.size(); first += 8) {
      std::vector<Sample> samples(std::min<size_t>(8, frames.size() - first));
      tbb::parallel_for(size_t(0), samples.size(),
                        [&](size_t i) { samples[i] = ds.load(frames[first + i], info.views[v]); });
      const Batch batch = make_batch(samples);
      NoGradGuard no_grad;
      // One pass of each network: the prediction, and the same pose with PADefNet off.
      nets.pose_net->eval();
      nets.deformation_net->eval();
      const Tensor deformation = nets.deformation_net->forward(batch.images);
      CapturePrediction p, t;
      if (cfg.oracle_pose) {
        std::vector<double> d;
        for (int f : batch.frames)
          for (int64_t k = 0; k < oracle.dofs.cols(); ++k) d.push_back(oracle.dofs(f, k));
        const Tensor dofs = Tensor::from_data({int64_t(batch.frames.size()), oracle.dofs.cols()}, d, DType::F32);
        p = model.predict_posed(dofs, deformation);
        t = model.predict_posed(dofs, Tensor());
      } else {
        const SampleViews views = batch_views(batch, sup, model);
        const Tensor pose_out = nets.pose(batch);
        p = model.predict(pose_out, deformation, views);
        t = model.predict(pose_out, Tensor(), views);
      }
      LandmarkStatistics stats;
      multiview_landmark_loss(p.keypoints, batch.frames, sup, model.keypoint_mask(), &stats);
      kp.add(stats.mean_error_px, stats.detections);
      for (int b = 0; b < batch.size(); ++b) {
        const int f = batch.frames[b];
        ++e.predictions;
        SplitFrameEvaluation fe;
        fe.frame = f;
        fe.view = v;
        // The prediction and its ground truth; the keypoints the model does not fit are
        // not measured. The predicted pivot is the predicted translation (the truth's with
        // the oracle pose, whose root rotation is then not measured).
        PosedFrame predicted, truth;
        predicted.body = sample_vertices(p.body, b);
        if (p.cloth.defined()) predicted.cloth = sample_vertices(p.cloth, b);
        predicted.body25 = sample_vertices(p.keypoints, b);
        for (int m = 0; m < kBody25Count; ++m)
          if (model.keypoint_mask()[m] <= 0) predicted.body25.row(m).setConstant(kNotMeasured);
        truth.body = gt_body[f], truth.body25 = gt_keypoints[f], truth.pivot = gt_pivot[f];
        if (ch.has_cloth()) truth.cloth = gt_cloth[f];
        if (cfg.oracle_pose) {
          predicted.pivot = gt_pivot[f];
        } else {
          for (int a = 0; a < 3; ++a) predicted.pivot[a] = p.translation.data<float>()[3 * b + a];
          Eigen::Matrix3d R_pred;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) R_pred(r, c) = p.rotation.data<float>()[9 * b + 3 * r + c];
          predicted.root_rotation = R_pred;
          truth.root_rotation = gt_rotation[f];
        }
        if (!cfg.oracle_pose) {
          Eigen::VectorXd err(param.free_dofs.size());
          for (size_t i = 0; i < param.free_dofs.size(); ++i) {
            const int d = param.free_dofs[i];
            err[i] = p.dofs.data<float>()[b * p.dofs.size(1) + d] - motion.dofs(f, d);
          }
          view_err[f] = dof_err.add(err, view_err.count(f - 1) && same_segment(info, f - 1, f) ? long(view_err[f - 1]) : -1);
        }
        FrameMeasures& fm = fe.measures;
        measure_geometry(ch, predicted, truth, true, fm);
        fm.body_distances_mm.clear(), fm.cloth_distances_mm.clear();  // not pooled here
        if (std::isfinite(fm.root_rotation_error_deg)) rotation_errors.push_back(fm.root_rotation_error_deg);
        if (std::isfinite(fm.root_heading_error_deg)) heading_errors.push_back(fm.root_heading_error_deg);
        const Vertices body_t = sample_vertices(t.body, b);
        Vertices cloth_t;
        if (p.cloth.defined()) {
          cloth_t = sample_vertices(t.cloth, b);
          template_cloth_err.add(mean_distance(cloth_t, gt_cloth[f]) * mpu * 1e3);
        }
        const TriangleMesh* cloth_mesh = p.cloth.defined() ? &ch.cloth->mesh : nullptr;
        std::vector<double> ious(V), tmpl(V);
        tbb::parallel_for(0, V, [&](int w) {
          const Camera& cam = sup.silhouette_camera(f, w);
          ious[w] = rendered_silhouette_iou(cam, ch.body.mesh, predicted.body, cloth_mesh,
                                            cloth_mesh ? &predicted.cloth : nullptr, sup.mask(f, w));
          tmpl[w] = rendered_silhouette_iou(cam, ch.body.mesh, body_t, cloth_mesh, cloth_mesh ? &cloth_t : nullptr,
                                            sup.mask(f, w));
        });
        measure_ious(ious, v, fm);
        for (int w = 0; w < V; ++w) iou.add(ious[w]), tmpl_iou.add(tmpl[w]);
        if (p.cloth.defined()) {
          cloth_seq[f] = predicted.cloth;
          body_seq[f] = predicted.body;
          penetration.penetration_depth_sum_mm += fm.penetration_depth_sum_mm;
          penetration.penetrating_vertices += fm.penetrating_vertices, penetration.cloth_vertices += fm.cloth_vertices;
          penetration.penetration_max_mm = std::max(penetration.penetration_max_mm, fm.penetration_max_mm);
        }
        row_of[f] = e.per_frame.size();
        e.per_frame.push_back(fe);
      }
    }
    // Out-of-balance force of each three consecutive frames of this input view.
    if (!with_balance) continue;
    for (int f : frames) {
      if (!cloth_seq.count(f - 1) || !cloth_seq.count(f - 2) || !same_segment(info, f - 2, f)) continue;
      measure_balance(ch, simulation, info.fps, body_seq[f - 1], body_seq[f], cloth_seq[f - 2], cloth_seq[f - 1],
                      cloth_seq[f], e.per_frame[row_of.at(f)].measures, &balance);
    }
  }
  for (const SplitFrameEvaluation& fe : e.per_frame) means.add(fe.measures);
  e.oob_frames = balance.frames;
  e.keypoint_error_px = kp.value();
  e.mean_pose_keypoint_error_px = mean_kp.value();
  e.joint_error_mm = means.mean("mpjpe_mm");
  e.joint_error_root_relative_mm = means.mean("mpjpe_root_relative_mm");
  e.root_rotation_error_deg = means.mean("root_rotation_error_deg");
  const RotationErrorSummary rotation = summarize_rotation_errors(rotation_errors);
  e.root_rotation_median_deg = rotation.median_deg, e.root_rotation_p95_deg = rotation.p95_deg,
  e.root_rotation_above_45 = rotation.above_45;
  const RotationErrorSummary heading = summarize_rotation_errors(heading_errors);
  e.root_heading_median_deg = heading.median_deg, e.root_heading_above_45 = heading.above_45;
  e.mean_pose_joint_error_root_relative_mm = mean_joint_aligned.value();
  e.silhouette_iou = iou.value();
  e.template_silhouette_iou = tmpl_iou.value();
  e.cloth_error_mm = means.mean("cloth_error_mean_mm");
  e.chamfer_mm = means.mean("cloth_chamfer_mm");
  e.skinned_true_pose_cloth_error_mm = skinned_cloth_err.value();
  e.template_cloth_error_mm = template_cloth_err.value();
  e.body_error_mm = means.mean("body_error_mean_mm");
  if (ch.has_cloth()) {
    const double n = double(penetration.cloth_vertices);
    e.penetration_mean_mm = penetration.penetrating_vertices
                                ? penetration.penetration_depth_sum_mm / double(penetration.penetrating_vertices)
                                : 0.0;  // no vertex inside: depth 0
    e.penetration_mean_all_mm = n > 0 ? penetration.penetration_depth_sum_mm / n : kNotMeasured;
    e.penetration_max_mm = penetration.penetration_max_mm;
    e.penetrating_fraction = n > 0 ? double(penetration.penetrating_vertices) / n : kNotMeasured;
  }
  e.oob_n = distribution(balance.n);
  e.oob_rel = distribution(balance.rel);
  e.oob_outside_n = distribution(balance.outside_n);
  e.inertia_mean_n = balance.inertia.value();
  e.elastic_mean_n = balance.elastic.value();
  e.collision_mean_n = balance.collision.value();
  e.friction_mean_n = balance.friction.value();
  std::vector<std::string> dof_names;
  for (int d : param.free_dofs) dof_names.push_back(ch.skeleton.dofs[d].name);
  dof_err.summarise(dof_names, e);
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

}  // namespace weft::capture
