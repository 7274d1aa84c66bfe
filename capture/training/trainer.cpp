#include "capture/training/trainer.h"

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <future>
#include <memory>
#include <sstream>

#include "capture/character/skeletool_io.h"
#include "capture/deformation/losses.h"
#include "capture/detection/detection_losses.h"
#include "capture/detection/person_detection.h"
#include "capture/evaluation/frame_measures.h"
#include "graph/atomic_file.h"
#include "capture/io/portable_random.h"
#include "files/text_reader.h"
#include "capture/garment/garment_simulator.h"
#include "capture/garment/garment_windows.h"
#include "capture/model/capture_networks.h"
#include "capture/training/loss_log.h"
#include "capture/model/model_folder.h"
#include "capture/render/silhouette_iou.h"
#include "capture/training/multiview_losses.h"
#include "capture/training/silhouette_rays.h"
#include "capture/training/simulation_loss.h"
#include "capture/training/virtual_poses.h"
#include "graph/autograd.h"
#include "graph/error.h"
#include "nn/checkpoint.h"
#include "nn/data_parallel.h"
#include "nn/optim.h"
#include "nn/schedule.h"
#include "ops/geometry.h"
#include "ops/ops.h"
#include "physics/newton_solver.h"
#include "physics/simulation_window.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Seconds per part of a step, summed over the steps of a stage.
struct PartTimes {
  std::map<std::string, double> seconds;
  int steps = 0;
  // Adds the time since `t` to `part` and restarts `t`.
  void lap(const char* part, Clock::time_point& t) {
    const auto now = Clock::now();
    seconds[part] += std::chrono::duration<double>(now - t).count();
    t = now;
  }
};

bool all_finite(const nn::Module& m) {
  for (const nn::NamedTensor& p : m.named_parameters()) {
    const float* d = p.tensor.data<float>();
    for (int64_t i = 0; i < p.tensor.numel(); ++i)
      if (!std::isfinite(d[i])) return false;
  }
  return true;
}

// The body and the cloth as one mesh (the silhouette is of both).
Faces combined_faces(const Character& ch) {
  const Faces& fb = ch.body.mesh.F;
  if (!ch.has_cloth()) return fb;
  const Faces& fc = ch.cloth->mesh.F;
  Faces f(fb.rows() + fc.rows(), 3);
  f << fb, (fc.array() + int(ch.body.mesh.num_vertices())).matrix();
  return f;
}

void append_windows(const fs::path& path, int64_t step, const std::vector<SimulationWindowRecord>& records) {
  const bool fresh = !fs::exists(path);
  std::ofstream out(path, std::ios::app);
  if (fresh)
    out << "step,window,frame,start_max_mm,start_inside,cleaned_inside,cleanup_iterations,status,newton_iterations,"
           "frames_kept,rays\n";
  for (size_t w = 0; w < records.size(); ++w) {
    const SimulationWindowRecord& r = records[w];
    out << step << ',' << w << ',' << r.frame << ',' << fmt::format("{:.3f}", r.start_max_mm) << ',' << r.start_inside
        << ',' << r.cleaned_inside << ',' << r.cleanup_iterations << ',' << r.status << ',' << r.newton_iterations
        << ',' << r.frames_kept << ',' << r.rays << '\n';
  }
}

class Trainer {
 public:
  Trainer(const TrainOptions& options, const TrainingConfig& config)
      : options_(options), cfg_(config), info_(read_dataset_info(options.data)),
        character_(load_character(info_.character)), model_(character_, cfg_.network),
        nets_(character_, cfg_.network, cfg_.seed), faces_(combined_faces(character_)),
        shards_(cfg_.shards > 0 ? cfg_.shards : group_.size()) {
    WEFT_CHECK(shards_ % group_.size() == 0, cfg_.file, ": shards: ", shards_, " cannot be spread evenly over the ",
               group_.size(), " ranks of this job (mpirun -np); use a multiple of the ranks, or 0 for one per rank");
    // The physics stage simulates the garment as the dataset was made: a dataset without
    // those settings is an error now, not when the stage starts.
    if (cfg_.stages[2].steps > 0) read_dataset_simulation(options.data);
    DatasetOptions d;
    d.input_size = cfg_.network.input_size;
    d.margin = cfg_.network.margin;
    d.split = "train";
    d.augmentation = cfg_.augmentation;
    train_ = std::make_unique<SyntheticDataset>(options.data, d);
    d.augmentation = AugmentationOptions();
    WEFT_CHECK(!train_->frames().empty(), options.data, "/dataset.yaml: the train split is empty");
    std::vector<int> frames = train_->frames();
    if (info_.splits.count("val") && !info_.splits.at("val").empty()) {
      d.split = "val";
      val_ = std::make_unique<SyntheticDataset>(options.data, d);
      frames.insert(frames.end(), val_->frames().begin(), val_->frames().end());
    }
    supervision_ = std::make_unique<MultiviewSupervision>(info_, frames, cfg_.silhouette_size);
    if (cfg_.stages[3].steps > 0) {  // the person detector's crops: its own size, margin and augmentation
      DatasetOptions dd;
      dd.input_size = cfg_.network.detector.input_size;
      dd.margin = cfg_.network.detector.margin;
      dd.split = "train";
      dd.augmentation = cfg_.detector_augmentation;
      detector_train_ = std::make_unique<SyntheticDataset>(options.data, dd);
    }
    if (cfg_.stages[0].steps > 0 && cfg_.stages[0].weights.virtual_landmarks > 0) {
      WEFT_CHECK(shards_ == 1, cfg_.file, ": virtual_poses: not available with data parallelism yet (", shards_,
                 " shards); train on one process, or set stages.pose.virtual_landmarks: 0");
      const auto t0 = Clock::now();
      virtual_ = std::make_unique<VirtualPoses>(character_, cfg_.virtual_poses, *supervision_, train_->frames(),
                                                cfg_.network.input_size, cfg_.network.margin, cfg_.augmentation);
      spdlog::info("virtual poses: {} poses from {} motion(s) at {} fps, retargeted in {:.1f} s; {} per step, {} "
                   "views each, {} detector model",
                   virtual_->poses(), cfg_.virtual_poses.motions.size(), cfg_.virtual_poses.fps, seconds_since(t0),
                   cfg_.virtual_poses.batch_size, cfg_.virtual_poses.views,
                   cfg_.virtual_poses.keypoints.model == KeypointErrorModel::openpose ? "openpose" : "gaussian");
    }
    bool with_3d = false;
    for (const StageConfig& s : cfg_.stages) with_3d |= s.steps > 0 && s.weights.keypoints_3d > 0;
    if (with_3d) triangulate_frames(frames);
    rest_body25_ = pose_character(character_, character_.rest_dofs).body25;
    body_arap_ = arap_terms(character_.body.graph, DType::F32);
    if (character_.has_cloth()) {
      cloth_arap_ = arap_terms(character_.cloth->graph, DType::F32);
      attachment_ = attachment_terms(character_.attachment, DType::F32);
    }
    const fs::path gt = fs::path(options.data) / "gt" / "pose.motion";
    if (fs::exists(gt)) {
      gt_motion_ = read_motion(gt.string(), int(character_.rest_dofs.size()));
      for (int f : frames)
        if (f < gt_motion_.num_frames()) {
          const PosedCharacter posed = pose_character(character_, gt_motion_.dofs.row(f).transpose());
          gt_keypoints_[f] = posed.body25;
          gt_roots_[f] = {posed.joints[model_.parametrisation().pivot_joint].translation(),
                          root_rotation_world(character_, model_.parametrisation(), posed)};
        }
    }
    if (cfg_.oracle_pose) {
      WEFT_CHECK(fs::exists(gt), cfg_.file, ": oracle_pose poses the character by the ground truth, but ", gt.string(),
                 " does not exist (a dataset of `weft synth` has it)");
      for (int f : frames)
        WEFT_CHECK(f < gt_motion_.num_frames(), gt.string(), ": ", gt_motion_.num_frames(),
                   " frames, but the dataset uses frame ", f, " (oracle_pose)");
      spdlog::info("oracle pose: the warm start, the physics stage and validation pose the character by {}",
                   gt.string());
      oracle_motion_ = gt_motion_;
      if (cfg_.oracle_pose_noise.enabled()) {
        const PoseNoiseConfig& n = cfg_.oracle_pose_noise;
        oracle_motion_ = perturbed_motion(gt_motion_, character_.skeleton, n);
        spdlog::info("oracle pose perturbed as PoseNet errs: {} dofs from {}, scale {}, correlation {} frames, seed {}",
                     n.spread.size(), n.file, n.scale, n.correlation_frames, n.seed);
      }
    }
    spdlog::info("data: {} ({} train frames, {} val, {} views, {}×{}); character {}: {} body + {} cloth vertices, "
                 "{} + {} graph nodes, {} regressed dofs",
                 options.data, train_->frames().size(), val_ ? val_->frames().size() : 0, info_.views.size(),
                 info_.image_width, info_.image_height, character_.name, character_.body.mesh.num_vertices(),
                 character_.has_cloth() ? character_.cloth->mesh.num_vertices() : 0, character_.body.graph.num_nodes(),
                 character_.has_cloth() ? character_.cloth->graph.num_nodes() : 0,
                 model_.parametrisation().free_dofs.size());
    spdlog::info("networks: 2 × {} at {}², {:.1f} M parameters", cfg_.network.backbone, cfg_.network.input_size,
                 nets_.num_parameters() / 1e6);
  }

