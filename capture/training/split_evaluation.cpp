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

}  // namespace

nlohmann::json distribution_json(const Distribution& d) {
  return {{"mean", d.mean}, {"p95", d.p95}, {"p99", d.p99}, {"max", d.max}, {"count", d.count}};
}

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
  j["seconds"] = seconds;
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (const SplitFrameEvaluation& f : per_frame)
    rows.push_back({{"frame", f.frame},
                    {"view", f.view},
                    {"joint_error_mm", f.joint_error_mm},
                    {"root_rotation_error_deg", f.root_rotation_error_deg},
                    {"cloth_error_mm", f.cloth_error_mm},
                    {"chamfer_mm", f.chamfer_mm},
                    {"body_error_mm", f.body_error_mm},
                    {"iou", f.iou},
                    {"penetration_mean_all_mm", f.penetration_mean_all_mm},
                    {"penetrating_fraction", f.penetrating_fraction},
                    {"oob_mean_n", f.oob_mean_n},
                    {"oob_p95_n", f.oob_p95_n},
                    {"oob_max_n", f.oob_max_n},
                    {"oob_mean_rel", f.oob_mean_rel},
                    {"oob_outside_mean_n", f.oob_outside_mean_n},
                    {"inertia_mean_n", f.inertia_mean_n},
                    {"elastic_mean_n", f.elastic_mean_n},
                    {"collision_mean_n", f.collision_mean_n},
                    {"friction_mean_n", f.friction_mean_n}});
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

  // The garment's simulation as the dataset was made (dataset.yaml; none: not measured).
  const std::optional<SynthSimulationConfig> dataset_simulation =
      ch.has_cloth() ? find_dataset_simulation(data) : std::nullopt;
  const bool measure_balance = dataset_simulation.has_value();
  const SynthSimulationConfig simulation = dataset_simulation.value_or(SynthSimulationConfig{});

  SplitEvaluation e;
  e.split = split;
  e.oracle_pose = cfg.oracle_pose;
  e.frames = int(frames.size());
  e.views = V;
  std::vector<double> rotation_errors;
  MeasuredMean rotation_err, kp, joint, joint_aligned, iou, tmpl_iou, cloth_err, chamfer, body_err, pen, pen_all, inside;
  MeasuredMean inertia, elastic, collision, friction;
  std::vector<double> oob_values, oob_rel_values, oob_outside_values;
  double pen_max = 0;
  for (int v = 0; v < V; ++v) {
    std::map<int, Vertices> cloth_seq, body_seq;
    std::map<int, size_t> row_of;  // frame → its row of e.per_frame for this view
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
          for (int64_t k = 0; k < motion.dofs.cols(); ++k) d.push_back(motion.dofs(f, k));
        const Tensor dofs = Tensor::from_data({int64_t(batch.frames.size()), motion.dofs.cols()}, d, DType::F32);
        p = model.predict_posed(dofs, deformation);
        t = model.predict_posed(dofs, Tensor());
      } else {
        const SampleViews views = batch_views(batch, sup, model);
        const Tensor pose_out = nets.pose_net->forward(batch.images);
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
        const Vertices K = sample_vertices(p.keypoints, b);
        const Eigen::RowVector3d t_pred(p.translation.data<float>()[3 * b], p.translation.data<float>()[3 * b + 1],
                                        p.translation.data<float>()[3 * b + 2]);
        const Vertices& G = gt_keypoints[f];
        if (!cfg.oracle_pose) {
          Eigen::Matrix3d R_pred;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) R_pred(r, c) = p.rotation.data<float>()[9 * b + 3 * r + c];
          fe.root_rotation_error_deg = rotation_error_deg(R_pred, gt_rotation[f]);
          rotation_err.add(fe.root_rotation_error_deg);
          rotation_errors.push_back(fe.root_rotation_error_deg);
        }
        MeasuredMean frame_joint;
        for (int m = 0; m < kBody25Count; ++m) {
          if (model.keypoint_mask()[m] <= 0 || !G.row(m).allFinite()) continue;
          joint.add((K.row(m) - G.row(m)).norm() * mpu * 1e3);
          frame_joint.add((K.row(m) - G.row(m)).norm() * mpu * 1e3);
          // Root-relative (the pivot joint at the origin, rotations kept): how the root
          // rotation and the articulation split a pose is not unique (hips and spine can
          // turn the body too), the posed skeleton is.
          const Eigen::Vector3d g_rel = G.row(m).transpose() - gt_pivot[f];
          const Eigen::RowVector3d pivot = cfg.oracle_pose ? Eigen::RowVector3d(gt_pivot[f].transpose()) : t_pred;
          joint_aligned.add(((K.row(m) - pivot).transpose() - g_rel).norm() * mpu * 1e3);
        }
        fe.joint_error_mm = frame_joint.value();
        const Vertices body = sample_vertices(p.body, b), body_t = sample_vertices(t.body, b);
        fe.body_error_mm = mean_distance(body, gt_body[f]) * mpu * 1e3;
        body_err.add(fe.body_error_mm);
        Vertices cloth, cloth_t;
        if (p.cloth.defined()) {
          cloth = sample_vertices(p.cloth, b), cloth_t = sample_vertices(t.cloth, b);
          fe.cloth_error_mm = mean_distance(cloth, gt_cloth[f]) * mpu * 1e3;
          fe.chamfer_mm = chamfer_distance_mm(cloth, gt_cloth[f], ch.cloth->mesh.F, mpu);
          cloth_err.add(fe.cloth_error_mm);
          chamfer.add(fe.chamfer_mm);
          template_cloth_err.add(mean_distance(cloth_t, gt_cloth[f]) * mpu * 1e3);
        }
        const TriangleMesh* cloth_mesh = p.cloth.defined() ? &ch.cloth->mesh : nullptr;
        std::vector<double> ious(V), tmpl(V);
        tbb::parallel_for(0, V, [&](int w) {
          const Camera& cam = sup.silhouette_camera(f, w);
          ious[w] = rendered_silhouette_iou(cam, ch.body.mesh, body, cloth_mesh, cloth_mesh ? &cloth : nullptr,
                                            sup.mask(f, w));
          tmpl[w] = rendered_silhouette_iou(cam, ch.body.mesh, body_t, cloth_mesh, cloth_mesh ? &cloth_t : nullptr,
                                            sup.mask(f, w));
        });
        MeasuredMean frame_iou;
        for (int w = 0; w < V; ++w) iou.add(ious[w]), tmpl_iou.add(tmpl[w]), frame_iou.add(ious[w]);
        fe.iou = frame_iou.value();
        if (p.cloth.defined()) {
          cloth_seq[f] = cloth;
          body_seq[f] = body;
          const Penetration in = cloth_penetration(ch, body, cloth);
          pen.sum += in.depth_sum * 1e3, pen.n += in.vertices_inside;
          pen_all.sum += in.depth_sum * 1e3, pen_all.n += cloth.rows();
          inside.sum += in.vertices_inside, inside.n += cloth.rows();
          pen_max = std::max(pen_max, in.max_depth * 1e3);
          fe.penetration_mean_all_mm = in.depth_sum * 1e3 / cloth.rows();
          fe.penetrating_fraction = double(in.vertices_inside) / cloth.rows();
        }
        row_of[f] = e.per_frame.size();
        e.per_frame.push_back(fe);
      }
    }
    // Out-of-balance force of each three consecutive frames of this input view.
    if (!measure_balance) continue;
    for (int f : frames) {
      if (!cloth_seq.count(f - 1) || !cloth_seq.count(f - 2) || !same_segment(info, f - 2, f)) continue;
      const ClothBalance cb = cloth_out_of_balance(ch, simulation, info.fps, body_seq[f - 1], body_seq[f],
                                                   cloth_seq[f - 2], cloth_seq[f - 1], cloth_seq[f]);
      const std::vector<double> depth = cloth_signed_distances_mm(ch, body_seq[f], cloth_seq[f]);
      const physics::VertexBalance& vb = cb.vertices;
      std::vector<double> residual, outside;
      MeasuredMean in_f, el_f, co_f, fr_f, rel_f;
      for (int i : cb.free_vertices) {
        residual.push_back(vb.residual[i]);
        oob_values.push_back(vb.residual[i]);
        oob_rel_values.push_back(vb.residual[i] / vb.weight[i]);
        rel_f.add(vb.residual[i] / vb.weight[i]);
        if (depth[i] >= 0) outside.push_back(vb.residual[i]), oob_outside_values.push_back(vb.residual[i]);
        in_f.add(vb.inertia[i]), el_f.add(vb.elastic[i]), co_f.add(vb.collision[i]), fr_f.add(vb.friction[i]);
        inertia.add(vb.inertia[i]), elastic.add(vb.elastic[i]), collision.add(vb.collision[i]),
            friction.add(vb.friction[i]);
      }
      SplitFrameEvaluation& fe = e.per_frame[row_of.at(f)];
      const Distribution d = distribution(residual);
      fe.oob_mean_n = d.mean, fe.oob_p95_n = d.p95, fe.oob_max_n = d.max, fe.oob_mean_rel = rel_f.value();
      fe.oob_outside_mean_n = distribution(outside).mean;
      fe.inertia_mean_n = in_f.value(), fe.elastic_mean_n = el_f.value(), fe.collision_mean_n = co_f.value(),
      fe.friction_mean_n = fr_f.value();
      ++e.oob_frames;
    }
  }
  e.keypoint_error_px = kp.value();
  e.mean_pose_keypoint_error_px = mean_kp.value();
  e.joint_error_mm = joint.value();
  e.joint_error_root_relative_mm = joint_aligned.value();
  e.root_rotation_error_deg = rotation_err.value();
  const RotationErrorSummary rotation = summarize_rotation_errors(rotation_errors);
  e.root_rotation_median_deg = rotation.median_deg, e.root_rotation_p95_deg = rotation.p95_deg,
  e.root_rotation_above_45 = rotation.above_45;
  e.mean_pose_joint_error_root_relative_mm = mean_joint_aligned.value();
  e.silhouette_iou = iou.value();
  e.template_silhouette_iou = tmpl_iou.value();
  e.cloth_error_mm = cloth_err.value();
  e.chamfer_mm = chamfer.value();
  e.skinned_true_pose_cloth_error_mm = skinned_cloth_err.value();
  e.template_cloth_error_mm = template_cloth_err.value();
  e.body_error_mm = body_err.value();
  if (ch.has_cloth()) {
    e.penetration_mean_mm = pen.n ? pen.value() : 0.0;  // no vertex inside: depth 0
    e.penetration_mean_all_mm = pen_all.value();
    e.penetration_max_mm = pen_max;
    e.penetrating_fraction = inside.value();
  }
  e.oob_n = distribution(oob_values);
  e.oob_rel = distribution(oob_rel_values);
  e.oob_outside_n = distribution(oob_outside_values);
  e.inertia_mean_n = inertia.value();
  e.elastic_mean_n = elastic.value();
  e.collision_mean_n = collision.value();
  e.friction_mean_n = friction.value();
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

}  // namespace weft::capture
