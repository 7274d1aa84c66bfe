#include "capture/evaluation/training_set_comparison.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <tuple>

#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/evaluation/frame_measures.h"
#include "capture/model/capture_networks.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

TrainingPoses read_training_poses(const std::string& data, const std::string& split, const Character& ch) {
  const DatasetInfo info = read_dataset_info(data);
  const std::string info_yaml = (fs::path(info.dir) / "dataset.yaml").string();
  const auto it = info.splits.find(split);
  WEFT_CHECK(it != info.splits.end() && !it->second.empty(), info_yaml, ": no split '", split,
             "' with frames (the training data of --training-data needs one)");
  WEFT_CHECK(std::abs(info.metres_per_unit - ch.metres_per_unit) <= 1e-9 * ch.metres_per_unit, info_yaml,
             ": metres_per_unit ", info.metres_per_unit, " differs from the captured character's ",
             ch.metres_per_unit);
  const std::string motion_path = (fs::path(info.dir) / "gt" / "pose.motion").string();
  const Motion motion = read_motion(motion_path, int(ch.rest_dofs.size()));
  const std::string cameras_path = (fs::path(info.dir) / "cameras.yaml").string();
  std::map<std::string, Camera> cameras;
  for (const Camera& c : read_cameras_yaml(cameras_path)) cameras[c.name] = c;
  const PoseParametrisation param = pose_parametrisation(ch);

  TrainingPoses t;
  t.data = data, t.split = split, t.frames = it->second, t.views = info.views;
  const size_t n = t.frames.size();
  t.body25.resize(n), t.pivot.resize(n), t.root_rotation.resize(n), t.cameras.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const int f = t.frames[k];
    WEFT_CHECK(f < motion.num_frames(), motion_path, ": no row for frame ", f, " of split '", split, "'");
    for (const std::string& v : info.views) {
      const std::string name = dataset_camera_name(info, f, v);
      const auto c = cameras.find(name);
      WEFT_CHECK(c != cameras.end(), cameras_path, ": no camera '", name, "'");
      t.cameras[k].push_back(c->second);
    }
  }
  tbb::parallel_for(size_t(0), n, [&](size_t k) {
    const Transforms joints = forward_kinematics(ch.skeleton, motion.dofs.row(t.frames[k]).transpose());
    t.body25[k] = body25_positions(ch, joints, marker_positions(ch.skeleton, joints, ch.zero_pose));
    t.pivot[k] = joints[param.pivot_joint].translation();
    t.root_rotation[k] = joints[param.pivot_joint].linear();
  });
  return t;
}

Eigen::MatrixX2d normalized_points_2d(const Eigen::MatrixX2d& p, const std::vector<char>& use) {
  Eigen::MatrixX2d out = p;
  Eigen::RowVector2d centre = Eigen::RowVector2d::Zero();
  int n = 0;
  for (int i = 0; i < p.rows(); ++i)
    if (use[i]) centre += p.row(i), ++n;
  if (n == 0) return out;
  centre /= n;
  double ss = 0;
  for (int i = 0; i < p.rows(); ++i)
    if (use[i]) ss += (p.row(i) - centre).squaredNorm();
  const double scale = ss > 0 ? 1 / std::sqrt(ss / n) : 1;
  for (int i = 0; i < p.rows(); ++i)
    if (use[i]) out.row(i) = (p.row(i) - centre) * scale;
  return out;
}

namespace {

// Root-relative and PA-MPJPE (mm) of a prediction against the truth, both world.
std::pair<double, double> pose_errors_mm(const Vertices& predicted, const Eigen::Vector3d& predicted_pivot,
                                         const Vertices& truth, const Eigen::Vector3d& true_pivot, double mpu) {
  const double root_relative = mean_joint_error_mm(predicted.rowwise() - predicted_pivot.transpose(),
                                                   truth.rowwise() - true_pivot.transpose(), mpu);
  return {root_relative, mean_joint_error_mm(procrustes_aligned(predicted, truth), truth, mpu)};
}

}  // namespace

