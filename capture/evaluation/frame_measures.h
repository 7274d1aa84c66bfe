#pragma once
// The per-frame measures of a predicted body and garment (character units in, the units
// named in each result out), each on plain Eigen meshes so that they apply to any
// method's output. Both evaluations, `weft eval` (capture_evaluation.h) and `weft train
// --evaluate` (training/split_evaluation.h), measure a frame with measure_geometry,
// measure_balance and measure_ious into one FrameMeasures, whose fields frame_metrics()
// lists by name, unit and meaning: a new metric is a field, its line in that table and
// its computation here, and tests/capture/frame_metrics_test.cpp fails until it has a
// known-answer case. The measures:
// - vertex distance to the ground truth (mm) and the joint error over the mapped BODY_25
//   keypoints (MPJPE, mm);
// - penetration of the free cloth vertices into the body's active faces (those the
//   simulator collides with; capture/garment/garment_simulator.h body_obstacle); the
//   anchors are left out, as in the force: they are tied to the body's surface, so half of
//   them lie a fraction of a millimetre inside it whatever the garment does;
// - out-of-balance force m·a − (f_int + f_ext + f_coll) of the newest of three
//   consecutive frames (physics/cloth_metrics.h), a from their centred difference, with
//   the garment simulator of a synth config's simulation section: the predicted body of
//   the two newest frames as the moving obstacle, over the vertices not held by the
//   attachment (the anchors, e.g. the waistband) and over all;
// - silhouette IoU of the rendered body + cloth against a mask per view.
#include <opencv2/core.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "capture/character/character.h"
#include "capture/io/camera.h"
#include "capture/garment/garment_config.h"
#include "capture/garment/garment_windows.h"
#include "physics/cloth_metrics.h"