  TrainSummary run(const std::function<void(const TrainProgress&)>& progress);
  ValidationReport validate(const SyntheticDataset& split, int samples);
  CaptureNetworks& networks() { return nets_; }

 private:
  struct StepResult {
    std::map<std::string, double> terms;
    int windows = 0, failures = 0;
    std::map<std::string, int> failure_statuses;  // the first failed step's status per failed window
    std::vector<SimulationWindowRecord> window_records;     // this process's windows
  };
  // Averages the gradients of what `opt` steps, and the batch-norm statistics of the
  // network the stage trains, over the shards of every batch and the ranks.
  std::unique_ptr<nn::DataParallel> make_data_parallel(const StageConfig& stage, const nn::Optimizer& opt) {
    const nn::Module& net = stage.kind == StageKind::pose       ? static_cast<const nn::Module&>(*nets_.pose_net)
                            : stage.kind == StageKind::detector ? static_cast<const nn::Module&>(*nets_.detector)
                                                                : static_cast<const nn::Module&>(*nets_.deformation_net);
    return std::make_unique<nn::DataParallel>(group_, opt.params(), net.named_buffers(), shards_);
  }
  std::unique_ptr<nn::Optimizer> make_optimizer(const StageConfig& stage) {
    nn::AdamWOptions o;
    o.lr = stage.lr;
    o.weight_decay = stage.weight_decay;
    std::vector<nn::NamedTensor> params;
    if (stage.kind == StageKind::pose)
      params = nets_.pose_parameters();
    else if (stage.kind == StageKind::detector)
      for (nn::NamedTensor p : nets_.detector->named_parameters()) params.push_back({"detector." + p.name, p.tensor});
    else
      for (nn::NamedTensor p : nets_.deformation_net->named_parameters())
        params.push_back({"deformation_net." + p.name, p.tensor});
    return std::make_unique<nn::AdamW>(std::move(params), o);
  }
  CapturePrediction forward(const Batch& batch, StageKind stage, bool training, PartTimes* times = nullptr);
  std::map<std::string, Tensor> image_and_regulariser_terms(const CapturePrediction& p, const Batch& batch,
                                                            const LossWeights& w, LandmarkStatistics* stats);
  // One step on this process's shards of the global batch (one, without data parallelism).
  StepResult train_step(int64_t step, const StageConfig& stage, nn::Optimizer& opt, nn::DataParallel& dp,
                        const std::vector<Batch>& shards, PartTimes& times);
  std::vector<Batch> physics_shards(int64_t step, const StageConfig& stage, bool parallel) const;
  // This process's shards of a batch that holds its rank's share (DatasetPrefetcher's shards).
  std::vector<Batch> local_shards(const Batch& rank_share) const;
  void check_shards(const StageConfig& stage) const;
  // Rolls the windows' simulations (TBB) and returns what L_sim needs of them.
  struct SimulatedWindows {
    std::vector<int64_t> rows;   // batch rows compared with a simulated state
    std::vector<double> target;  // their simulated states (character units)
  };
  SimulatedWindows simulate(const CapturePrediction& p, const Batch& batch, StepResult& result);
  Tensor simulation_term(const CapturePrediction& p, const SimulatedWindows& sims) const;
  void save(int64_t step, const StageConfig& stage, const nn::Optimizer& opt);