TrainingSetComparison compare_with_training_set(const TrainingPoses& tr, const std::vector<TestFramePose>& test,
                                                double mpu) {
  WEFT_CHECK(!tr.frames.empty(), "compare_with_training_set: no training frames");
  const size_t n = tr.frames.size(), views = tr.views.size();
  const int rows = int(tr.body25[0].rows());
  const double nan = std::numeric_limits<double>::quiet_NaN();

  // The mean pose relative to the pivot in its heading frame.
  Vertices mean_pose = Vertices::Zero(rows, 3);
  for (size_t k = 0; k < n; ++k)
    mean_pose += ((heading_rotation(tr.root_rotation[k]).transpose() *
                   (tr.body25[k].rowwise() - tr.pivot[k].transpose()).transpose())
                      .transpose());
  mean_pose /= double(n);

  // Every training frame's keypoints in every view's image (pixels; NaN rows unmapped).
  std::vector<Eigen::MatrixX2d> projected(n * views);
  tbb::parallel_for(size_t(0), n, [&](size_t k) {
    for (size_t v = 0; v < views; ++v) {
      Eigen::MatrixX2d p(rows, 2);
      for (int i = 0; i < rows; ++i)
        p.row(i) = tr.body25[k].row(i).allFinite()
                       ? Eigen::RowVector2d(tr.cameras[k][v].project(tr.body25[k].row(i).transpose()).transpose())
                       : Eigen::RowVector2d::Constant(nan);
      projected[k * views + v] = p;
    }
  });

  TrainingSetComparison c;
  c.data = tr.data, c.split = tr.split, c.training_frames = int(n), c.training_views = int(views);
  c.frames.resize(test.size());
  tbb::parallel_for(size_t(0), test.size(), [&](size_t t) {
    const TestFramePose& q = test[t];
    WEFT_CHECK(q.body25.rows() == rows, "compare_with_training_set: test frame ", q.id, " has ", q.body25.rows(),
               " keypoints, the training poses ", rows);
    TrainingSetFrame& r = c.frames[t];
    r.id = q.id;
    // The nearest training pose.
    r.nearest_pose_pa_mm = std::numeric_limits<double>::infinity();
    for (size_t k = 0; k < n; ++k) {
      const double d = mean_joint_error_mm(procrustes_aligned(tr.body25[k], q.body25), q.body25, mpu);
      if (d < r.nearest_pose_pa_mm) r.nearest_pose_pa_mm = d, r.nearest_pose_frame = tr.frames[k];
    }
    // The mean pose with the true heading and pivot.
    const Vertices mean_here =
        ((heading_rotation(q.root_rotation) * mean_pose.transpose()).colwise() + q.pivot).transpose();
    std::tie(r.mean_pose_root_relative_mm, r.mean_pose_pa_mm) = pose_errors_mm(mean_here, q.pivot, q.body25, q.pivot, mpu);
    // The 2D retrieval over the keypoints detected in the test view and mapped in the skeleton.
    std::vector<char> use(rows, 0);
    Eigen::MatrixX2d detected(rows, 2);
    int used = 0;
    for (int i = 0; i < rows; ++i) {
      detected.row(i) = q.detections.row(i).head<2>();
      use[i] = q.detections(i, 2) > 0 && q.body25.row(i).allFinite();
      used += use[i];
    }
    r.nearest_2d_root_relative_mm = r.nearest_2d_pa_mm = nan;
    if (used < 3) return;
    const Eigen::MatrixX2d a = normalized_points_2d(detected, use);
    double best = std::numeric_limits<double>::infinity();
    size_t best_kv = 0;
    for (size_t kv = 0; kv < projected.size(); ++kv) {
      const Eigen::MatrixX2d b = normalized_points_2d(projected[kv], use);
      double d = 0;
      for (int i = 0; i < rows; ++i)
        if (use[i]) d += (a.row(i) - b.row(i)).squaredNorm();
      if (d < best) best = d, best_kv = kv;
    }
    const size_t k = best_kv / views, v = best_kv % views;
    r.nearest_2d_frame = tr.frames[k], r.nearest_2d_view = tr.views[v];
    // The same pose relative to the camera: training camera → input camera.
    const Eigen::Matrix3d carry = q.camera.R.transpose() * tr.cameras[k][v].R;
    const Vertices retrieved =
        ((carry * (tr.body25[k].rowwise() - tr.pivot[k].transpose()).transpose()).colwise() + q.pivot).transpose();
    std::tie(r.nearest_2d_root_relative_mm, r.nearest_2d_pa_mm) = pose_errors_mm(retrieved, q.pivot, q.body25, q.pivot, mpu);
  });

  MeasuredMean nearest, mean_rr, mean_pa, ret_rr, ret_pa;
  for (const TrainingSetFrame& r : c.frames) {
    nearest.add(r.nearest_pose_pa_mm), mean_rr.add(r.mean_pose_root_relative_mm), mean_pa.add(r.mean_pose_pa_mm);
    ret_rr.add(r.nearest_2d_root_relative_mm), ret_pa.add(r.nearest_2d_pa_mm);
  }
  c.nearest_pose_pa_mm = nearest.value(), c.mean_pose_root_relative_mm = mean_rr.value(),
  c.mean_pose_pa_mm = mean_pa.value(), c.nearest_2d_root_relative_mm = ret_rr.value(),
  c.nearest_2d_pa_mm = ret_pa.value();
  return c;
}

}  // namespace weft::capture
