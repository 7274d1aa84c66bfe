#include "capture/evaluation/evaluation_report.h"

#include <fmt/format.h>

#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "capture/plots/svg_line_plot.h"
#include "graph/atomic_file.h"
#include "capture/io/png_file.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string overlay_file(const EvaluationOverlay& o) { return fmt::format("overlay_{}_{:04d}.png", o.label, o.id); }

// One per-frame value of every frame (NaN → null in JSON).
template <class Get>
std::vector<double> column(const CaptureEvaluation& e, Get get) {
  std::vector<double> v;
  for (const FrameEvaluation& f : e.frames) v.push_back(get(f));
  return v;
}
std::vector<double> column(const CaptureEvaluation& e, double FrameMeasures::*metric) {
  return column(e, [&](const FrameEvaluation& f) { return f.measures.*metric; });
}

json distribution_json(const Distribution& d) {
  return {{"mean", d.mean}, {"p95", d.p95}, {"p99", d.p99}, {"max", d.max}, {"count", d.count}};
}

// A number for the tables ("—" when not measured).
std::string num(double v, int decimals) { return std::isfinite(v) ? fmt::format("{:.{}f}", v, decimals) : "—"; }
std::string sci(double v) { return std::isfinite(v) ? fmt::format("{:.4g}", v) : "—"; }

// The frames in three groups by their distance to the nearest training pose (nearest
// third first): that distance, the capture's root-relative MPJPE and PA-MPJPE, and the 2D
// retrieval's root-relative error, means per group.
struct DistanceGroup {
  int frames = 0;
  double nearest_pose_pa_mm = 0, mpjpe_root_relative_mm = 0, pa_mpjpe_mm = 0, nearest_2d_root_relative_mm = 0;
};
std::vector<DistanceGroup> groups_by_training_distance(const CaptureEvaluation& e) {
  if (!e.training_set || e.training_set->frames.size() != e.frames.size() || e.frames.size() < 3) return {};
  const std::vector<TrainingSetFrame>& t = e.training_set->frames;
  std::vector<size_t> order(t.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return t[a].nearest_pose_pa_mm < t[b].nearest_pose_pa_mm; });
  std::vector<DistanceGroup> groups;
  for (int g = 0; g < 3; ++g) {
    const size_t first = order.size() * g / 3, last = order.size() * (g + 1) / 3;
    MeasuredMean d, rr, pa, ret;
    for (size_t k = first; k < last; ++k) {
      const size_t i = order[k];
      d.add(t[i].nearest_pose_pa_mm), rr.add(e.frames[i].measures.mpjpe_root_relative_mm);
      pa.add(e.frames[i].measures.pa_mpjpe_mm), ret.add(t[i].nearest_2d_root_relative_mm);
    }
    groups.push_back({int(last - first), d.value(), rr.value(), pa.value(), ret.value()});
  }
  return groups;
}

}  // namespace

