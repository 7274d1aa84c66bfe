#include "capture/evaluation/capture_evaluation.h"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <numbers>
#include <numeric>

#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/io/openpose.h"
#include "capture/evaluation/capture_folder.h"
#include "capture/evaluation/frame_measures.h"
#include "geometry/mesh_io.h"
#include "capture/render/detection_drawing.h"
#include "capture/render/renderer.h"
#include "capture/model/capture_networks.h"
#include "capture/render/silhouette_iou.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

double nan_max(double a, double b) { return std::isnan(a) ? b : std::isnan(b) ? a : std::max(a, b); }

// A ground-truth mesh of the dataset, checked against the template.
Vertices read_gt_mesh(const DatasetInfo& info, const std::string& name, int frame, int vertices,
                      const Character& ch) {
  const fs::path path = fs::path(info.dir) / "gt" / fmt::format("{}_{:04d}.ply", name, frame);
  WEFT_CHECK(fs::exists(path), path.string(), ": missing (expected the ground-truth ", name, " of frame ", frame, ")");
  const TriangleMesh m = read_ply(path.string());
  WEFT_CHECK(m.V.rows() == vertices, path.string(), ": ", m.V.rows(), " vertices, expected ", vertices, " (the ",
             name, " of ", ch.source, ": the capture's character is not the dataset's)");
  return m.V;
}

// The frame's prediction or ground truth, kept for the out-of-balance force of the frames after it.
struct Kept {
  int id = -1;
  Vertices body, cloth, gt_body, gt_cloth;
};