  TrainOptions options_;
  TrainingConfig cfg_;
  DatasetInfo info_;
  Character character_;
  CaptureModel model_;
  CaptureNetworks nets_;
  Faces faces_;
  std::unique_ptr<SyntheticDataset> train_, val_;
  std::unique_ptr<SyntheticDataset> detector_train_;  // the detector stage's crops (null without the stage)
  // The detector stage's terms on a batch of its crops: L_hm against Gaussians at the
  // detections, L_mask against the masks at the mask grid; `px` and `iou` get the decoded
  // keypoints' mean error (crop pixels, confident labels) and the mask IoU at the grid.
  std::map<std::string, Tensor> detector_terms(const Batch& batch, double* px, double* iou) {
    const DetectorConfig& dc = cfg_.network.detector;
    const HeatmapCodec codec = detector_codec(dc);
    nets_.detector->train();
    const DetectorOutput out = nets_.detector->run(batch.images);
    const HeatmapTargets t = encode_heatmaps(batch.keypoints, codec);
    const Tensor mask_target = ops::avg_pool2d(batch.masks, DetectorConfig::kMaskStride, DetectorConfig::kMaskStride);
    std::map<std::string, Tensor> terms;
    terms["heatmaps"] = heatmap_loss(out.heatmaps, t.heatmaps, t.weights);
    terms["mask"] = mask_loss(out.mask_logits, mask_target);
    double error = 0, count = 0, inter = 0, uni = 0;
    const float* kp = batch.keypoints.data<float>();
    const float* z = out.mask_logits.data<float>();
    const float* m = mask_target.data<float>();
    for (int64_t b = 0; b < batch.size(); ++b) {
      const Body25 k = decode_heatmaps(out.heatmaps, b, codec);
      for (int j = 0; j < kBody25Count; ++j) {
        const float* label = kp + (b * kBody25Count + j) * 3;
        if (!(label[2] >= 0.1)) continue;
        error += k(j, 2) > 0 ? std::hypot(k(j, 0) - label[0], k(j, 1) - label[1]) : double(dc.input_size);
        count += 1;
      }
    }
    for (int64_t i = 0; i < mask_target.numel(); ++i) {
      const bool p = z[i] > 0, y = m[i] >= 0.5f;
      inter += p && y, uni += p || y;
    }
    *px = count > 0 ? error / count : 0;
    *iou = uni > 0 ? inter / uni : 1;
    return terms;
  }
  std::unique_ptr<MultiviewSupervision> supervision_;
  std::unique_ptr<VirtualPoses> virtual_;  // the pose stage's virtual poses (null: none)
  // L_lm of the lifting branch alone on the step's virtual poses (virtual_poses.h).
  Tensor virtual_landmark_term(int64_t step, LandmarkStatistics* stats) const {
    const VirtualBatch v = virtual_->batch(cfg_.seed, step);
    const Tensor out = nets_.pose_from_keypoints(v.input);
    const SampleViews views = sample_views(v.input.cameras, v.views, model_.keypoint_mask(), DType::F32);
    const CapturePrediction p = model_.predict(out, Tensor(), views, false);
    return landmark_loss_over_views(p.keypoints, v.views, model_.keypoint_mask(), stats);
  }
  ArapTerms body_arap_, cloth_arap_;
  AttachmentTerms attachment_;
  std::map<int, Vertices> gt_keypoints_;
  // L_3d's targets: per frame, the keypoints triangulated from every view's detections
  // (character units, NaN rows: not triangulated).
  std::map<int, Body25> triangulated_;
  void triangulate_frames(const std::vector<int>& frames) {
    int points = 0, possible = 0;
    for (int f : frames) {
      std::vector<KeypointView> views;
      for (int v = 0; v < supervision_->views(); ++v)
        views.push_back({supervision_->camera(f, v), supervision_->detections(f, v)});
      const Body25 q = triangulate_keypoints(views, model_.keypoint_mask());
      triangulated_[f] = q;
      for (int m = 0; m < kBody25Count; ++m) {
        possible += model_.keypoint_mask()[m] > 0;
        points += q.row(m).allFinite();
      }
    }
    spdlog::info("keypoints_3d: {} of {} mapped keypoints triangulated over {} frames ({} views each)", points,
                 possible, frames.size(), supervision_->views());
  }
  // L_3d of a batch: the mean squared distance (m²) of its keypoints to the triangulated ones.
  Tensor keypoint_3d_term(const CapturePrediction& p, const Batch& batch) const {
    const int64_t B = batch.size();
    std::vector<double> targets(B * kBody25Count * 3, 0.0), weights(B * kBody25Count, 0.0);
    double total = 0;
    for (int64_t b = 0; b < B; ++b) {
      const Body25& q = triangulated_.at(batch.frames[b]);
      for (int m = 0; m < kBody25Count; ++m) {
        if (!q.row(m).allFinite()) continue;
        weights[b * kBody25Count + m] = 1, total += 1;
        for (int a = 0; a < 3; ++a) targets[(b * kBody25Count + m) * 3 + a] = q(m, a);
      }
    }
    const DType dt = p.keypoints.dtype();
    const double mpu = character_.metres_per_unit;
    const Tensor loss = keypoint_3d_loss(p.keypoints, Tensor::from_data({B, kBody25Count, 3}, targets, dt),
                                         Tensor::from_data({B, kBody25Count}, weights, dt));
    return ops::scale(loss, mpu * mpu * double(B) / std::max(total, 1.0));
  }
  // L_lp of a batch: the pelvis's up axis against where the lumbar share of each predicted
  // trunk's lean (MidHip → Neck, held fixed: the prior moves the pelvis, not the trunk)
  // puts it.
  Tensor lumbopelvic_term(const CapturePrediction& p) const {
    constexpr int kNeck = 1, kMidHip = 8;
    const Eigen::Vector3d rest = rest_body25_.row(kNeck) - rest_body25_.row(kMidHip);
    WEFT_CHECK(rest.allFinite(), cfg_.file, ": lumbopelvic needs the character's BODY_25 Neck and MidHip (",
               info_.character, " does not map both)");
    const int64_t B = p.keypoints.size(0);
    std::vector<double> targets(B * 3);
    for (int64_t b = 0; b < B; ++b) {
      const Vertices K = sample_vertices(p.keypoints, b);
      const Eigen::Vector3d t = lumbopelvic_target((K.row(kNeck) - K.row(kMidHip)).transpose(), rest, cfg_.lumbar_share);
      for (int a = 0; a < 3; ++a) targets[b * 3 + a] = t(a);
    }
    return lumbopelvic_loss(p.rotation, Tensor::from_data({B, 3}, targets, p.rotation.dtype()));
  }
  Vertices rest_body25_;  // the character's BODY_25 keypoints at rest
  struct RootPose {
    Eigen::Vector3d pivot;     // the pivot joint's position (character units)
    Eigen::Matrix3d rotation;  // root_rotation_world
  };
  std::map<int, RootPose> gt_roots_;  // the truth's, per frame of gt/pose.motion
  Motion gt_motion_;  // gt/pose.motion (empty without one)
  Motion oracle_motion_;  // config oracle_pose: gt_motion_, perturbed by oracle_pose_noise when given
  // The oracle's dofs of the batch's frames [B, D] (config oracle_pose).
  Tensor oracle_dofs(const Batch& batch) const {
    const int64_t D = oracle_motion_.dofs.cols();
    std::vector<double> d;
    d.reserve(batch.frames.size() * D);
    for (int f : batch.frames)
      for (int64_t k = 0; k < D; ++k) d.push_back(oracle_motion_.dofs(f, k));
    return Tensor::from_data({int64_t(batch.frames.size()), D}, d, DType::F32);
  }
  physics::SimulatorFactory simulator_;
  SynthSimulationConfig simulation_settings_;  // the physics stage's garment simulation (material, collisions)
  std::vector<int> window_starts_;  // train frames that start F consecutive train frames
  nn::ProcessGroup& group_ = nn::ProcessGroup::world();
  int shards_ = 1;  // shards per global batch, over all ranks (nn/data_parallel.h)

  // What Trainer::run carries from step to step, in the order run makes it (destroyed in
  // reverse: the physics loader's future before the prefetcher and the optimiser).
  struct RunState {
    int64_t done = 0;  // the step resumed from (0: a fresh start)
    std::unique_ptr<nn::Optimizer> opt;
    const StageConfig* stage = nullptr;  // the stage opt belongs to
    std::unique_ptr<LossLog> log;        // rank 0's
    int64_t total = 0, last_step = 0;
    Clock::time_point t0;
    std::unique_ptr<DatasetPrefetcher> prefetcher;
    std::unique_ptr<nn::DataParallel> dp;
    std::future<std::vector<Batch>> next_physics;
    int64_t next_physics_step = -1;
    std::map<StageKind, PartTimes> stage_times;
    const StageConfig* prefetcher_stage = nullptr;
    const StageConfig* setup_stage = nullptr;  // the stage dp (and the simulator) is set up for
  };
  // Trainer::run's stages (next to run).
  void start_run(const fs::path& ckdir, RunState& st);
  void open_run_files(const fs::path& run, RunState& st);
  void set_up_stage(const StageConfig& s, int64_t stage_start, int64_t step, RunState& st);
  std::vector<Batch> step_shards(int64_t step, const StageConfig& s, int64_t stage_start, RunState& st);
  void book_step(int64_t step, const StageConfig& s, int64_t stage_start, const StepResult& r, PartTimes& times,
                 const fs::path& run, RunState& st, TrainSummary& summary,
                 const std::function<void(const TrainProgress&)>& progress);
};

CapturePrediction Trainer::forward(const Batch& batch, StageKind stage, bool training, PartTimes* times) {
  auto t = Clock::now();
  const Learning learning = !training                  ? Learning::none
                            : stage == StageKind::pose ? Learning::pose
                            : stage == StageKind::physics && cfg_.physics.freeze_batch_norm
                                ? Learning::deformation_frozen_statistics
                                : Learning::deformation;
  const bool oracle = cfg_.oracle_pose && stage != StageKind::pose;
  CapturePrediction p = predict_batch(nets_, model_, batch, *supervision_, learning, stage != StageKind::pose,
                                      stage != StageKind::pose, oracle ? oracle_dofs(batch) : Tensor());
  if (times) times->lap("networks forward and deformation layer", t);
  return p;
}