namespace weft::capture {

// "Not measured", in every evaluation: NaN in memory, null in JSON.
inline constexpr double kNotMeasured = std::numeric_limits<double>::quiet_NaN();
// A free cloth vertex outside the body but closer than this counts as in contact (m): the
// simulator's default collision thickness (garment_config.h).
inline constexpr double kContactDistanceM = 0.004;

// ‖a_i − b_i‖ per row, in mm (rows of a and b correspond; character units × metres_per_unit).
std::vector<double> vertex_distances_mm(const Vertices& a, const Vertices& b, double metres_per_unit);

// The q-quantile (q in [0, 1]) with linear interpolation between order statistics
// (NumPy's default); NaN for no values.
double quantile(std::vector<double> values, double q);

// Mean distance (mm) over the BODY_25 rows finite in both (unmapped keypoints are NaN);
// NaN when none is.
double mean_joint_error_mm(const Vertices& predicted_body25, const Vertices& true_body25, double metres_per_unit);

// The garment's vertices not held by the attachment (its anchors), in order.
Vertices free_cloth_vertices(const Character& character, const Vertices& cloth);
// Cloth vertices inside the body (depths in metres).
Penetration cloth_penetration(const Character& character, const Vertices& body, const Vertices& cloth);
// Signed distance (mm) of each cloth vertex to the body's active faces: < 0 inside.
std::vector<double> cloth_signed_distances_mm(const Character& character, const Vertices& body,
                                              const Vertices& cloth);

// The distance (mm) of each BODY_25 row (NaN where either row is not finite).
std::vector<double> joint_distances_mm(const Vertices& predicted_body25, const Vertices& true_body25,
                                       double metres_per_unit);

// The prediction aligned to the truth by the similarity (scale, rotation, translation)
// that minimises the squared distance over the rows finite in both (Umeyama 1991, Eigen's
// umeyama): the alignment of PA-MPJPE. Rows not finite in both stay NaN; fewer than three
// such rows give all NaN.
Vertices procrustes_aligned(const Vertices& predicted, const Vertices& truth);

// Root-relative joint errors (pred_i − pred_pivot) − (true_i − true_pivot) seen from a camera
// of world → camera rotation R: the mean size of their component along the camera's axis
// (depth) and across it (image plane), mm, over the rows finite in both.
struct ViewErrorSplit {
  double depth_mm = kNotMeasured;
  double image_plane_mm = kNotMeasured;
};
ViewErrorSplit view_error_split(const Vertices& predicted_root_relative, const Vertices& true_root_relative,
                                const Eigen::Matrix3d& world_to_camera, double metres_per_unit);

// The twist about the world's vertical (+y) of a rotation: its heading alone.
Eigen::Matrix3d heading_rotation(const Eigen::Matrix3d& rotation);

// The geodesic angle (degrees, 0..180) between two rotations: the root orientation's error.
double rotation_error_deg(const Eigen::Matrix3d& predicted, const Eigen::Matrix3d& truth);

// The heading error (degrees, 0..180): the twist about the world's vertical (+y) of
// predicted · truthᵀ, the turn that takes the true orientation to the predicted one. A
// rotation about the vertical counts whole, a tilt about a horizontal axis not at all: the
// front/back confusion (180°) without the pelvis's pitch, which keypoints leave open (the
// spine and hips above and below it can make up for it).
double heading_error_deg(const Eigen::Matrix3d& predicted, const Eigen::Matrix3d& truth);

// The tilt error (degrees, 0..180): the swing of predicted · truthᵀ, what is left of the
// rotation error once its twist about the vertical (the heading error) is taken out: the
// pelvis's pitch and roll. A rotation about the vertical counts not at all, a tilt about a
// horizontal axis whole.
double tilt_error_deg(const Eigen::Matrix3d& predicted, const Eigen::Matrix3d& truth);

// The trunk direction error (degrees, 0..180): the angle between the predicted and the
// true direction from BODY_25's MidHip (8) to its Neck (1), which 3D keypoints determine
// whatever the pelvis and the lumbar spine share of a lean (one view's 2D keypoints: across
// the image only). NaN when either keypoint is not mapped in either skeleton (rows with
// NaN, or fewer than 9 rows).
double trunk_direction_error_deg(const Vertices& predicted_body25, const Vertices& true_body25);

// Root orientation errors over predictions: the median, the 95th percentile and the
// fraction above 45° (front/back and side confusions); NaN for none.
struct RotationErrorSummary {
  double median_deg = kNotMeasured, p95_deg = kNotMeasured, above_45 = kNotMeasured;
};
RotationErrorSummary summarize_rotation_errors(const std::vector<double>& errors_deg);

// Symmetric Chamfer distance (mm) of two meshes with the same faces F (a prediction and
// its ground truth): the mean distance of a's vertices to b's surface and of b's vertices
// to a's, averaged. Unlike the per-vertex error it does not count a garment that slid
// along its own surface (a near-symmetric skirt turned by a few degrees) as wrong.
double chamfer_distance_mm(const Vertices& a, const Vertices& b, const Faces& F, double metres_per_unit);

// A running mean of measured values: non-finite values (not measured) are left out, and
// the mean of none is kNotMeasured. count weighs a value (e.g. a mean over count items).
struct MeasuredMean {
  double sum = 0;
  int64_t n = 0;
  void add(double x, int64_t count = 1) {
    if (std::isfinite(x)) sum += x * count, n += count;
  }
  double value() const { return n ? sum / n : kNotMeasured; }
};

// Mean, 95th and 99th percentile (quantile()) and max of pooled values; NaN for none.
struct Distribution {
  double mean = kNotMeasured, p95 = kNotMeasured, p99 = kNotMeasured, max = kNotMeasured;
  int64_t count = 0;
};
Distribution distribution(const std::vector<double>& values);

// Out-of-balance force of frame t given frames t − 2 and t − 1, 1/fps s apart (the
// character needs a garment). body_prev and body: the body at frames t − 1 and t. The
// anchors are pinned where they are predicted (a pin then adds no force), and measured:
// - free: over the unpinned vertices. An anchor is held by its attachment to the body,
//   whose reaction force is not modelled, so its own balance is not measured;
// - all: over every vertex, as `weft train --evaluate` measures. The anchors then show the
//   load of the garment hanging from them as out of balance (4.8 m g on average over the
//   tiny dataset's simulated ground truth, where the free vertices are in balance).
struct ClothBalance {
  physics::FrameMetrics free, all;
  physics::VertexBalance vertices;  // per vertex, anchors included: the residual and its terms (N)
  std::vector<int> free_vertices;   // the vertices `free` is over (not anchors)
};
ClothBalance cloth_out_of_balance(const Character& character, const SynthSimulationConfig& simulation, double fps,
                                  const Vertices& body_prev, const Vertices& body, const Vertices& cloth_prev2,
                                  const Vertices& cloth_prev, const Vertices& cloth);

// IoU per camera of the rendered body (+ cloth when given) against masks[k] (CV_8UC1 of
// cameras[k]'s image size, nonzero foreground); 0 for a camera the body is not wholly in
// front of. Views render in parallel.
std::vector<double> silhouette_ious(const Character& character, const Vertices& body, const Vertices* cloth,
                                    const std::vector<Camera>& cameras, const std::vector<cv::Mat>& masks);

// A posed frame, predicted or true (character units).
struct PosedFrame {
  Vertices body, cloth;                             // cloth: empty without a garment
  Vertices body25;                                  // BODY_25 keypoints of the posed skeleton; NaN rows: not measured
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  // the pivot joint's position
  std::optional<Eigen::Matrix3d> root_rotation;     // the pivot joint's global rotation; none: not measured
  // The truth's: the input view's world → camera rotation, which splits the root-relative
  // joint error into the camera's depth and its image plane; none: not split.
  std::optional<Eigen::Matrix3d> view_rotation;
};

// Every measure of one predicted frame (NaN: not measured). The fields that are metrics
// are listed in frame_metrics(); the counts and per-vertex values below them are what
// pooled figures (a mean over penetrating vertices, a 95th percentile over vertices) need.
struct FrameMeasures {
  double pivot_error_mm = kNotMeasured;
  double mpjpe_mm = kNotMeasured, mpjpe_root_relative_mm = kNotMeasured;
  double pa_mpjpe_mm = kNotMeasured;  // after a similarity Procrustes alignment
  double mpjpe_depth_mm = kNotMeasured, mpjpe_image_plane_mm = kNotMeasured;  // root-relative, input camera
  double root_rotation_error_deg = kNotMeasured;
  double root_heading_error_deg = kNotMeasured, root_tilt_error_deg = kNotMeasured;
  double trunk_direction_error_deg = kNotMeasured;
  double body_error_mean_mm = kNotMeasured, body_error_p95_mm = kNotMeasured;
  double cloth_error_mean_mm = kNotMeasured, cloth_error_p95_mm = kNotMeasured, cloth_chamfer_mm = kNotMeasured;
  double penetration_mean_mm = kNotMeasured;      // over the cloth vertices inside (0 when none is)
  double penetration_mean_all_mm = kNotMeasured;  // over every cloth vertex (0 outside)
  double penetration_max_mm = kNotMeasured, penetrating_fraction = kNotMeasured;
  double contact_fraction = kNotMeasured;  // free cloth vertices outside but within kContactDistanceM of the body
  // Out-of-balance force over the vertices the attachment does not hold (free), and over all.
  double oob_force_mean_n = kNotMeasured, oob_force_p95_n = kNotMeasured, oob_force_p99_n = kNotMeasured,
         oob_force_max_n = kNotMeasured;
  double oob_force_mean_rel = kNotMeasured, oob_force_max_rel = kNotMeasured;
  double oob_force_outside_mean_n = kNotMeasured;  // over the free vertices outside the body
  double oob_force_all_vertices_mean_n = kNotMeasured, oob_force_all_vertices_max_n = kNotMeasured;
  double inertia_mean_n = kNotMeasured, elastic_mean_n = kNotMeasured, collision_mean_n = kNotMeasured,
         friction_mean_n = kNotMeasured;
  double amv_iou = kNotMeasured, rv_iou = kNotMeasured, sv_iou = kNotMeasured;