// Draws the body (blue) and cloth (orange) translucently over `image`, outlined in white.
cv::Mat draw_meshes(const cv::Mat& image, const Camera& camera, const Character& ch, const Vertices& body,
                    const Vertices* cloth) {
  cv::Mat out = image.clone();
  if (!in_front(camera, body)) return out;
  std::vector<RenderMesh> meshes(cloth ? 2 : 1);
  meshes[0].mesh = &ch.body.mesh;
  meshes[0].vertices = &body;
  if (cloth) {
    meshes[1].mesh = &ch.cloth->mesh;
    meshes[1].vertices = cloth;
    meshes[1].part = 2;
  }
  const RenderResult r = render(camera, meshes);
  const cv::Vec3b body_bgr(230, 140, 40), cloth_bgr(20, 140, 255);
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const uchar part = r.parts.at<uchar>(y, x);
      if (!part) continue;
      const cv::Vec3b c = part == 2 ? cloth_bgr : body_bgr;
      cv::Vec3b& p = out.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) p[k] = cv::saturate_cast<uchar>(0.45 * p[k] + 0.55 * c[k]);
    }
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(r.mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
  cv::drawContours(out, contours, -1, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
  return out;
}

void caption(cv::Mat& image, const std::string& text) {
  const double scale = std::max(0.35, image.cols / 700.0);
  const cv::Point at(6, int(18 * scale + 4));
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 3, cv::LINE_AA);
  cv::putText(image, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
}

// What the evaluation reads, checked against each other (open_inputs).
struct EvaluationInputs {
  CaptureFolder cap;
  std::string cap_json;
  DatasetInfo info;
  Character character;
  int input_view = 0;
  SynthSimulationConfig simulation;  // the cloth material for the out-of-balance force
  bool with_oob = false;
  std::vector<int> order;   // the capture's frames in frame-id order
  std::vector<int> failed;  // their ids that failed in the dataset's simulation (sorted)
  Eigen::MatrixXd dofs;     // the captured dofs, one row per capture frame
  std::string gt_motion_path;
  Motion gt_motion;
  PoseParametrisation param;
  std::string cameras_path;
  std::map<std::string, Camera> cameras;

  const Camera& camera_of(int frame, const std::string& view) const {
    const std::string name = dataset_camera_name(info, frame, view);
    const auto it = cameras.find(name);
    WEFT_CHECK(it != cameras.end(), cameras_path, ": no camera '", name, "'");
    return it->second;
  }
};

// Both folders, the input view, the character, and their units and frame rate checked
// against each other.
void open_inputs(const EvaluationOptions& o, EvaluationInputs& in, CaptureEvaluation& e) {
  WEFT_CHECK(o.iou_every >= 1, "--iou-every must be ≥ 1, is ", o.iou_every);
  in.cap = read_capture_folder(o.prediction);
  const CaptureFolder& cap = in.cap;
  const std::string& cap_json = in.cap_json = (fs::path(cap.dir) / "capture.json").string();
  in.info = read_dataset_info(o.data);
  const DatasetInfo& info = in.info;
  const std::string info_yaml = (fs::path(info.dir) / "dataset.yaml").string();

  e.options = o;
  e.views = info.views;
  e.view = o.view.empty() ? cap.view : o.view;
  const auto view_it = std::find(info.views.begin(), info.views.end(), e.view);
  WEFT_CHECK(view_it != info.views.end(), "the input view '", e.view, "' (",
             o.view.empty() ? cap_json + "'s \"view\"" : std::string("--view"), ") is not a view of ", info_yaml,
             " (views: ", fmt::format("{}", fmt::join(info.views, ", ")), "); pass --view with one of them");
  in.input_view = int(view_it - info.views.begin());

  WEFT_CHECK(fs::exists(cap.character), cap_json, ": character '", cap.character, "' does not exist");
  in.character = load_character(cap.character);
  const Character& ch = in.character;
  e.character = cap.character;
  e.has_cloth = ch.has_cloth();
  const double mpu = ch.metres_per_unit;
  e.metres_per_unit = mpu;
  WEFT_CHECK(std::abs(cap.metres_per_unit - mpu) <= 1e-9 * mpu, cap_json, ": metres_per_unit ", cap.metres_per_unit,
             " differs from the character's ", mpu, " (", cap.character, ")");
  WEFT_CHECK(std::abs(info.metres_per_unit - mpu) <= 1e-9 * mpu, info_yaml, ": metres_per_unit ",
             info.metres_per_unit, " differs from the captured character's ", mpu, " (", cap.character, ")");
  // Frame ids are the dataset's: one frame lasts 1/fps of the dataset.
  e.fps = info.fps;
  if (std::abs(cap.fps - info.fps) > 1e-9 * info.fps) {
    e.notes.push_back(fmt::format("capture.json's fps {} differs from the dataset's {}: accelerations use the "
                                  "dataset's (frame ids are the dataset's frames)",
                                  cap.fps, info.fps));
    spdlog::warn("{}", e.notes.back());
  }
}

// The cloth material for the out-of-balance force: --synth-config, else the dataset's.
void choose_simulation(const EvaluationOptions& o, EvaluationInputs& in, CaptureEvaluation& e) {
  if (e.has_cloth) {
    if (!o.synth_config.empty()) {
      WEFT_CHECK(fs::exists(o.synth_config), o.synth_config, ": no such synth config (from --synth-config)");
      in.simulation = load_simulation_config(o.synth_config);
      e.synth_config = o.synth_config;
      in.with_oob = true;
    } else if (const std::optional<SynthSimulationConfig> s = find_dataset_simulation(o.data)) {
      in.simulation = *s;
      e.synth_config = (fs::path(o.data) / "dataset.yaml").string();
      in.with_oob = true;
    } else {
      e.notes.push_back("out-of-balance force not measured: no simulation settings give the cloth material (the "
                        "dataset's dataset.yaml has no simulation section: regenerate it with weft synth, or pass "
                        "--synth-config)");
      spdlog::warn("{}", e.notes.back());
    }
  } else {
    e.notes.push_back("the character has no garment: cloth error, penetration and out-of-balance force not measured");
  }
}

// The captured frames in id order, each a frame of the dataset; those whose simulation
// failed; the captured and the true poses; the dataset's cameras.
void read_frames(EvaluationInputs& in, CaptureEvaluation& e) {
  const CaptureFolder& cap = in.cap;
  const DatasetInfo& info = in.info;
  std::vector<int>& order = in.order;
  order.resize(cap.frames.size());
  std::iota(order.begin(), order.end(), 0);
  for (int i : order)
    WEFT_CHECK(cap.frames[i].id < info.frames, in.cap_json, ": frames[", i, "]: id ", cap.frames[i].id,
               " is not a frame of the dataset ", info.dir, " (frames 0..", info.frames - 1, ")");
  std::sort(order.begin(), order.end(), [&](int a, int b) { return cap.frames[a].id < cap.frames[b].id; });
  for (int i : order) {
    const int id = cap.frames[i].id;
    if (std::count(info.failed_frames.begin(), info.failed_frames.end(), id)) in.failed.push_back(id);
  }
  if (!in.failed.empty()) {
    e.notes.push_back(fmt::format("frames {} failed in the dataset's simulation: their ground-truth cloth is not "
                                  "in equilibrium, so their cloth vertex error is not measured",
                                  fmt::join(in.failed, ", ")));
    spdlog::warn("{}", e.notes.back());
  }
  in.dofs = read_captured_dofs(cap, in.character);
  in.gt_motion_path = (fs::path(info.dir) / "gt" / "pose.motion").string();
  in.gt_motion = read_motion(in.gt_motion_path, int(in.character.rest_dofs.size()));
  in.param = pose_parametrisation(in.character);
  in.cameras_path = (fs::path(info.dir) / "cameras.yaml").string();
  for (const Camera& c : read_cameras_yaml(in.cameras_path)) in.cameras[c.name] = c;
}

// What the summary pools over frames.
struct Pooled {
  std::vector<double> cloth_distances, body_distances;  // for the 95th percentiles
  FrameMetricMeans means;
  std::vector<double> root_rotation_deg, root_heading_deg, root_tilt_deg, trunk_direction_deg;
  BalancePool balance, gt_balance;
  FrameMeasures penetration, gt_penetration;  // sums over frames (depth, vertices inside)
  std::vector<MeasuredMean> joint_root_relative, joint_pa;  // per BODY_25 row
  std::vector<TestFramePose> test_poses;                   // for the training-set comparison
};

// Every measure of capture frame k (in id order); prev2 and prev1 are the frames before
// it, for the out-of-balance force; its meshes are returned for the frames after it.
Kept measure_frame(const EvaluationInputs& in, const EvaluationOptions& o, int k, const Kept& prev2,
                   const Kept& prev1, CaptureEvaluation& e, Pooled& pool) {
  const Character& ch = in.character;
  const double mpu = ch.metres_per_unit;
  const CapturedFrame& cf = in.cap.frames[in.order[k]];
  const int f = cf.id;
  FrameEvaluation fe;
  fe.id = f;
  WEFT_CHECK(f < in.gt_motion.num_frames(), in.gt_motion_path, ": no row for frame ", f);
  const PosedCharacter gt_pose = pose_character(ch, in.gt_motion.dofs.row(f).transpose());
  const Eigen::Vector3d gt_pivot = gt_pose.joints[in.param.pivot_joint].translation();
  if (o.gt_translation) fe.shift = gt_pivot - cf.pivot;
  const Eigen::RowVector3d shift = fe.shift.transpose();

  Kept now;
  now.id = f;
  CapturedMeshes m = read_captured_meshes(in.cap, f, ch);
  now.body = m.body.rowwise() + shift;
  if (e.has_cloth) now.cloth = m.cloth.rowwise() + shift;
  now.gt_body = read_gt_mesh(in.info, "body", f, int(ch.body.mesh.V.rows()), ch);
  if (e.has_cloth) now.gt_cloth = read_gt_mesh(in.info, "cloth", f, int(ch.cloth->mesh.V.rows()), ch);

  // Pose, 3D error and penetration. The pivot error is the prediction's before any shift;
  // the joints are the shifted ones, and root-relative they are the same either way. A
  // frame whose simulation failed has no trustworthy cloth to compare with: its cloth
  // error is not measured (the rest of the frame is).
  const PosedCharacter pred_pose = pose_character(ch, in.dofs.row(in.order[k]).transpose());
  PosedFrame predicted, truth;
  predicted.body = now.body, predicted.cloth = now.cloth;
  predicted.body25 = pred_pose.body25.rowwise() + shift;
  predicted.pivot = pred_pose.joints[in.param.pivot_joint].translation() + fe.shift;
  predicted.root_rotation = pred_pose.joints[in.param.pivot_joint].linear();
  truth.body = now.gt_body, truth.cloth = now.gt_cloth, truth.body25 = gt_pose.body25, truth.pivot = gt_pivot;
  truth.root_rotation = gt_pose.joints[in.param.pivot_joint].linear();
  const Camera& input_camera = in.camera_of(f, e.view);
  truth.view_rotation = input_camera.R;
  fe.predicted_body25 = predicted.body25, fe.true_body25 = truth.body25;
  FrameMeasures& fm = fe.measures;
  measure_geometry(ch, predicted, truth, !std::binary_search(in.failed.begin(), in.failed.end(), f), fm);
  for (auto [means, errors] : {std::pair{&pool.joint_root_relative, &fm.joint_errors_root_relative_mm},
                               std::pair{&pool.joint_pa, &fm.joint_errors_pa_mm}}) {
    if (means->size() < errors->size()) means->resize(errors->size());
    for (size_t j = 0; j < errors->size(); ++j) (*means)[j].add((*errors)[j]);
  }
  if (!o.training_data.empty()) {
    TestFramePose tp;
    tp.id = f, tp.body25 = gt_pose.body25, tp.pivot = gt_pivot, tp.root_rotation = *truth.root_rotation;
    tp.camera = input_camera;
    tp.detections = read_dataset_keypoints(dataset_keypoints_path(in.info, f, e.view));
    pool.test_poses.push_back(std::move(tp));
  }
  fm.pivot_error_mm = (cf.pivot - gt_pivot).norm() * mpu * 1e3;
  pool.root_rotation_deg.push_back(fm.root_rotation_error_deg);
  pool.root_heading_deg.push_back(fm.root_heading_error_deg);
  pool.root_tilt_deg.push_back(fm.root_tilt_error_deg);
  if (std::isfinite(fm.trunk_direction_error_deg)) pool.trunk_direction_deg.push_back(fm.trunk_direction_error_deg);
  pool.body_distances.insert(pool.body_distances.end(), fm.body_distances_mm.begin(), fm.body_distances_mm.end());
  pool.cloth_distances.insert(pool.cloth_distances.end(), fm.cloth_distances_mm.begin(), fm.cloth_distances_mm.end());
  fm.body_distances_mm.clear(), fm.cloth_distances_mm.clear();  // pooled: not kept per frame
  if (e.has_cloth) {
    measure_penetration(ch, now.gt_body, now.gt_cloth, fe.ground_truth);
    for (auto [sum, frame] : {std::pair{&pool.penetration, &fm}, std::pair{&pool.gt_penetration, &fe.ground_truth}}) {
      sum->penetration_depth_sum_mm += frame->penetration_depth_sum_mm;
      sum->penetrating_vertices += frame->penetrating_vertices, sum->cloth_vertices += frame->cloth_vertices;
      sum->penetration_max_mm = nan_max(sum->penetration_max_mm, frame->penetration_max_mm);
    }
    // Out-of-balance force over frames f − 2, f − 1, f of one clip, of both.
    if (in.with_oob && f >= 2 && prev2.id == f - 2 && prev1.id == f - 1 && same_segment(in.info, f - 2, f)) {
      measure_balance(ch, in.simulation, e.fps, prev1.body, now.body, prev2.cloth, prev1.cloth, now.cloth, fm,
                      &pool.balance);
      measure_balance(ch, in.simulation, e.fps, prev1.gt_body, now.gt_body, prev2.gt_cloth, prev1.gt_cloth,
                      now.gt_cloth, fe.ground_truth, &pool.gt_balance);
    }
  }

  // Silhouette IoU on every N-th frame, every view.
  if (k % o.iou_every == 0) {
    std::vector<Camera> cams;
    std::vector<cv::Mat> masks;
    for (const std::string& v : in.info.views) {
      cams.push_back(in.camera_of(f, v));
      masks.push_back(read_dataset_mask(in.info, f, v));
    }
    fe.iou = silhouette_ious(ch, now.body, e.has_cloth ? &now.cloth : nullptr, cams, masks);
    measure_ious(fe.iou, in.input_view, fm);
    ++e.iou_frames;
  }

  pool.means.add(fm);
  e.frames.push_back(std::move(fe));
  return now;
}

// The summary's figures from what the frames pooled.
void summarize(const EvaluationInputs& in, const Pooled& pool, CaptureEvaluation& e) {
  const FrameMetricMeans& means = pool.means;
  e.oob_frames = pool.balance.frames, e.gt_oob_frames = pool.gt_balance.frames;
  if (in.with_oob && e.oob_frames == 0) {
    e.notes.push_back("out-of-balance force not measured: no three consecutive captured frames of one clip");
    spdlog::warn("{}", e.notes.back());
  }
  if (in.info.views.size() == 1)
    e.notes.push_back("the dataset has one view: RVIoU (all but the input view) is undefined");

  e.pivot_error_mm = means.mean("pivot_error_mm");
  e.body_error_mean_mm = means.mean("body_error_mean_mm");
  e.body_error_p95_mm = quantile(pool.body_distances, 0.95);
  e.mpjpe_mm = means.mean("mpjpe_mm");
  e.mpjpe_root_relative_mm = means.mean("mpjpe_root_relative_mm");
  e.pa_mpjpe_mm = means.mean("pa_mpjpe_mm");
  e.mpjpe_depth_mm = means.mean("mpjpe_depth_mm");
  e.mpjpe_image_plane_mm = means.mean("mpjpe_image_plane_mm");
  for (const MeasuredMean& m : pool.joint_root_relative) e.joint_error_root_relative_mm.push_back(m.value());
  for (const MeasuredMean& m : pool.joint_pa) e.joint_error_pa_mm.push_back(m.value());
  const RotationErrorSummary rotation = summarize_rotation_errors(pool.root_rotation_deg);
  e.root_rotation_median_deg = rotation.median_deg, e.root_rotation_p95_deg = rotation.p95_deg,
  e.root_rotation_above_45 = rotation.above_45;
  const RotationErrorSummary heading = summarize_rotation_errors(pool.root_heading_deg);
  e.root_heading_median_deg = heading.median_deg, e.root_heading_p95_deg = heading.p95_deg,
  e.root_heading_above_45 = heading.above_45;
  const RotationErrorSummary tilt = summarize_rotation_errors(pool.root_tilt_deg);
  e.root_tilt_median_deg = tilt.median_deg, e.root_tilt_p95_deg = tilt.p95_deg;
  const RotationErrorSummary trunk = summarize_rotation_errors(pool.trunk_direction_deg);
  e.trunk_direction_median_deg = trunk.median_deg, e.trunk_direction_p95_deg = trunk.p95_deg;
  if (e.has_cloth) {
    e.cloth_chamfer_mm = means.mean("cloth_chamfer_mm");
    e.cloth_error_mean_mm = means.mean("cloth_error_mean_mm");
    e.cloth_error_p95_mm = quantile(pool.cloth_distances, 0.95);
    const auto mean_inside = [](const FrameMeasures& s) {
      return s.penetrating_vertices ? s.penetration_depth_sum_mm / double(s.penetrating_vertices) : 0.0;
    };
    const FrameMeasures &pen = pool.penetration, &gt_pen = pool.gt_penetration;
    e.penetration_mean_mm = mean_inside(pen), e.gt_penetration_mean_mm = mean_inside(gt_pen);
    e.penetration_max_mm = pen.penetration_max_mm, e.gt_penetration_max_mm = gt_pen.penetration_max_mm;
    e.penetration_mean_all_mm = pen.penetration_depth_sum_mm / double(pen.cloth_vertices);
    e.penetrating_fraction = double(pen.penetrating_vertices) / double(pen.cloth_vertices);
    e.gt_penetrating_fraction = double(gt_pen.penetrating_vertices) / double(gt_pen.cloth_vertices);
  }
  const BalancePool &b = pool.balance, &g = pool.gt_balance;
  e.oob_n = distribution(b.n), e.oob_rel = distribution(b.rel);
  e.gt_oob_n = distribution(g.n), e.gt_oob_rel = distribution(g.rel);
  e.oob_all_n = distribution(b.all_n), e.oob_all_rel = distribution(b.all_rel);
  e.gt_oob_all_n = distribution(g.all_n), e.gt_oob_all_rel = distribution(g.all_rel);
  e.oob_outside_n = distribution(b.outside_n);
  e.inertia_mean_n = b.inertia.value(), e.elastic_mean_n = b.elastic.value(),
  e.collision_mean_n = b.collision.value(), e.friction_mean_n = b.friction.value();
  e.amv_iou = means.mean("amv_iou"), e.rv_iou = means.mean("rv_iou"), e.sv_iou = means.mean("sv_iou");
}

// The model's detections the capture read, against the dataset's truth on the captured frames.
void measure_detector_inputs(const EvaluationInputs& in, CaptureEvaluation& e) {
  const CaptureFolder& cap = in.cap;
  if (cap.detections.empty()) return;
  if (cap.masks_from != "detector" || cap.keypoints_from != "detector") {
    e.notes.push_back(fmt::format("the capture read its {} from the person detector, its {} from elsewhere: the "
                                  "detector's inputs are not measured",
                                  cap.masks_from == "detector" ? "masks" : "keypoints",
                                  cap.masks_from == "detector" ? "keypoints" : "masks"));
    return;
  }
  std::vector<int> ids;
  for (const CapturedFrame& f : cap.frames) ids.push_back(f.id);
  try {
    e.detections = measure_detections(
        cap.detections, {in.info, in.character, in.gt_motion, in.gt_motion_path, in.cameras, in.cameras_path}, e.view, ids);
  } catch (const Error& error) {  // e.g. frames named otherwise than the dataset's: the rest still counts
    e.notes.push_back(fmt::format("the detector's inputs are not measured: {}", error.what()));
    spdlog::warn("{}", e.notes.back());
    return;
  }
  for (const std::string& line : detection_summary_lines(*e.detections)) spdlog::info("the detector's inputs: {}", line);
}

// Overlays of the worst and the median frame: by cloth error, else by the input view's IoU.
void draw_overlays(const EvaluationInputs& in, CaptureEvaluation& e) {
  const Character& ch = in.character;
  const auto score = [&](int k) {
    const FrameMeasures& m = e.frames[k].measures;
    return e.has_cloth ? m.cloth_error_mean_mm : -m.sv_iou;
  };
  std::vector<int> ranked;
  for (int k = 0; k < int(e.frames.size()); ++k)
    if (std::isfinite(score(k))) ranked.push_back(k);
  std::stable_sort(ranked.begin(), ranked.end(), [&](int a, int b) { return score(a) > score(b); });
  std::vector<std::pair<std::string, int>> picks;
  if (!ranked.empty()) picks.push_back({"worst", ranked.front()});
  if (ranked.size() > 1) picks.push_back({"median", ranked[ranked.size() / 2]});
  for (const auto& [label, k] : picks) {
    const int f = e.frames[k].id;
    const std::string image_path = dataset_image_path(in.info, f, e.view);
    const cv::Mat image = cv::imread(image_path, cv::IMREAD_COLOR);
    WEFT_CHECK(!image.empty(), image_path, ": missing or unreadable (expected the input view's image of frame ", f,
               ")");
    const Camera& camera = in.camera_of(f, e.view);
    WEFT_CHECK(image.cols == camera.width && image.rows == camera.height, image_path, ": ", image.cols, "×",
               image.rows, " pixels, expected the camera's ", camera.width, "×", camera.height);
    const Eigen::RowVector3d shift = e.frames[k].shift.transpose();
    const CapturedMeshes m = read_captured_meshes(in.cap, f, ch);
    const Vertices body = m.body.rowwise() + shift;
    const Vertices cloth = e.has_cloth ? Vertices(m.cloth.rowwise() + shift) : Vertices();
    const Vertices gt_body = read_gt_mesh(in.info, "body", f, int(ch.body.mesh.V.rows()), ch);
    const Vertices gt_cloth =
        e.has_cloth ? read_gt_mesh(in.info, "cloth", f, int(ch.cloth->mesh.V.rows()), ch) : Vertices();
    cv::Mat left = draw_meshes(image, camera, ch, body, e.has_cloth ? &cloth : nullptr);
    cv::Mat right = draw_meshes(image, camera, ch, gt_body, e.has_cloth ? &gt_cloth : nullptr);
    caption(left, fmt::format("prediction, frame {}", f));
    caption(right, "ground truth");
    std::vector<cv::Mat> panels{left, right};
    if (e.detections) {  // the detector's mask and keypoints the capture read, on the left
      const std::string name = dataset_frame_name(f);
      const fs::path dir(in.cap.detections);
      const std::string mask_path = (dir / "masks" / (name + ".png")).string();
      const cv::Mat mask = cv::imread(mask_path, cv::IMREAD_GRAYSCALE);
      WEFT_CHECK(mask.size() == image.size(), mask_path, ": missing, unreadable or not the frame's size");
      cv::Mat inputs = draw_detection(image, read_dataset_keypoints((dir / "keypoints" / (name + "_keypoints.json")).string()),
                                      mask);
      caption(inputs, "the detector's mask and keypoints");
      panels.insert(panels.begin(), inputs);
    }
    EvaluationOverlay ov;
    ov.label = label;
    ov.id = f;
    ov.ranked_by = e.has_cloth ? fmt::format("cloth error {:.1f} mm", e.frames[k].measures.cloth_error_mean_mm)
                               : fmt::format("SVIoU {:.4f}", e.frames[k].measures.sv_iou);
    cv::hconcat(panels, ov.image);
    e.overlays.push_back(std::move(ov));
  }
}

}  // namespace

CaptureEvaluation evaluate_capture(const EvaluationOptions& o, const std::function<void(int, int)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  CaptureEvaluation e;
  EvaluationInputs in;
  open_inputs(o, in, e);
  choose_simulation(o, in, e);
  read_frames(in, e);
  Pooled pool;
  Kept prev2, prev1;
  const int total = int(in.order.size());
  for (int k = 0; k < total; ++k) {
    Kept now = measure_frame(in, o, k, prev2, prev1, e, pool);
    prev2 = std::move(prev1);
    prev1 = std::move(now);
    if (progress) progress(k + 1, total);
  }
  summarize(in, pool, e);
  if (!o.training_data.empty()) {
    spdlog::info("comparing the {} test poses with the training set {} (split '{}')", pool.test_poses.size(),
                 o.training_data, o.training_split);
    const TrainingPoses training = read_training_poses(o.training_data, o.training_split, in.character);
    e.training_set = compare_with_training_set(training, pool.test_poses, in.character.metres_per_unit);
  }
  measure_detector_inputs(in, e);
  draw_overlays(in, e);
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return e;
}

}  // namespace weft::capture