std::map<std::string, Tensor> Trainer::image_and_regulariser_terms(const CapturePrediction& p, const Batch& batch,
                                                                   const LossWeights& w, LandmarkStatistics* stats) {
  std::map<std::string, Tensor> t;
  const double m2 = character_.metres_per_unit * character_.metres_per_unit;  // units² → m²
  if (w.landmarks > 0 || stats)
    t["landmarks"] = multiview_landmark_loss(p.keypoints, batch.frames, *supervision_, model_.keypoint_mask(), stats);
  if (w.keypoints_3d > 0) t["keypoints_3d"] = keypoint_3d_term(p, batch);
  if (w.lumbopelvic > 0) t["lumbopelvic"] = lumbopelvic_term(p);
  if (w.silhouette > 0) {
    const Tensor all = p.cloth.defined() ? ops::concat({p.body, p.cloth}, 1) : p.body;
    t["silhouette"] = multiview_silhouette_loss(all, faces_, batch.frames, *supervision_);
  }
  // Each graph's term carries its own weight here: `arap` (the body's) weighs the sum.
  if ((w.arap > 0 || w.cloth_arap > 0) && p.body_rotations.defined()) {
    const double body_w = w.arap > 0 ? 1.0 : 0.0, cloth_w = w.arap > 0 ? w.cloth_arap / w.arap : 0.0;
    Tensor a = ops::scale(arap_loss(body_arap_, p.body_rotations, p.body_translations),
                          body_w * m2 / std::max<int64_t>(1, body_arap_.edges.size(0)));
    if (p.cloth_rotations.defined() && cloth_w > 0)
      a = ops::add(a, ops::scale(arap_loss(cloth_arap_, p.cloth_rotations, p.cloth_translations),
                                 cloth_w * m2 / std::max<int64_t>(1, cloth_arap_.edges.size(0))));
    t["arap"] = a;
  }
  if (w.attachment > 0 && p.cloth.defined() && attachment_.anchors.numel() > 0)
    t["attachment"] = ops::scale(attachment_loss(attachment_, p.cloth, p.body), m2 / attachment_.anchors.numel());
  return t;
}

// The physics stage's batch: `windows` runs of F consecutive train frames, each seen from
// one view, drawn from (seed, step) alone so a resumed run draws the same. Data
// parallelism cuts it by windows: this process loads its shards' windows only.
std::vector<Batch> Trainer::physics_shards(int64_t step, const StageConfig& stage, bool parallel) const {
  const int F = cfg_.physics.window_frames;
  const int windows = std::max(1, stage.batch_size / F);
  PortableRandom rng(mix_seed(cfg_.seed, 0x5157, uint64_t(step)));
  std::vector<std::pair<int, std::string>> keys;
  for (int w = 0; w < windows; ++w) {
    const int start = window_starts_[std::min<size_t>(window_starts_.size() - 1,
                                                      size_t(rng.uniform() * window_starts_.size()))];
    const std::string& view = info_.views[std::min<size_t>(info_.views.size() - 1, size_t(rng.uniform() * info_.views.size()))];
    for (int j = 0; j < F; ++j) keys.emplace_back(start + j, view);
  }
  const int local = shards_ / group_.size(), first_shard = group_.rank() * local;
  const auto [first, last] = std::pair(nn::shard_range(windows, first_shard, shards_).first * F,
                                       nn::shard_range(windows, first_shard + local - 1, shards_).second * F);
  std::vector<Sample> samples(size_t(last - first));
  auto load = [&](size_t i) { samples[i] = train_->load(keys[first + i].first, keys[first + i].second); };
  if (parallel)
    tbb::parallel_for(size_t(0), samples.size(), load);
  else
    for (size_t i = 0; i < samples.size(); ++i) load(i);
  std::vector<Batch> out;
  for (int j = 0; j < local; ++j) {
    const auto [w0, w1] = nn::shard_range(windows, first_shard + j, shards_);
    out.push_back(make_batch(std::vector<Sample>(samples.begin() + (w0 * F - first), samples.begin() + (w1 * F - first))));
    out.back().whole_size = windows * F;
  }
  return out;
}

std::vector<Batch> Trainer::local_shards(const Batch& share) const {
  const int local = shards_ / group_.size(), first_shard = group_.rank() * local;
  if (local == 1) return {share};
  const int64_t n = share.whole_size, offset = nn::shard_range(n, group_.rank(), group_.size()).first;
  std::vector<Batch> out;
  for (int j = 0; j < local; ++j) {
    const auto [first, last] = nn::shard_range(n, first_shard + j, shards_);
    out.push_back(batch_rows(share, int(first - offset), int(last - offset)));
  }
  return out;
}

// Every shard of every batch holds at least one sample (physics: one window).
void Trainer::check_shards(const StageConfig& s) const {
  if (shards_ == 1) return;
  const char* name = stage_name(s.kind);
  if (s.kind == StageKind::physics) {
    const int windows = std::max(1, s.batch_size / cfg_.physics.window_frames);
    WEFT_CHECK(windows >= shards_, cfg_.file, ": stages.", name, ".batch_size: ", s.batch_size, " gives ", windows,
               " simulation windows of ", cfg_.physics.window_frames, " frames, fewer than the ", shards_,
               " shards of data parallelism (shards, or the ranks of mpirun -np): raise it to at least ",
               shards_ * cfg_.physics.window_frames);
  } else {
    WEFT_CHECK(s.batch_size >= shards_, cfg_.file, ": stages.", name, ".batch_size: ", s.batch_size,
               " samples cannot be cut into the ", shards_,
               " shards of data parallelism (shards, or the ranks of mpirun -np)");
    WEFT_CHECK(train_->size() >= shards_, options_.data, ": the train split's ", train_->size(),
               " samples cannot be cut into ", shards_, " shards");
  }
}

// The windows of L_sim (simulation_loss.h): window w holds batch rows w·F … w·F + F − 1,
// frames t' … t' + F − 1 of one clip; its converged simulated frames are the targets of
// rows w·F + 1 ….
Trainer::SimulatedWindows Trainer::simulate(const CapturePrediction& p, const Batch& batch, StepResult& r) {
  const int F = cfg_.physics.window_frames;
  const int windows = batch.size() / F;
  const double mpu = character_.metres_per_unit;
  std::vector<physics::SimulationWindow> sims(windows);
  std::vector<SimulationWindowRecord> records(windows);
  SilhouetteRayOptions rays;
  rays.max_pixels = cfg_.physics.ray_max_pixels;
  rays.metres_per_unit = mpu;
  tbb::parallel_for(0, windows, [&](int w) {
    PredictedWindow in;
    for (int j = 0; j < F; ++j) {
      in.cloth.push_back(sample_vertices(p.cloth, w * F + j));
      in.body.push_back(sample_vertices(p.body, w * F + j));
      if (j > 0 && cfg_.physics.ray_stiffness > 0)
        in.rays.push_back(silhouette_rays(*supervision_, batch.frames[w * F + j], in.body[j], in.cloth[j], faces_, rays));
    }
    records[w].frame = batch.frames[w * F];
    sims[w] = simulation_loss_window(character_, simulation_settings_, in, cfg_.physics.resolve_start, records[w]);
  });
  const auto results = physics::simulate_windows(simulator_, sims);
  SimulatedWindows out;
  for (int w = 0; w < windows; ++w) {
    SimulationWindowRecord& rec = records[w];
    const std::vector<Vertices> targets = simulation_loss_targets(results[w], mpu, rec);
    for (size_t j = 0; j < targets.size(); ++j) {
      out.rows.push_back(w * F + 1 + int64_t(j));
      const Vertices& V = targets[j];
      for (int i = 0; i < V.rows(); ++i)
        for (int k = 0; k < 3; ++k) out.target.push_back(V(i, k));
    }
    ++r.windows;
    if (rec.frames_kept < F - 1) {
      ++r.failures;
      ++r.failure_statuses[rec.status];
    }
    r.window_records.push_back(rec);
  }
  return out;
}

