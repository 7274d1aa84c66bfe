#include "capture/evaluation/detection_accuracy.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <numeric>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "capture/character/character.h"
#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/io/camera.h"
#include "capture/render/keypoint_visibility.h"
#include "capture/render/renderer.h"
#include "geometry/mesh_io.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
const double kNaN = std::numeric_limits<double>::quiet_NaN();

// The error of a predicted keypoint against a reference one (frame pixels).
double keypoint_error(const Body25& pred, int m, double u, double v) {
  return pred(m, 2) > 0 ? std::hypot(pred(m, 0) - u, pred(m, 1) - v) : kInf;
}

template <class F>
std::vector<double> pooled(const std::array<std::vector<double>, kBody25Count>& per_joint, F keep) {
  std::vector<double> out;
  for (int m = 0; m < kBody25Count; ++m)
    if (keep(m)) out.insert(out.end(), per_joint[m].begin(), per_joint[m].end());
  return out;
}

nlohmann::json number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

// The entries of `values` whose `keep` flag is set.
std::vector<double> kept(const std::vector<double>& values, const std::vector<char>& keep) {
  std::vector<double> out;
  for (size_t i = 0; i < values.size(); ++i)
    if (keep[i]) out.push_back(values[i]);
  return out;
}

// Over all keypoints, the entries whose keypoint the camera sees.
std::pair<std::vector<double>, std::vector<double>> visible_errors(const DetectionAccuracy& a) {
  std::vector<double> errors, thresholds;
  for (int m = 0; m < kBody25Count; ++m) {
    const auto e = kept(a.truth_error_px[m], a.truth_visible[m]), t = kept(a.truth_threshold_px[m], a.truth_visible[m]);
    errors.insert(errors.end(), e.begin(), e.end());
    thresholds.insert(thresholds.end(), t.begin(), t.end());
  }
  return {errors, thresholds};
}

// The depth of the true body (posed by the dataset's motion) and, when the dataset has it,
// the true garment of frame f, as the studio rendered them.
cv::Mat true_depth(const DetectionTruth& truth, const Camera& camera, int f, const Vertices& body) {
  std::vector<RenderMesh> meshes{{&truth.character.body.mesh, &body, 1}};
  Vertices cloth;
  const fs::path cloth_path = fs::path(truth.info.dir) / "gt" / fmt::format("cloth_{:04d}.ply", f);
  if (truth.character.has_cloth() && fs::exists(cloth_path)) {
    cloth = read_ply(cloth_path.string()).V;
    WEFT_CHECK(cloth.rows() == truth.character.cloth->mesh.V.rows(), cloth_path.string(), ": ", cloth.rows(),
               " vertices, the character's garment has ", truth.character.cloth->mesh.V.rows());
    meshes.push_back({&truth.character.cloth->mesh, &cloth, 2});
  }
  return render(camera, meshes).depth;
}
}  // namespace

double mask_iou(const cv::Mat& a, const cv::Mat& b) {
  WEFT_CHECK(a.size() == b.size() && a.type() == CV_8UC1 && b.type() == CV_8UC1,
             "mask_iou: expected two 8-bit masks of one size");
  cv::Mat both, either;
  cv::bitwise_and(a != 0, b != 0, both);
  cv::bitwise_or(a != 0, b != 0, either);
  const int u = cv::countNonZero(either);
  return u == 0 ? 1.0 : double(cv::countNonZero(both)) / u;
}

double median_of(std::vector<double> v) {
  if (v.empty()) return kNaN;
  const size_t k = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + k, v.end());
  if (v.size() % 2) return v[k];
  const double upper = v[k];
  return 0.5 * (*std::max_element(v.begin(), v.begin() + k) + upper);
}

double fraction_within(const std::vector<double>& errors, const std::vector<double>& thresholds) {
  WEFT_CHECK(errors.size() == thresholds.size(), "fraction_within: ", errors.size(), " errors, ", thresholds.size(),
             " thresholds");
  if (errors.empty()) return kNaN;
  size_t n = 0;
  for (size_t i = 0; i < errors.size(); ++i) n += errors[i] <= thresholds[i];
  return double(n) / errors.size();
}

DetectionAccuracy measure_detections(const std::string& detections, const std::string& data, const std::string& view,
                                     const std::vector<int>& only_frames) {
  const DatasetInfo info = read_dataset_info(data);
  const Character character = load_character(info.character);
  const std::string gt = (fs::path(data) / "gt" / "pose.motion").string();
  WEFT_CHECK(fs::exists(gt), gt, ": missing (the true keypoints come from the dataset's ground-truth pose)");
  const Motion motion = read_motion(gt, int(character.rest_dofs.size()));
  const std::string cameras_path = (fs::path(data) / "cameras.yaml").string();
  std::map<std::string, Camera> cameras;
  for (Camera& c : read_cameras_yaml(cameras_path)) cameras[c.name] = c;
  return measure_detections(detections, {info, character, motion, gt, cameras, cameras_path}, view, only_frames);
}