std::string CaptureEvaluation::to_json() const {
  json j;
  j["format"] = "weft-eval/1";
  j["prediction"] = options.prediction;
  j["data"] = options.data;
  j["view"] = view;
  j["views"] = views;
  j["character"] = character;
  j["synth_config"] = synth_config;
  j["gt_translation"] = options.gt_translation;
  j["iou_every"] = options.iou_every;
  j["metres_per_unit"] = metres_per_unit;
  j["fps"] = fps;
  j["seconds"] = seconds;
  j["notes"] = notes;
  json& s = j["summary"];
  s["frames"] = frames.size();
  // The means and maxima (the paper's figures) first, then the distribution pooled over vertices.
  const auto oob = [](const Distribution& n, const Distribution& rel) {
    return json{{"mean_n", n.mean}, {"max_n", n.max}, {"mean_rel", rel.mean}, {"max_rel", rel.max},
                {"p95_n", n.p95}, {"p99_n", n.p99}, {"vertices", n.count}};
  };
  s["out_of_balance_force"] = oob(oob_n, oob_rel);
  s["out_of_balance_force"]["frames"] = oob_frames;
  s["out_of_balance_force"]["outside_body_n"] = distribution_json(oob_outside_n);
  s["out_of_balance_force"]["terms_mean_n"] = {{"inertia", inertia_mean_n},
                                               {"elastic", elastic_mean_n},
                                               {"collision", collision_mean_n},
                                               {"friction", friction_mean_n}};
  s["out_of_balance_force"]["ground_truth"] = oob(gt_oob_n, gt_oob_rel);
  s["out_of_balance_force"]["ground_truth"]["frames"] = gt_oob_frames;
  s["out_of_balance_force_all_vertices"] = oob(oob_all_n, oob_all_rel);
  s["out_of_balance_force_all_vertices"]["ground_truth"] = oob(gt_oob_all_n, gt_oob_all_rel);
  s["penetration"] = {{"mean_cm", penetration_mean_mm / 10},
                      {"mean_mm", penetration_mean_mm},
                      {"mean_all_mm", penetration_mean_all_mm},
                      {"max_mm", penetration_max_mm},
                      {"fraction_inside", penetrating_fraction},
                      {"ground_truth",
                       {{"mean_cm", gt_penetration_mean_mm / 10},
                        {"mean_mm", gt_penetration_mean_mm},
                        {"max_mm", gt_penetration_max_mm},
                        {"fraction_inside", gt_penetrating_fraction}}}};
  s["iou"] = {{"frames", iou_frames}, {"amv", amv_iou}, {"rv", rv_iou}, {"sv", sv_iou}};
  s["cloth_error_mm"] = {{"mean", cloth_error_mean_mm}, {"p95", cloth_error_p95_mm}};
  s["body_error_mm"] = {{"mean", body_error_mean_mm}, {"p95", body_error_p95_mm}};
  s["cloth_chamfer_mm"] = cloth_chamfer_mm;
  s["mpjpe_mm"] = mpjpe_mm;
  s["mpjpe_root_relative_mm"] = mpjpe_root_relative_mm;
  s["pa_mpjpe_mm"] = pa_mpjpe_mm;
  s["mpjpe_root_relative_split_mm"] = {{"depth", mpjpe_depth_mm}, {"image_plane", mpjpe_image_plane_mm}};
  json joints = json::array();
  for (size_t j = 0; j < joint_error_root_relative_mm.size(); ++j)
    joints.push_back({{"keypoint", j < kBody25Names.size() ? kBody25Names[j] : "?"},
                      {"root_relative_mm", joint_error_root_relative_mm[j]},
                      {"pa_mm", j < joint_error_pa_mm.size() ? joint_error_pa_mm[j] : kNotMeasured}});
  s["per_joint"] = joints;
  s["pivot_error_mm"] = pivot_error_mm;
  s["root_rotation_deg"] = {{"median", root_rotation_median_deg},
                            {"p95", root_rotation_p95_deg},
                            {"fraction_above_45", root_rotation_above_45}};
  s["root_heading_deg"] = {{"median", root_heading_median_deg},
                           {"p95", root_heading_p95_deg},
                           {"fraction_above_45", root_heading_above_45}};
  s["root_tilt_deg"] = {{"median", root_tilt_median_deg}, {"p95", root_tilt_p95_deg}};
  s["trunk_direction_deg"] = {{"median", trunk_direction_median_deg}, {"p95", trunk_direction_p95_deg}};
  json& p = j["per_frame"];
  std::vector<int> ids;
  json shifts = json::array(), ious = json::array();
  for (const FrameEvaluation& f : frames) {
    ids.push_back(f.id);
    shifts.push_back({f.shift.x(), f.shift.y(), f.shift.z()});
    ious.push_back(f.iou.empty() ? json(nullptr) : json(f.iou));
  }
  p["id"] = ids;
  p["shift"] = shifts;
  for (const FrameMetric& m : frame_metrics()) p[m.name] = column(*this, m.value);
  p["penetrating_vertices"] = column(*this, [](const auto& f) { return double(f.measures.penetrating_vertices); });
  p["gt_penetration_mean_mm"] = column(*this, [](const auto& f) { return f.ground_truth.penetration_mean_mm; });
  p["gt_penetration_max_mm"] = column(*this, [](const auto& f) { return f.ground_truth.penetration_max_mm; });
  p["gt_oob_force_mean_n"] = column(*this, [](const auto& f) { return f.ground_truth.oob_force_mean_n; });
  p["gt_oob_force_max_n"] = column(*this, [](const auto& f) { return f.ground_truth.oob_force_max_n; });
  p["iou_per_view"] = ious;
  json ov = json::array();
  for (const EvaluationOverlay& o : overlays)
    ov.push_back({{"label", o.label}, {"id", o.id}, {"ranked_by", o.ranked_by}, {"file", overlay_file(o)}});
  j["overlays"] = ov;
  if (detections) j["detections"] = json::parse(detection_accuracy_json(*detections));
  if (training_set) {
    const TrainingSetComparison& t = *training_set;
    json& c = j["training_set"];
    c["data"] = t.data, c["split"] = t.split, c["frames"] = t.training_frames, c["views"] = t.training_views;
    c["summary"] = {{"nearest_pose_pa_mm", t.nearest_pose_pa_mm},
                    {"mean_pose_root_relative_mm", t.mean_pose_root_relative_mm},
                    {"mean_pose_pa_mm", t.mean_pose_pa_mm},
                    {"nearest_2d_root_relative_mm", t.nearest_2d_root_relative_mm},
                    {"nearest_2d_pa_mm", t.nearest_2d_pa_mm}};
    json groups = json::array();
    for (const DistanceGroup& g : groups_by_training_distance(*this))
      groups.push_back({{"frames", g.frames},
                        {"nearest_pose_pa_mm", g.nearest_pose_pa_mm},
                        {"mpjpe_root_relative_mm", g.mpjpe_root_relative_mm},
                        {"pa_mpjpe_mm", g.pa_mpjpe_mm},
                        {"nearest_2d_root_relative_mm", g.nearest_2d_root_relative_mm}});
    c["by_distance_third"] = groups;
    json& pf = c["per_frame"];
    std::vector<double> nearest, mean_rr, mean_pa, ret_rr, ret_pa;
    std::vector<int> nearest_frame, ret_frame;
    std::vector<std::string> ret_view;
    for (const TrainingSetFrame& f : t.frames) {
      nearest.push_back(f.nearest_pose_pa_mm), nearest_frame.push_back(f.nearest_pose_frame);
      mean_rr.push_back(f.mean_pose_root_relative_mm), mean_pa.push_back(f.mean_pose_pa_mm);
      ret_rr.push_back(f.nearest_2d_root_relative_mm), ret_pa.push_back(f.nearest_2d_pa_mm);
      ret_frame.push_back(f.nearest_2d_frame), ret_view.push_back(f.nearest_2d_view);
    }
    const auto nulls = [](const std::vector<double>& v) {
      json a = json::array();
      for (double x : v) a.push_back(std::isfinite(x) ? json(x) : json(nullptr));
      return a;
    };
    pf["nearest_pose_pa_mm"] = nulls(nearest), pf["nearest_pose_frame"] = nearest_frame;
    pf["mean_pose_root_relative_mm"] = nulls(mean_rr), pf["mean_pose_pa_mm"] = nulls(mean_pa);
    pf["nearest_2d_root_relative_mm"] = nulls(ret_rr), pf["nearest_2d_pa_mm"] = nulls(ret_pa);
    pf["nearest_2d_frame"] = ret_frame, pf["nearest_2d_view"] = ret_view;
  }
  return j.dump(1) + "\n";
}