// L_sim: mean squared distance (m²) per vertex between the predicted and the simulated
// cloth at the windows' simulated frames; undefined when every window failed.
Tensor Trainer::simulation_term(const CapturePrediction& p, const SimulatedWindows& sims) const {
  if (sims.rows.empty()) return Tensor();
  const double mpu = character_.metres_per_unit;
  const int64_t n = sims.rows.size(), V = p.cloth.size(1);
  const Tensor predicted = ops::index_select(p.cloth, 0, Tensor::from_indices({n}, sims.rows));
  return simulation_loss(predicted, Tensor::from_data({n, V, 3}, sims.target, DType::F32), mpu);
}

Trainer::StepResult Trainer::train_step(int64_t step, const StageConfig& stage, nn::Optimizer& opt,
                                        nn::DataParallel& dp, const std::vector<Batch>& shards, PartTimes& times) {
  StepResult r;
  std::map<std::string, double> weights;
  for (const LossTerm& term : loss_terms()) weights[term.name] = stage.weights.*term.weight;
  // Per figure: Σ_j w_j · value_j over this process's shards (w_j: the shard's share of
  // the global batch, so the gradient is that of this weighted sum), and in how many
  // shards it was present. One shard on one process: the batch's own values.
  std::map<std::string, std::pair<double, int>> sums;
  auto add = [&](const std::string& name, double share, double value) {
    auto& [sum, count] = sums[name];
    sum += share * value;
    ++count;
  };
  dp.begin_step();
  for (const Batch& batch : shards) {
    const double share = double(batch.size()) / batch.whole_size;
    dp.begin_shard();
    const bool detecting = stage.kind == StageKind::detector;
    const CapturePrediction p = detecting ? CapturePrediction() : forward(batch, stage.kind, true, &times);
    auto t = Clock::now();
    // The simulation runs on TBB threads while this thread computes the image losses.
    const bool simulating = stage.kind == StageKind::physics && stage.weights.simulation > 0;
    std::future<SimulatedWindows> simulated;
    if (simulating)
      simulated = std::async(std::launch::async, [&] { return simulate(p, batch, r); });
    LandmarkStatistics stats;
    std::map<std::string, Tensor> terms;
    if (detecting) {
      double px = 0, iou = 0;
      terms = detector_terms(batch, &px, &iou);
      add("detector_px", share, px);
      add("detector_iou", share, iou);
      times.lap("detector and its losses", t);
    } else {
      terms = image_and_regulariser_terms(p, batch, stage.weights, &stats);
      times.lap("losses", t);
    }
    if (stage.kind == StageKind::pose && stage.weights.virtual_landmarks > 0) {
      LandmarkStatistics virtual_stats;
      terms["virtual_landmarks"] = virtual_landmark_term(step, &virtual_stats);
      add("virtual_keypoint_px", share, virtual_stats.mean_error_px);
      times.lap("virtual poses (detections and lifting branch)", t);
    }
    if (simulating) {
      const Tensor sim = simulation_term(p, simulated.get());
      if (sim.defined()) terms["simulation"] = sim;
      times.lap("simulation (beyond the losses)", t);
    }
    Tensor total;
    for (const auto& [name, t] : terms) {
      add(name, share, t.item());
      const double w = weights.at(name);
      if (w <= 0) continue;
      const Tensor wt = ops::scale(t, w);
      total = total.defined() ? ops::add(total, wt) : wt;
    }
    if (!detecting) add("keypoint_px", share, stats.mean_error_px);
    WEFT_CHECK(total.defined(), cfg_.file, ": stages.", stage_name(stage.kind), ": every loss weight is 0");
    add("total", share, total.item());
    opt.zero_grad();
    (dp.active() ? ops::scale(total, share) : total).backward();
    times.lap("backward", t);
    dp.end_shard();
  }
  // The step's figures over all ranks, in one small all-reduce: what rank 0 logs, and
  // what every rank checks before its optimiser steps.
  auto t = Clock::now();
  static const std::vector<std::string> kFigures = [] {
    std::vector<std::string> names;
    for (const LossTerm& term : loss_terms()) names.push_back(term.name);
    names.insert(names.end(), {"keypoint_px", "virtual_keypoint_px", "detector_px", "detector_iou", "total"});
    return names;
  }();
  static const physics::StepStatus kFailures[] = {physics::StepStatus::max_iterations,
                                                  physics::StepStatus::line_search_failed,
                                                  physics::StepStatus::non_finite};
  std::vector<double> all;
  for (const std::string& name : kFigures) {
    const auto it = sums.find(name);
    all.push_back(it == sums.end() ? 0.0 : it->second.first);
    all.push_back(it == sums.end() ? 0.0 : it->second.second);
  }
  all.push_back(r.windows);
  all.push_back(r.failures);
  for (physics::StepStatus f : kFailures) all.push_back(r.failure_statuses[physics::to_string(f)]);
  group_.all_reduce_sum(std::span<double>(all), "loss terms");
  for (size_t i = 0; i < std::size(kFigures); ++i)
    if (all[2 * i + 1] > 0) r.terms[kFigures[i]] = all[2 * i];
  size_t k = 2 * std::size(kFigures);
  r.windows = int(all[k++]);
  r.failures = int(all[k++]);
  r.failure_statuses.clear();
  for (physics::StepStatus f : kFailures)
    if (const int n = int(all[k++]); n > 0) r.failure_statuses[physics::to_string(f)] = n;
  for (const auto& [name, w] : weights)
    if (const auto it = r.terms.find(name); it != r.terms.end() && !std::isfinite(it->second))
      fail(options_.run, ": step ", step, " (stage ", stage_name(stage.kind), "): the ", name, " loss is ", it->second,
           "; stopping before it reaches the networks (the last checkpoint is intact)");
  if (stage.kind == StageKind::physics) r.terms["sim_failures"] = r.failures;
  if (group_.distributed()) times.lap("waiting for the other ranks", t);
  if (dp.active()) {
    dp.finish_step();
    times.lap("all-reduce of the gradients", t);
  }
  opt.step();
  times.lap("optimiser", t);
  ++times.steps;
  return r;
}

void Trainer::save(int64_t step, const StageConfig& stage, const nn::Optimizer& opt) {
  WEFT_CHECK(all_finite(nets_), options_.run, ": step ", step,
             ": a network parameter is not finite; not writing a checkpoint (the last one is intact)");
  // Rank 0's checkpoint stands for every rank: check that it does.
  nn::check_identical_on_all_ranks(group_, nn::state_checksum(nets_), options_.run + ": checkpoint of step " +
                                                                          std::to_string(step));
  if (!group_.is_root()) return;
  const fs::path dir = fs::path(options_.run) / "checkpoints";
  fs::create_directories(dir);
  nn::save_checkpoint((dir / checkpoint_file(step)).string(), nets_, &opt, step, nullptr,
                      {{"weft.stage", stage_name(stage.kind)}, {"weft.backbone", cfg_.network.backbone},
                       {"weft.shards", std::to_string(shards_)}});
  auto all = list_checkpoints(dir);
  while (int(all.size()) > cfg_.keep_checkpoints) {
    fs::remove(all.front().second);
    all.erase(all.begin());
  }
}