DetectionAccuracy measure_detections(const std::string& detections, const DetectionTruth& truth,
                                     const std::string& view, const std::vector<int>& only_frames) {
  const DatasetInfo& info = truth.info;
  const std::string& data = info.dir;
  WEFT_CHECK(std::find(info.views.begin(), info.views.end(), view) != info.views.end(), data, ": no view '", view,
             "' (dataset.yaml views)");
  std::vector<int> frames;
  for (const auto& [name, ids] : info.splits) frames.insert(frames.end(), ids.begin(), ids.end());
  std::sort(frames.begin(), frames.end());
  if (!only_frames.empty()) {
    for (int f : only_frames)
      WEFT_CHECK(std::binary_search(frames.begin(), frames.end(), f), data, ": no frame ", f, " in its splits");
    frames = only_frames;
    std::sort(frames.begin(), frames.end());
  }

  DetectionAccuracy a;
  a.data = data, a.view = view, a.detections = detections;
  for (int f : frames) {
    const std::string name = dataset_frame_name(f);
    const fs::path mask_path = fs::path(detections) / "masks" / (name + ".png");
    const fs::path kp_path = fs::path(detections) / "keypoints" / (name + "_keypoints.json");
    WEFT_CHECK(fs::exists(mask_path), mask_path.string(), ": missing (frame ", f, " of ", data, ")");
    const cv::Mat predicted_mask = cv::imread(mask_path.string(), cv::IMREAD_UNCHANGED);
    WEFT_CHECK(predicted_mask.type() == CV_8UC1, mask_path.string(), ": expected an 8-bit one-channel mask");
    const Body25 predicted = read_dataset_keypoints(kp_path.string());
    const cv::Mat truth_mask = read_dataset_mask(info, f, view);
    WEFT_CHECK(predicted_mask.size() == truth_mask.size(), mask_path.string(), ": ", predicted_mask.cols, "x",
               predicted_mask.rows, ", the dataset's masks are ", truth_mask.cols, "x", truth_mask.rows);
    a.frames.push_back(name);
    a.iou.push_back(mask_iou(predicted_mask, truth_mask));
    const double height = cv::boundingRect(truth_mask).height;
    const double threshold = a.pck_fraction * height;

    WEFT_CHECK(f < truth.motion.num_frames(), truth.motion_path, ": ", truth.motion.num_frames(),
               " frames, the dataset has frame ", f);
    const PosedCharacter posed = pose_character(truth.character, truth.motion.dofs.row(f).transpose());
    const Vertices& body25 = posed.body25;
    const auto cam = truth.cameras.find(dataset_camera_name(info, f, view));
    WEFT_CHECK(cam != truth.cameras.end(), truth.cameras_path, ": no camera '", dataset_camera_name(info, f, view), "'");
    const auto seen = keypoint_visibility(cam->second, body25, true_depth(truth, cam->second, f, posed.body),
                                          kOcclusionDepthToleranceM / info.metres_per_unit);
    const Body25 labels = read_dataset_keypoints(dataset_keypoints_path(info, f, view));
    for (int m = 0; m < kBody25Count; ++m) {
      if (body25.row(m).allFinite()) {
        const Eigen::Vector2d p = cam->second.project(body25.row(m).transpose());
        a.truth_error_px[m].push_back(keypoint_error(predicted, m, p.x(), p.y()));
        a.truth_threshold_px[m].push_back(threshold);
        a.truth_visible[m].push_back(seen[m] == KeypointVisibility::visible);
      }
      if (labels(m, 2) > 0) {
        a.label_error_px[m].push_back(keypoint_error(predicted, m, labels(m, 0), labels(m, 1)));
        a.label_threshold_px[m].push_back(threshold);
      }
    }
  }
  WEFT_CHECK(!a.frames.empty(), data, ": no frames in its splits");
  return a;
}