namespace {

// joints.csv: per frame and mapped BODY_25 keypoint, the prediction's position as measured
// and the ground truth's, world metres: what any further joint measure needs.
std::string joints_csv(const CaptureEvaluation& e) {
  std::string out = "frame,keypoint,predicted_x_m,predicted_y_m,predicted_z_m,true_x_m,true_y_m,true_z_m\n";
  for (const FrameEvaluation& f : e.frames)
    for (int k = 0; k < int(f.true_body25.rows()) && k < int(f.predicted_body25.rows()); ++k) {
      if (!f.true_body25.row(k).allFinite() || !f.predicted_body25.row(k).allFinite()) continue;
      const Eigen::RowVector3d p = f.predicted_body25.row(k) * e.metres_per_unit,
                               t = f.true_body25.row(k) * e.metres_per_unit;
      out += fmt::format("{},{},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f},{:.6f}\n", f.id, kBody25Names[k], p.x(), p.y(), p.z(),
                         t.x(), t.y(), t.z());
    }
  return out;
}

}  // namespace

std::vector<std::string> write_evaluation_report(const CaptureEvaluation& e, const std::string& dir) {
  fs::create_directories(dir);
  // Overlays of an earlier report in this folder would be left beside this one's.
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    const bool current = std::any_of(e.overlays.begin(), e.overlays.end(),
                                     [&](const EvaluationOverlay& o) { return overlay_file(o) == name; });
    if (name.rfind("overlay_", 0) == 0 && entry.path().extension() == ".png" && !current) fs::remove(entry.path());
  }
  std::vector<std::string> written;
  const auto write_text = [&](const std::string& name, const std::string& text) {
    const std::string path = (fs::path(dir) / name).string();
    write_text_atomically(path, text);
    written.push_back(path);
  };
  for (const EvaluationOverlay& o : e.overlays) {
    const std::string path = (fs::path(dir) / overlay_file(o)).string();
    write_png_atomically(path, o.image);
    written.push_back(path);
  }
  write_text("metrics.json", e.to_json());
  write_text("joints.csv", joints_csv(e));

  std::vector<int> ids;
  for (const FrameEvaluation& f : e.frames) ids.push_back(f.id);
  const auto col = [&](auto get) { return column(e, get); };
  std::string h;
  h += "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>weft eval: " + html_escape(e.options.prediction) +
       "</title>\n<style>body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em}"
       "table{border-collapse:collapse;margin:.5em 0}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
       "th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}.note{color:#a40}"
       "img{max-width:100%;border:1px solid #ccc}code{background:#f5f5f5}</style></head><body>\n";
  h += "<h1>weft eval</h1>\n<p>prediction <code>" + html_escape(e.options.prediction) + "</code><br>data <code>" +
       html_escape(e.options.data) + "</code><br>input view <b>" + html_escape(e.view) + "</b> of " +
       std::to_string(e.views.size()) + " views; " + std::to_string(e.frames.size()) + " captured frames; " +
       (e.options.gt_translation ? "<b>ground-truth global translation applied</b> (--gt-translation)"
                                 : "predicted global translation") +
       (e.options.iou_every == 1 ? std::string("; IoU on every frame")
                                 : fmt::format("; IoU on one frame in {}", e.options.iou_every)) +
       "; cloth material from " +
       (e.synth_config.empty() ? std::string("— (none)") : "<code>" + html_escape(e.synth_config) + "</code>") +
       fmt::format("; {:.1f} s.</p>\n", e.seconds);
  for (const std::string& n : e.notes) h += "<p class=\"note\">" + html_escape(n) + "</p>\n";

  h += "<h2>Summary</h2>\n<table><tr><th>metric</th><th>prediction</th><th>ground truth (same measure)</th>"
       "<th>unit</th></tr>\n";
  const auto row = [&](const std::string& name, const std::string& pred, const std::string& gt,
                       const std::string& unit) {
    h += "<tr><td>" + name + "</td><td>" + pred + "</td><td>" + gt + "</td><td>" + unit + "</td></tr>\n";
  };
  row(fmt::format("out-of-balance force (vertices the attachment does not hold), mean (over {} frame{})", e.oob_frames,
                 e.oob_frames == 1 ? "" : "s"), sci(e.oob_n.mean), sci(e.gt_oob_n.mean), "N");
  row("out-of-balance force, max", sci(e.oob_n.max), sci(e.gt_oob_n.max), "N");
  row("out-of-balance force, mean, relative", sci(e.oob_rel.mean), sci(e.gt_oob_rel.mean), "× vertex weight");
  row("out-of-balance force, max, relative", sci(e.oob_rel.max), sci(e.gt_oob_rel.max), "× vertex weight");
  row("out-of-balance force over all vertices (anchors pinned where predicted), mean", sci(e.oob_all_n.mean),
      sci(e.gt_oob_all_n.mean), "N");
  row("out-of-balance force over all vertices, max", sci(e.oob_all_n.max), sci(e.gt_oob_all_n.max), "N");
  row("out-of-balance force over all vertices, mean, relative", sci(e.oob_all_rel.mean), sci(e.gt_oob_all_rel.mean),
      "× vertex weight");
  row("penetration depth, mean over penetrating vertices", num(e.penetration_mean_mm / 10, 3),
      num(e.gt_penetration_mean_mm / 10, 3), "cm");
  row("penetration depth, max", num(e.penetration_max_mm, 2), num(e.gt_penetration_max_mm, 2), "mm");
  row("cloth vertices inside the body", num(100 * e.penetrating_fraction, 2), num(100 * e.gt_penetrating_fraction, 2),
      "%");
  row(fmt::format("AMVIoU (all views, over {} frame{})", e.iou_frames, e.iou_frames == 1 ? "" : "s"),
      num(e.amv_iou, 4), "", "");
  row("RVIoU (all but the input view)", num(e.rv_iou, 4), "", "");
  row("SVIoU (the input view)", num(e.sv_iou, 4), "", "");
  row("cloth vertex error, mean", num(e.cloth_error_mean_mm, 2), "", "mm");
  row("cloth vertex error, 95th percentile", num(e.cloth_error_p95_mm, 2), "", "mm");
  row("body vertex error, mean", num(e.body_error_mean_mm, 2), "", "mm");
  row("body vertex error, 95th percentile", num(e.body_error_p95_mm, 2), "", "mm");
  row("cloth Chamfer distance", num(e.cloth_chamfer_mm, 2), "", "mm");
  row("MPJPE (mapped BODY_25 joints)", num(e.mpjpe_mm, 2), "", "mm");
  row("MPJPE, root-relative", num(e.mpjpe_root_relative_mm, 2), "", "mm");
  row("PA-MPJPE (after a similarity Procrustes alignment)", num(e.pa_mpjpe_mm, 2), "", "mm");
  row("root-relative joint error along the input camera's axis (depth), mean size", num(e.mpjpe_depth_mm, 2), "",
      "mm");
  row("root-relative joint error across it (image plane), mean size", num(e.mpjpe_image_plane_mm, 2), "", "mm");
  row("root rotation error, median", num(e.root_rotation_median_deg, 2), "", "°");
  row("root rotation error, 95th percentile", num(e.root_rotation_p95_deg, 2), "", "°");
  row("frames with the root rotation off by more than 45°", num(100 * e.root_rotation_above_45, 2), "", "%");
  row("heading error (the turn about the vertical), median", num(e.root_heading_median_deg, 2), "", "°");
  row("frames with the heading off by more than 45° (front/back)", num(100 * e.root_heading_above_45, 2), "", "%");
  row("tilt error (the pelvis's pitch and roll), median", num(e.root_tilt_median_deg, 2), "", "°");
  row("trunk direction error (MidHip → Neck), median", num(e.trunk_direction_median_deg, 2), "", "°");
  row("global translation error (pivot joint, before any shift)", num(e.pivot_error_mm, 2), "", "mm");
  h += "</table>\n<p>Definitions: docs/EVALUATION.md. The ground-truth column measures the dataset's own meshes "
       "the same way: the floor the data allows.</p>\n";

  if (e.detections) {
    const DetectionFigures d = detection_figures(*e.detections);
    h += "<h2>The capture's inputs: the person detector</h2>\n<p>The capture read the model's own keypoints and "
         "masks (from the pixels alone: <code>" + html_escape(e.detections->detections) +
         "</code>); measured here against the dataset on the captured frames (PCK: within " +
         num(100 * e.detections->pck_fraction, 0) + " % of the person's height). The overlays below show them on the "
         "left.</p>\n<table><tr><th>measure</th><th>value</th><th>unit</th></tr>\n";
    const auto drow = [&](const std::string& name, const std::string& v, const std::string& unit) {
      h += "<tr><td>" + name + "</td><td>" + v + "</td><td>" + unit + "</td></tr>\n";
    };
    drow("mask IoU against the true mask, median", num(d.mask_iou_median, 4), "");
    drow("mask IoU, worst frame", num(d.mask_iou_min, 4), "");
    drow(fmt::format("keypoint error against the true keypoints, median ({} keypoints)", d.truth_keypoints),
         num(d.truth_median_px, 2), "px");
    drow("keypoints within the PCK threshold of the truth", num(100 * d.truth_pck, 1), "%");
    drow(fmt::format("the same over the keypoints the camera sees, not hidden behind the body ({} keypoints)",
                     d.visible_keypoints),
         num(100 * d.visible_pck, 1), "%");
    drow("keypoint error against the dataset's own detections, median", num(d.label_median_px, 2), "px");
    h += "</table>\n";
  }

  h += "<h2>Per frame</h2>\n";
  h += svg_line_plot("3D vertex error", "mm",
                     ids, {{"cloth mean", col([](const auto& f) { return f.measures.cloth_error_mean_mm; }), "#d62728"},
                           {"cloth p95", col([](const auto& f) { return f.measures.cloth_error_p95_mm; }), "#ff9896"},
                           {"body mean", col([](const auto& f) { return f.measures.body_error_mean_mm; }), "#1f77b4"},
                           {"body p95", col([](const auto& f) { return f.measures.body_error_p95_mm; }), "#aec7e8"}});
  h += svg_line_plot("Joint and global translation error", "mm", ids,
                     {{"MPJPE", col([](const auto& f) { return f.measures.mpjpe_mm; }), "#2ca02c"},
                      {"pivot", col([](const auto& f) { return f.measures.pivot_error_mm; }), "#9467bd"}});
  h += svg_line_plot("Root-relative joint error and its parts", "mm", ids,
                     {{"root-relative", col([](const auto& f) { return f.measures.mpjpe_root_relative_mm; }), "#2ca02c"},
                      {"PA-MPJPE", col([](const auto& f) { return f.measures.pa_mpjpe_mm; }), "#17becf"},
                      {"depth (input camera)", col([](const auto& f) { return f.measures.mpjpe_depth_mm; }), "#d62728"},
                      {"image plane", col([](const auto& f) { return f.measures.mpjpe_image_plane_mm; }), "#ff7f0e"}});
  h += svg_line_plot("Penetration depth", "mm", ids,
                     {{"mean", col([](const auto& f) { return f.measures.penetration_mean_mm; }), "#d62728"},
                      {"max", col([](const auto& f) { return f.measures.penetration_max_mm; }), "#ff7f0e"},
                      {"ground truth max", col([](const auto& f) { return f.ground_truth.penetration_max_mm; }), "#7f7f7f"}});
  h += svg_line_plot("Out-of-balance force", "N", ids,
                     {{"mean", col([](const auto& f) { return f.measures.oob_force_mean_n; }), "#1f77b4"},
                      {"max", col([](const auto& f) { return f.measures.oob_force_max_n; }), "#ff7f0e"},
                      {"ground truth max", col([](const auto& f) { return f.ground_truth.oob_force_max_n; }), "#7f7f7f"}});
  h += svg_line_plot("Out-of-balance force relative to a vertex's weight", "× m g", ids,
                     {{"mean", col([](const auto& f) { return f.measures.oob_force_mean_rel; }), "#1f77b4"},
                      {"max", col([](const auto& f) { return f.measures.oob_force_max_rel; }), "#ff7f0e"}});
  h += svg_line_plot("Silhouette IoU", "IoU", ids,
                     {{"AMV", col([](const auto& f) { return f.measures.amv_iou; }), "#2ca02c", true},
                      {"RV", col([](const auto& f) { return f.measures.rv_iou; }), "#17becf", true},
                      {"SV", col([](const auto& f) { return f.measures.sv_iou; }), "#bcbd22", true}});

  if (!e.joint_error_root_relative_mm.empty()) {
    h += "<h2>Per joint</h2>\n<p>Mean over frames of each BODY_25 keypoint's error (— unmapped in the "
         "skeleton).</p>\n<table><tr><th>keypoint</th><th>root-relative mm</th><th>PA mm</th></tr>\n";
    for (size_t j = 0; j < e.joint_error_root_relative_mm.size(); ++j)
      h += fmt::format("<tr><td>{} {}</td><td>{}</td><td>{}</td></tr>\n", j,
                       j < kBody25Names.size() ? kBody25Names[j] : "?", num(e.joint_error_root_relative_mm[j], 1),
                       num(j < e.joint_error_pa_mm.size() ? e.joint_error_pa_mm[j] : kNotMeasured, 1));
    h += "</table>\n";
  }
  if (e.training_set) {
    const TrainingSetComparison& t = *e.training_set;
    h += fmt::format("<h2>Against the training set</h2>\n<p><code>{}</code>, split '{}': {} frames × {} views. "
                     "Definitions: docs/EVALUATION.md.</p>\n",
                     html_escape(t.data), html_escape(t.split), t.training_frames, t.training_views);
    h += "<table><tr><th>pose</th><th>root-relative MPJPE mm</th><th>PA-MPJPE mm</th></tr>\n";
    h += fmt::format("<tr><td>this capture</td><td>{}</td><td>{}</td></tr>\n", num(e.mpjpe_root_relative_mm, 1),
                     num(e.pa_mpjpe_mm, 1));
    h += fmt::format("<tr><td>the mean training pose (true heading)</td><td>{}</td><td>{}</td></tr>\n",
                     num(t.mean_pose_root_relative_mm, 1), num(t.mean_pose_pa_mm, 1));
    h += fmt::format("<tr><td>the training pose nearest in 2D (input view's keypoints)</td><td>{}</td><td>{}</td></tr>\n",
                     num(t.nearest_2d_root_relative_mm, 1), num(t.nearest_2d_pa_mm, 1));
    h += fmt::format("<tr><td>the nearest training pose in 3D (the data's floor)</td><td>—</td><td>{}</td></tr>\n",
                     num(t.nearest_pose_pa_mm, 1));
    h += "</table>\n<p>The frames by their distance to the nearest training pose, in thirds:</p>\n<table><tr>"
         "<th>third</th><th>frames</th><th>nearest training pose, PA mm</th><th>capture root-relative mm</th>"
         "<th>capture PA mm</th><th>2D retrieval root-relative mm</th></tr>\n";
    const std::vector<DistanceGroup> groups = groups_by_training_distance(e);
    for (size_t g = 0; g < groups.size(); ++g)
      h += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
                       g == 0 ? "nearest" : g == 1 ? "middle" : "farthest", groups[g].frames,
                       num(groups[g].nearest_pose_pa_mm, 1), num(groups[g].mpjpe_root_relative_mm, 1),
                       num(groups[g].pa_mpjpe_mm, 1), num(groups[g].nearest_2d_root_relative_mm, 1));
    h += "</table>\n";
    const auto tcol = [&](double TrainingSetFrame::*v) {
      std::vector<double> out;
      for (const TrainingSetFrame& f : t.frames) out.push_back(f.*v);
      return out;
    };
    h += svg_line_plot("Root-relative MPJPE against the baselines", "mm", ids,
                       {{"capture", col([](const auto& f) { return f.measures.mpjpe_root_relative_mm; }), "#2ca02c"},
                        {"2D retrieval", tcol(&TrainingSetFrame::nearest_2d_root_relative_mm), "#9467bd"},
                        {"mean training pose", tcol(&TrainingSetFrame::mean_pose_root_relative_mm), "#7f7f7f"},
                        {"nearest training pose (PA)", tcol(&TrainingSetFrame::nearest_pose_pa_mm), "#d62728"}});
  }

  h += std::string("<h2>Overlays</h2>\n<p>") +
       (e.detections ? "The detector's mask (orange outline) and keypoints (green, by BODY_25 index) that the capture "
                       "read (left), the input view with the prediction drawn on it (middle"
                     : "The input view with the prediction drawn on it (left") +
       "; body blue, cloth orange, outline white) beside the ground truth drawn the same way (right).</p>\n";
  for (const EvaluationOverlay& o : e.overlays)
    h += "<h3>" + html_escape(o.label) + " frame " + std::to_string(o.id) + " (" + html_escape(o.ranked_by) +
         ")</h3>\n<img src=\"" + overlay_file(o) + "\" alt=\"" + html_escape(o.label) + " frame\">\n";

  h += "<h2>Per-frame table</h2>\n<table><tr><th>frame</th><th>cloth mm</th><th>body mm</th><th>MPJPE mm</th>"
       "<th>pivot mm</th><th>pen. mean mm</th><th>pen. max mm</th><th>OOB mean N</th><th>OOB max N</th>"
       "<th>AMVIoU</th><th>RVIoU</th><th>SVIoU</th></tr>\n";
  for (const FrameEvaluation& f : e.frames)
    h += fmt::format(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td>"
        "<td>{}</td><td>{}</td><td>{}</td></tr>\n",
        f.id, num(f.measures.cloth_error_mean_mm, 2), num(f.measures.body_error_mean_mm, 2), num(f.measures.mpjpe_mm, 2), num(f.measures.pivot_error_mm, 2),
        num(f.measures.penetration_mean_mm, 3), num(f.measures.penetration_max_mm, 3), sci(f.measures.oob_force_mean_n), sci(f.measures.oob_force_max_n),
        num(f.measures.amv_iou, 4), num(f.measures.rv_iou, 4), num(f.measures.sv_iou, 4));
  h += "</table>\n<p>All numbers: <a href=\"metrics.json\">metrics.json</a>; the keypoints per frame, predicted and true: <a href=\"joints.csv\">joints.csv</a>.</p>\n</body></html>\n";
  write_text("report.html", h);
  return written;
}

}  // namespace weft::capture