ValidationReport Trainer::validate(const SyntheticDataset& split, int samples) {
  ValidationReport rep;
  const int n = std::min(samples, split.size());
  std::vector<int> indices;
  for (int i = 0; i < n; ++i) indices.push_back(int((int64_t(i) * split.size()) / n));
  double kp_sum = 0, joint_sum = 0, iou_sum = 0, pen_sum = 0;
  int kp_n = 0, joint_n = 0, iou_n = 0, pen_n = 0, cloth_n = 0;
  MeasuredMean root_relative;
  std::vector<double> rotation_errors, heading_errors;
  const double mpu = character_.metres_per_unit;
  for (int first = 0; first < n; first += 8) {
    std::vector<Sample> s(std::min(8, n - first));
    tbb::parallel_for(size_t(0), s.size(), [&](size_t i) { s[i] = split.load(indices[first + i]); });
    const Batch batch = make_batch(s);
    NoGradGuard no_grad;
    const CapturePrediction p = forward(batch, StageKind::warmup, false);
    LandmarkStatistics stats;
    multiview_landmark_loss(p.keypoints, batch.frames, *supervision_, model_.keypoint_mask(), &stats);
    kp_sum += stats.mean_error_px * stats.detections;
    kp_n += stats.detections;
    for (int b = 0; b < batch.size(); ++b) {
      const int frame = batch.frames[b];
      const Vertices K = sample_vertices(p.keypoints, b);
      if (const auto it = gt_keypoints_.find(frame); it != gt_keypoints_.end()) {
        const RootPose& truth = gt_roots_.at(frame);
        // The predicted pivot is the predicted translation (the truth's under the oracle pose,
        // whose prediction carries no translation of its own).
        Eigen::Vector3d pivot = truth.pivot;
        if (!cfg_.oracle_pose)
          for (int a = 0; a < 3; ++a) pivot[a] = p.translation.data<float>()[3 * b + a];
        for (int m = 0; m < kBody25Count; ++m)
          if (model_.keypoint_mask()[m] > 0 && it->second.row(m).allFinite()) {
            joint_sum += (K.row(m) - it->second.row(m)).norm() * mpu * 1000, ++joint_n;
            const Eigen::Vector3d rel = (K.row(m).transpose() - pivot) - (it->second.row(m).transpose() - truth.pivot);
            root_relative.add(rel.norm() * mpu * 1000);
          }
        if (!cfg_.oracle_pose) {
          Eigen::Matrix3d R;
          for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) R(r, c) = p.rotation.data<float>()[9 * b + 3 * r + c];
          rotation_errors.push_back(rotation_error_deg(R, truth.rotation));
          heading_errors.push_back(heading_error_deg(R, truth.rotation));
        }
      }
      const Vertices body = sample_vertices(p.body, b);
      Vertices cloth;
      if (p.cloth.defined()) cloth = sample_vertices(p.cloth, b);
      const TriangleMesh* cloth_mesh = p.cloth.defined() ? &character_.cloth->mesh : nullptr;
      std::vector<double> ious(supervision_->views());
      tbb::parallel_for(0, supervision_->views(), [&](int v) {
        ious[v] = rendered_silhouette_iou(supervision_->silhouette_camera(frame, v), character_.body.mesh, body,
                                          cloth_mesh, cloth_mesh ? &cloth : nullptr,
                                          supervision_->mask(frame, v));
      });
      for (double x : ious) iou_sum += x, ++iou_n;
      if (p.cloth.defined()) {
        FrameMeasures pen;  // the free vertices', as every evaluation measures them
        measure_penetration(character_, body, cloth, pen);
        pen_sum += pen.penetration_depth_sum_mm, pen_n += pen.penetrating_vertices, cloth_n += pen.cloth_vertices;
        rep.penetration_max_mm = std::max(rep.penetration_max_mm, pen.penetration_max_mm);
      }
    }
  }
  rep.samples = n;
  rep.keypoint_error_px = kp_n ? kp_sum / kp_n : 0;
  rep.joint_error_mm = joint_n ? joint_sum / joint_n : -1;
  rep.joint_error_root_relative_mm = root_relative.value();
  const RotationErrorSummary rotation = summarize_rotation_errors(rotation_errors);
  rep.root_rotation_median_deg = rotation.median_deg, rep.root_rotation_above_45 = rotation.above_45;
  const RotationErrorSummary heading = summarize_rotation_errors(heading_errors);
  rep.root_heading_median_deg = heading.median_deg, rep.root_heading_above_45 = heading.above_45;
  rep.silhouette_iou = iou_n ? iou_sum / iou_n : 0;
  rep.penetration_mean_mm = pen_n ? pen_sum / pen_n : 0;
  rep.penetrating_fraction = cloth_n ? double(pen_n) / cloth_n : 0;
  return rep;
}

// Keeps the rows of steps ≤ `step` of a CSV whose first column is the step (validation.csv,
// parameters.csv): a resumed run writes the later ones again.
void cut_validation(const fs::path& path, int64_t step) {
  if (!fs::exists(path)) return;
  std::istringstream in(read_file_bytes(path.string()));
  std::string line, kept;
  for (int i = 0; std::getline(in, line); ++i)
    if (i == 0 || (!line.empty() && std::stoll(line.substr(0, line.find(','))) <= step)) kept += line + "\n";
  if (step == 0) fs::remove(path);
  else write_text_atomically(path.string(), kept);
}

void append_validation(const fs::path& path, const ValidationReport& r) {
  const bool fresh = !fs::exists(path);
  std::ofstream out(path, std::ios::app);
  if (fresh)
    out << "step,samples,keypoint_error_px,joint_error_mm,silhouette_iou,penetration_mean_mm,penetration_max_mm,"
           "penetrating_fraction,joint_error_root_relative_mm,root_rotation_median_deg,root_rotation_above_45,"
           "root_heading_median_deg,root_heading_above_45\n";
  out << r.step << ',' << r.samples << ',' << r.keypoint_error_px << ',' << r.joint_error_mm << ','
      << r.silhouette_iou << ',' << r.penetration_mean_mm << ',' << r.penetration_max_mm << ','
      << r.penetrating_fraction << ',' << r.joint_error_root_relative_mm << ',' << r.root_rotation_median_deg << ','
      << r.root_rotation_above_45 << ',' << r.root_heading_median_deg << ',' << r.root_heading_above_45 << '\n';
}

// RUN/validation.png, the learning curves: validation.csv's error columns against the
// step, one panel each, the stages named from the config's step ranges.
void plot_validation(const fs::path& csv, const std::vector<StageConfig>& stages) {
  static const std::vector<std::string> plotted = {
      "joint_error_root_relative_mm", "root_rotation_median_deg", "root_rotation_above_45", "root_heading_median_deg",
      "root_heading_above_45", "joint_error_mm",
      "keypoint_error_px",            "silhouette_iou",           "penetration_mean_mm"};
  const auto cells_of = [](const std::string& line) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string cell; std::getline(ss, cell, ',');) cells.push_back(cell);
    return cells;
  };
  std::istringstream in(read_file_bytes(csv.string()));
  std::string line;
  std::getline(in, line);
  const std::vector<std::string> columns = cells_of(line);
  std::vector<LossRow> rows;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = cells_of(line);
    if (cells.empty()) continue;
    LossRow row;
    row.step = std::stoll(cells.at(0));
    int64_t end = 0;
    for (const StageConfig& s : stages) {
      end += s.steps;
      if (row.step <= end) {
        row.stage = stage_name(s.kind);
        break;
      }
    }
    for (size_t c = 1; c < std::min(cells.size(), columns.size()); ++c)
      if (std::find(plotted.begin(), plotted.end(), columns[c]) != plotted.end())
        row.terms[columns[c]] = std::strtod(cells[c].c_str(), nullptr);  // "nan": not measured
    rows.push_back(std::move(row));
  }
  if (!rows.empty()) plot_losses(rows, (csv.parent_path() / "validation.png").string(), "weft train: validation");
}