std::string detection_accuracy_json(const DetectionAccuracy& a) {
  nlohmann::json j;
  j["format"] = "weft-detection-accuracy/1";
  j["data"] = a.data;
  j["view"] = a.view;
  j["detections"] = a.detections;
  j["frames"] = a.frames.size();
  j["pck_fraction_of_height"] = a.pck_fraction;
  j["mask_iou"] = {{"median", number(median_of(a.iou))},
                   {"mean", number(std::accumulate(a.iou.begin(), a.iou.end(), 0.0) / a.iou.size())},
                   {"min", number(*std::min_element(a.iou.begin(), a.iou.end()))},
                   {"per_frame", a.iou}};
  auto summary = [&](const std::array<std::vector<double>, kBody25Count>& e,
                     const std::array<std::vector<double>, kBody25Count>& t) {
    nlohmann::json s;
    const auto all = pooled(e, [](int) { return true; });
    const auto thr = pooled(t, [](int) { return true; });
    size_t missed = 0;
    for (double v : all) missed += !std::isfinite(v);
    s["median_px"] = number(median_of(all));
    s["pck"] = number(fraction_within(all, thr));
    s["keypoints"] = all.size();
    s["undetected"] = missed;
    nlohmann::json per = nlohmann::json::object();
    for (int m = 0; m < kBody25Count; ++m)
      if (!e[m].empty())
        per[kBody25Names[m]] = {{"median_px", number(median_of(e[m]))},
                                {"pck", number(fraction_within(e[m], t[m]))},
                                {"count", e[m].size()}};
    s["per_keypoint"] = per;
    return s;
  };
  j["against_truth"] = summary(a.truth_error_px, a.truth_threshold_px);
  {
    const auto [errors, thresholds] = visible_errors(a);
    nlohmann::json v = {{"median_px", number(median_of(errors))},
                        {"pck", number(fraction_within(errors, thresholds))},
                        {"keypoints", errors.size()}};
    nlohmann::json per = nlohmann::json::object();
    for (int m = 0; m < kBody25Count; ++m) {
      const auto e = kept(a.truth_error_px[m], a.truth_visible[m]);
      if (!e.empty())
        per[kBody25Names[m]] = {{"median_px", number(median_of(e))},
                                {"pck", number(fraction_within(e, kept(a.truth_threshold_px[m], a.truth_visible[m])))},
                                {"count", e.size()}};
    }
    v["per_keypoint"] = per;
    j["against_truth"]["visible"] = v;
  }
  j["against_labels"] = summary(a.label_error_px, a.label_threshold_px);
  return j.dump(1) + "\n";
}

DetectionFigures detection_figures(const DetectionAccuracy& a) {
  const auto all = [](const std::array<std::vector<double>, kBody25Count>& per_joint) {
    return pooled(per_joint, [](int) { return true; });
  };
  DetectionFigures d;
  d.mask_iou_median = median_of(a.iou);
  d.mask_iou_min = a.iou.empty() ? kNaN : *std::min_element(a.iou.begin(), a.iou.end());
  const auto truth = all(a.truth_error_px), labels = all(a.label_error_px);
  d.truth_median_px = median_of(truth);
  d.truth_pck = fraction_within(truth, all(a.truth_threshold_px));
  d.label_median_px = median_of(labels);
  d.label_pck = fraction_within(labels, all(a.label_threshold_px));
  d.truth_keypoints = truth.size();
  const auto [visible, visible_thresholds] = visible_errors(a);
  d.visible_median_px = median_of(visible);
  d.visible_pck = fraction_within(visible, visible_thresholds);
  d.visible_keypoints = visible.size();
  return d;
}

std::vector<std::string> detection_summary_lines(const DetectionAccuracy& a) {
  std::vector<std::string> out;
  const DetectionFigures d = detection_figures(a);
  out.push_back(fmt::format("{} frames of {} ({}): mask IoU median {:.4f} (min {:.4f})", a.frames.size(), a.data, a.view,
                            d.mask_iou_median, d.mask_iou_min));
  out.push_back(fmt::format("keypoints against the truth: median {:.2f} px, PCK@{:.0f}% {:.1f} % ({} keypoints); "
                            "against the dataset's detections: median {:.2f} px, PCK {:.1f} %",
                            d.truth_median_px, 100 * a.pck_fraction, 100 * d.truth_pck, d.truth_keypoints,
                            d.label_median_px, 100 * d.label_pck));
  out.push_back(fmt::format("the true keypoints the camera sees (not hidden behind the body): median {:.2f} px, "
                            "PCK@{:.0f}% {:.1f} % ({} of {} keypoints)",
                            d.visible_median_px, 100 * a.pck_fraction, 100 * d.visible_pck, d.visible_keypoints,
                            d.truth_keypoints));
  return out;
}

std::vector<std::string> detection_accuracy_lines(const DetectionAccuracy& a) {
  std::vector<std::string> out = detection_summary_lines(a);
  out.push_back("keypoint        truth median px  PCK %   labels median px  PCK %   visible PCK %  (of)");
  for (int m = 0; m < kBody25Count; ++m) {
    if (a.truth_error_px[m].empty() && a.label_error_px[m].empty()) continue;
    const auto visible = kept(a.truth_error_px[m], a.truth_visible[m]);
    out.push_back(fmt::format("{:<14} {:>16.2f} {:>6.1f} {:>18.2f} {:>6.1f} {:>15.1f} {:>5}", kBody25Names[m],
                              median_of(a.truth_error_px[m]),
                              100 * fraction_within(a.truth_error_px[m], a.truth_threshold_px[m]),
                              median_of(a.label_error_px[m]),
                              100 * fraction_within(a.label_error_px[m], a.label_threshold_px[m]),
                              100 * fraction_within(visible, kept(a.truth_threshold_px[m], a.truth_visible[m])),
                              visible.size()));
  }
  return out;
}

}  // namespace weft::capture