  int64_t cloth_vertices = 0, penetrating_vertices = 0;
  double penetration_depth_sum_mm = 0;
  std::vector<double> body_distances_mm, cloth_distances_mm;  // per vertex (cloth: empty when not measured)
  // Per BODY_25 row (NaN: not measured): root-relative and after the Procrustes alignment.
  std::vector<double> joint_errors_root_relative_mm, joint_errors_pa_mm;
};

// One per-frame metric: its name (the key in metrics.json and in the split evaluation's
// rows), unit and meaning, and where FrameMeasures holds it.
struct FrameMetric {
  const char* name;
  const char* unit;
  const char* meaning;
  double FrameMeasures::*value;
};
// Every per-frame metric, in the order both evaluations write them.
const std::vector<FrameMetric>& frame_metrics();

// The mean over frames of every metric of frame_metrics() (not measured: left out).
class FrameMetricMeans {
 public:
  FrameMetricMeans();
  void add(const FrameMeasures& m);
  // The mean of the metric named `name` (an error names an unknown one).
  double mean(const std::string& name) const;

 private:
  std::vector<MeasuredMean> means_;
};

// Pose and shape of `predicted` against `truth`: pivot and joint errors (rows NaN in
// either are left out), root rotation (when both have one), body vertex error, and with
// `cloth_error` the cloth's vertex error and Chamfer distance (false: e.g. a ground truth
// whose simulation failed); and the predicted cloth's penetration into the predicted body.
void measure_geometry(const Character& character, const PosedFrame& predicted, const PosedFrame& truth,
                      bool cloth_error, FrameMeasures& m);
// Penetration of `cloth` into `body` alone (e.g. of a ground-truth frame).
void measure_penetration(const Character& character, const Vertices& body, const Vertices& cloth, FrameMeasures& m);

// The out-of-balance force's per-vertex values pooled over frames, for distributions.
struct BalancePool {
  int frames = 0;
  std::vector<double> n, rel, outside_n, all_n, all_rel;  // N, × weight; free vertices unless "all"
  MeasuredMean inertia, elastic, collision, friction;     // N, over the free vertices
};
// The out-of-balance force of frame t given frames t − 2 and t − 1 (cloth_out_of_balance)
// into m's oob_* and term fields, and its values into `pool` when given.
void measure_balance(const Character& character, const SynthSimulationConfig& simulation, double fps,
                     const Vertices& body_prev, const Vertices& body, const Vertices& cloth_prev2,
                     const Vertices& cloth_prev, const Vertices& cloth, FrameMeasures& m, BalancePool* pool = nullptr);

// AMVIoU (the mean over views), RVIoU (all but the input view; NaN with one view) and
// SVIoU (the input view) from the IoU of each view.
void measure_ious(const std::vector<double>& iou_per_view, int input_view, FrameMeasures& m);

}  // namespace weft::capture