// The mean time per step of each part (the parts add up to the step), logged and kept in
// RUN/timing_<stage>.json.
void log_times(const StageConfig& s, const PartTimes& times, const fs::path& run) {
  if (times.steps == 0) return;
  double total = 0;
  for (const auto& [part, sec] : times.seconds) total += sec;
  std::string line, json = "{\n  \"steps\": " + std::to_string(times.steps) + ",\n  \"ms_per_step\": {";
  bool first = true;
  for (const auto& [part, sec] : times.seconds) {
    line += fmt::format(", {} {:.0f}", part, 1e3 * sec / times.steps);
    json += fmt::format("{}\n    \"{}\": {:.3f}", first ? "" : ",", part, 1e3 * sec / times.steps);
    first = false;
  }
  json += fmt::format("\n  }},\n  \"total_ms_per_step\": {:.3f}\n}}\n", 1e3 * total / times.steps);
  spdlog::info("stage {}: {:.0f} ms per step over {} steps: {}", stage_name(s.kind), 1e3 * total / times.steps,
               times.steps, line.substr(2));
  write_text_atomically((run / fmt::format("timing_{}.json", stage_name(s.kind))).string(), json);
}

// --parameter-checksums: one row per step of RUN/parameters.csv with the checksum of both
// networks' parameters and batch-norm statistics (nn::state_checksum, equal exactly when
// bit-identical) and the sum of the parameters; every rank checks that it holds the same.
void append_parameter_checksum(const fs::path& path, int64_t step, const CaptureNetworks& nets,
                               nn::ProcessGroup& group) {
  const uint64_t checksum = nn::state_checksum(nets);
  nn::check_identical_on_all_ranks(group, checksum, "step " + std::to_string(step));
  if (!group.is_root()) return;
  double sum = 0;
  for (const nn::NamedTensor& p : nets.named_parameters()) {
    const float* d = p.tensor.data<float>();
    for (int64_t i = 0; i < p.tensor.numel(); ++i) sum += d[i];
  }
  const bool fresh = !fs::exists(path);
  std::ofstream out(path, std::ios::app);
  if (fresh) out << "step,checksum,parameter_sum\n";
  out << step << ',' << fmt::format("{:016x}", checksum) << ',' << fmt::format("{:.17g}", sum) << '\n';
}

void log_validation(const ValidationReport& r) {
  spdlog::info("validation at step {}: {} samples, keypoints {:.2f} px, joints {:.1f} mm ({:.1f} mm root-relative), "
               "root rotation median {:.1f}° ({:.1f} % above 45°), heading {:.1f}° ({:.1f} % above 45°), silhouette IoU {:.4f}, "
               "penetration mean {:.2f} mm max {:.2f} mm ({:.2f} % of cloth vertices)",
               r.step, r.samples, r.keypoint_error_px, r.joint_error_mm, r.joint_error_root_relative_mm,
               r.root_rotation_median_deg, 100 * r.root_rotation_above_45, r.root_heading_median_deg,
               100 * r.root_heading_above_45, r.silhouette_iou, r.penetration_mean_mm,
               r.penetration_max_mm, 100 * r.penetrating_fraction);
}

// Where to start: every rank resumes from rank 0's last checkpoint (with --resume), else
// from step 1, from the --init-weights weights if given.
void Trainer::start_run(const fs::path& ckdir, RunState& st) {
  const auto existing = list_checkpoints(ckdir);
  // Every rank resumes from rank 0's choice (a shared file system may show a rank a
  // stale listing).
  int64_t chosen = options_.resume && !existing.empty() ? existing.back().first : -1;
  group_.broadcast(std::span<int64_t>(&chosen, 1), 0, "the checkpoint to resume from");
  if (chosen >= 0) {
    const fs::path last = ckdir / checkpoint_file(chosen);
    WEFT_CHECK(fs::exists(last), last.string(), ": missing on ", group_.describe(),
               "; every rank reads rank 0's checkpoints, so RUN must be on a file system all ranks share");
    const nn::SafetensorsFile file = nn::load_safetensors(last.string());
    const auto it = file.metadata.find("weft.step");
    WEFT_CHECK(it != file.metadata.end(), last.string(), ": not a training checkpoint (no weft.step)");
    const int64_t step = std::stoll(it->second);
    WEFT_CHECK(step <= cfg_.total_steps(), last.string(), ": step ", step, " is past this config's ",
               cfg_.total_steps(), " steps");
    st.stage = &cfg_.stage_of(std::max<int64_t>(step, 1));
    st.opt = make_optimizer(*st.stage);
    const nn::TrainingCheckpoint loaded = nn::load_checkpoint(last.string(), nets_, st.opt.get(), nullptr);
    st.done = loaded.step;
    spdlog::info("resuming {} at step {} (stage {})", last.string(), st.done + 1, stage_name(st.stage->kind));
    if (const auto s = loaded.metadata.find("weft.shards"); s != loaded.metadata.end() && std::stoi(s->second) != shards_)
      spdlog::warn("{}: written with {} shards per batch, resumed with {}: the continuation is not the computation "
                   "the run started (set `shards` in the config to fix it across rank counts)",
                   last.string(), s->second, shards_);
  } else if (options_.resume) {
    spdlog::info("{}: no checkpoint yet: starting from step 1", ckdir.string());
  }
  if (st.done == 0 && !options_.init_weights.empty()) {
    if (load_capture_networks_for_a_new_detector(options_.init_weights, nets_))
      spdlog::info("starting from the weights of {}; it holds no person detector: the detector starts from its "
                   "initialisation", options_.init_weights);
    else
      spdlog::info("starting from the weights of {}", options_.init_weights);
  }
}

// Rank 0 writes every file of the run: the loss log, and the CSVs cut back to the step
// resumed from.
void Trainer::open_run_files(const fs::path& run, RunState& st) {
  if (!group_.is_root()) return;
  st.log = std::make_unique<LossLog>((run / "losses.csv").string(), options_.resume ? st.done : -1);
  cut_validation(run / "validation.csv", options_.resume ? st.done : 0);
  if (options_.parameter_checksums) cut_validation(run / "parameters.csv", options_.resume ? st.done : 0);
  cut_validation(run / "windows.csv", options_.resume ? st.done : 0);
}

// Stage s starts (or the run resumes in it): its optimiser (a fresh one for a new stage),
// its data parallelism and, for the physics stage, the garment simulator and the windows.
void Trainer::set_up_stage(const StageConfig& s, int64_t stage_start, int64_t step, RunState& st) {
  if (&s != st.stage || !st.opt) {  // a new stage gets a fresh optimiser; a resumed one keeps the loaded
    if (st.stage) spdlog::info("stage {} done at step {}", stage_name(st.stage->kind), step - 1);
    st.stage = &s;
    st.opt = make_optimizer(s);
  }
  st.setup_stage = &s;
  st.dp = make_data_parallel(s, *st.opt);
  spdlog::info("stage {}: steps {}–{}, batch {}, lr {}", stage_name(s.kind), stage_start + 1,
               stage_start + s.steps, s.batch_size, s.lr);
  if (s.kind != StageKind::physics) return;
  WEFT_CHECK(character_.has_cloth(), info_.character, ": the physics stage needs a garment");
  SynthSimulationConfig sim = read_dataset_simulation(options_.data);
  sim.max_iterations = cfg_.physics.max_iterations;
  sim.tolerance = cfg_.physics.tolerance;
  simulator_ = garment_simulator_factory(character_, sim, info_.fps, cfg_.physics.ray_stiffness);
  simulation_settings_ = sim;
  const std::vector<int>& fr = train_->frames();
  const int F = cfg_.physics.window_frames;
  window_starts_.clear();
  for (size_t i = 0; i + F <= fr.size(); ++i)
    if (fr[i + F - 1] == fr[i] + F - 1 && same_segment(info_, fr[i], fr[i + F - 1])) window_starts_.push_back(fr[i]);
  WEFT_CHECK(!window_starts_.empty(), options_.data, ": the train split has no run of ", F,
             " consecutive frames of one clip (physics.window_frames)");
}

// This process's shards of the step's batch: physics windows, or the prefetcher's next
// batch (a new prefetcher at each stage).
std::vector<Batch> Trainer::step_shards(int64_t step, const StageConfig& s, int64_t stage_start, RunState& st) {
  if (s.kind == StageKind::physics) {
    // Loaded one step ahead on another thread (a function of the step alone).
    std::vector<Batch> shards = st.next_physics.valid() && st.next_physics_step == step ? st.next_physics.get()
                                                                                       : physics_shards(step, s, true);
    if (step + 1 <= std::min(st.last_step, stage_start + s.steps)) {
      st.next_physics_step = step + 1;
      // One loading thread: the networks' kernels keep the cores.
      st.next_physics = std::async(std::launch::async, [this, step, &s] { return physics_shards(step + 1, s, false); });
    }
    return shards;
  }
  if (st.prefetcher_stage != &s) {
    st.prefetcher.reset();
    PrefetchOptions po;
    po.batch_size = s.batch_size;
    po.seed = mix_seed(cfg_.seed, uint64_t(s.kind), 0xBA7C);
    po.loader_threads = cfg_.loader_threads;
    po.drop_last = train_->size() >= s.batch_size;
    po.first_batch = step - stage_start - 1;
    po.shard = group_.rank();
    po.shards = group_.size();
    const SyntheticDataset& data = s.kind == StageKind::detector ? *detector_train_ : *train_;
    po.drop_last = data.size() >= s.batch_size;
    st.prefetcher = std::make_unique<DatasetPrefetcher>(data, po);
    st.prefetcher_stage = &s;
  }
  return local_shards(st.prefetcher->next());
}

// After a step: the summary's counts, the loss row, checksums, windows, progress and log,
// then the checkpoint, validation, loss plot and the stage's times as they fall due.
void Trainer::book_step(int64_t step, const StageConfig& s, int64_t stage_start, const StepResult& r,
                        PartTimes& times, const fs::path& run, RunState& st, TrainSummary& summary,
                        const std::function<void(const TrainProgress&)>& progress) {
  auto t_book = Clock::now();
  summary.simulation_windows += r.windows;
  summary.simulation_failures += r.failures;
  for (const auto& [status, count] : r.failure_statuses) summary.failure_statuses[status] += count;
  LossRow row;
  row.step = step;
  row.stage = stage_name(s.kind);
  row.terms = r.terms;
  row.terms["lr"] = st.opt->lr();
  if (st.log) st.log->append(row);
  if (options_.parameter_checksums) append_parameter_checksum(run / "parameters.csv", step, nets_, group_);
  if (group_.is_root() && !r.window_records.empty()) append_windows(run / "windows.csv", step, r.window_records);
  if (progress && group_.is_root()) progress({step, st.total, row.stage, r.terms});
  if (step % cfg_.log_every == 0 || step == st.last_step) {
    std::string msg;
    for (const auto& [k, v] : r.terms) msg += fmt::format(" {} {:.4g}", k, v);
    spdlog::info("step {}/{} [{}]{} ({:.2f} s/step)", step, st.total, row.stage, msg,
                 seconds_since(st.t0) / double(step - st.done));
  }
  const bool stage_end = step == stage_start + s.steps;
  if (step % cfg_.checkpoint_every == 0 || stage_end || step == st.last_step) save(step, s, *st.opt);
  if ((cfg_.validate_every > 0 && step % cfg_.validate_every == 0) || step == st.total) {
    if (val_ && group_.is_root()) {  // the other ranks go on to the next step's data and wait there
      ValidationReport v = validate(*val_, cfg_.validation_samples);
      v.step = step;
      append_validation(run / "validation.csv", v);
      plot_validation(run / "validation.csv", cfg_.stages);
      log_validation(v);
      summary.last_validation = v;
    }
  }
  if (st.log && (step % 25 == 0 || stage_end || step == st.last_step))
    plot_losses(st.log->rows(), (run / "losses.png").string());
  times.lap("log, checkpoint, plot, validation", t_book);
  if ((stage_end || step == st.last_step) && group_.is_root()) log_times(s, times, run);
}

TrainSummary Trainer::run(const std::function<void(const TrainProgress&)>& progress) {
  TrainSummary summary;
  const fs::path run(options_.run), ckdir = run / "checkpoints";
  RunState st;
  start_run(ckdir, st);
  open_run_files(run, st);
  if (shards_ > 1)
    spdlog::info("data parallel: {} ranks, {} shards per global batch ({} per rank), each with its own batch-norm "
                 "statistics; gradients and statistics averaged over the shards",
                 group_.size(), shards_, shards_ / group_.size());
  for (const StageConfig& s : cfg_.stages)  // before the first step, not at the stage
    if (s.steps > 0) check_shards(s);
  st.total = cfg_.total_steps();
  st.last_step = options_.stop_after >= 0 ? std::min(st.total, options_.stop_after) : st.total;
  summary.first_step = st.done + 1;
  st.t0 = Clock::now();
  for (int64_t step = st.done + 1; step <= st.last_step; ++step) {
    int64_t stage_start = 0;
    const StageConfig& s = cfg_.stage_of(step, &stage_start);
    if (&s != st.setup_stage) set_up_stage(s, stage_start, step, st);
    const nn::CosineLR schedule(s.lr, s.steps, s.lr * s.final_lr_fraction);
    st.opt->set_lr(schedule.lr(step - stage_start - 1));

    PartTimes& times = st.stage_times[s.kind];
    auto t_data = Clock::now();
    const std::vector<Batch> shards = step_shards(step, s, stage_start, st);
    times.lap("data (waiting)", t_data);
    const StepResult r = train_step(step, s, *st.opt, *st.dp, shards, times);
    book_step(step, s, stage_start, r, times, run, st, summary, progress);
  }
  summary.last_step = st.last_step;
  summary.seconds = seconds_since(st.t0);
  if (st.last_step == st.total && group_.is_root()) nn::save_weights((run / "model.safetensors").string(), nets_);
  return summary;
}

}  // namespace

TrainSummary train(const TrainOptions& options, const std::function<void(const TrainProgress&)>& progress) {
  const TrainingConfig cfg = load_training_config(options.config);
  const fs::path run(options.run);
  const fs::path saved = run / "config.yaml";
  if (!options.resume && fs::exists(run / "checkpoints") && !list_checkpoints(run / "checkpoints").empty())
    fail(options.run, ": already holds a run (checkpoints/); pass --resume to continue it or choose another folder");
  fs::create_directories(run);
  const std::string text = read_file_bytes(options.config);
  if (options.resume && fs::exists(saved)) {
    WEFT_CHECK(read_file_bytes(saved.string()) == text, options.config, ": differs from ", saved.string(),
               ", the config the run was started with; resume with that one");
  } else if (nn::ProcessGroup::world().is_root()) {
    write_text_atomically(saved.string(), text);
  }
  if (nn::ProcessGroup::world().is_root()) write_model_folder(options.run, options.config, options.data);
  Trainer trainer(options, cfg);
  return trainer.run(progress);
}

ValidationReport validate_checkpoint(const std::string& config, const std::string& data, const std::string& weights,
                                     const std::string& split, int samples) {
  TrainOptions o;
  o.config = config;
  o.data = data;
  const TrainingConfig cfg = load_training_config(config);
  Trainer trainer(o, cfg);
  nn::load_weights(weights, trainer.networks(), false);
  DatasetOptions d;
  d.input_size = cfg.network.input_size;
  d.margin = cfg.network.margin;
  d.split = split;
  const SyntheticDataset ds(data, d);
  return trainer.validate(ds, samples);
}

}  // namespace weft::capture
