// The training-set comparison of `weft eval --training-data` (capture/evaluation/
// training_set_comparison.h) on poses built for known answers: a test pose that is a
// training pose turned and moved, the mean of two poses, and the 2D retrieval finding the
// training view that saw the same pose from the same side.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "capture/evaluation/frame_measures.h"
#include "capture/evaluation/training_set_comparison.h"
#include "capture/io/openpose.h"

using namespace weft;
using namespace weft::capture;

namespace {

// A random "pose": 25 keypoints within 0.8 m of the pivot at (0, 1, 0), one row unmapped.
Vertices random_pose(int seed) {
  std::srand(seed);
  Vertices p = Vertices::Random(kBody25Count, 3) * 0.4;
  p.col(1) *= 2;
  p.rowwise() += Eigen::RowVector3d(0, 1, 0);
  p.row(24).setConstant(std::numeric_limits<double>::quiet_NaN());
  return p;
}

Eigen::Matrix3d turn_y(double rad) { return Eigen::AngleAxisd(rad, Eigen::Vector3d::UnitY()).toRotationMatrix(); }

// A camera 4 m from the world origin, looking at it from `heading_rad` about the vertical.
Camera camera_at(double heading_rad, const std::string& name) {
  Camera c;
  c.name = name;
  c.K << 500, 0, 320, 0, 500, 240, 0, 0, 1;
  c.width = 640, c.height = 480;
  // Camera axes: z toward the origin, y down.
  const Eigen::Vector3d centre = turn_y(heading_rad) * Eigen::Vector3d(0, 1, 4);
  const Eigen::Vector3d z = (Eigen::Vector3d(0, 1, 0) - centre).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d(0, -1, 0).cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  c.R.row(0) = x.transpose(), c.R.row(1) = y.transpose(), c.R.row(2) = z.transpose();
  c.t = -c.R * centre;
  return c;
}

// Training: three poses at the pivot (0, 1, 0), heading 0, seen by two cameras (front, side).
TrainingPoses training() {
  TrainingPoses t;
  t.data = "memory", t.split = "train", t.views = {"front", "side"};
  for (int k = 0; k < 3; ++k) {
    t.frames.push_back(10 + k);
    t.body25.push_back(random_pose(k + 1));
    t.pivot.push_back(Eigen::Vector3d(0, 1, 0));
    t.root_rotation.push_back(Eigen::Matrix3d::Identity());
    t.cameras.push_back({camera_at(0, "front"), camera_at(std::numbers::pi / 2, "side")});
  }
  return t;
}

// A test frame: training pose k turned by `turn` about the vertical through its pivot and
// moved by `move`, seen by a camera turned the same way (it sees what the side camera saw).
TestFramePose test_of(const TrainingPoses& t, int k, double turn, const Eigen::Vector3d& move) {
  TestFramePose q;
  q.id = 100 + k;
  const Eigen::Matrix3d R = turn_y(turn);
  q.pivot = t.pivot[k] + move;
  q.body25 = ((R * (t.body25[k].rowwise() - t.pivot[k].transpose()).transpose()).colwise() + q.pivot).transpose();
  q.root_rotation = R;
  // The side camera turned with the person and moved with them.
  Camera c = t.cameras[k][1];
  c.R = c.R * R.transpose();
  c.t = -c.R * (R * t.cameras[k][1].center() + move);
  q.camera = c;
  for (int i = 0; i < kBody25Count; ++i) {
    if (!q.body25.row(i).allFinite()) continue;
    q.detections.row(i).head<2>() = c.project(q.body25.row(i).transpose()).transpose();
    q.detections(i, 2) = 0.9;
  }
  return q;
}

}  // namespace

TEST(TrainingSetComparison, ATrainingPoseTurnedAndMovedIsFoundIn3DAndIn2D) {
  const TrainingPoses t = training();
  const TestFramePose q = test_of(t, 1, 0.7, {0.5, 0, -0.3});
  const TrainingSetComparison c = compare_with_training_set(t, {q}, 1.0);
  ASSERT_EQ(c.frames.size(), 1u);
  const TrainingSetFrame& r = c.frames[0];
  EXPECT_EQ(r.id, 101);
  EXPECT_EQ(r.nearest_pose_frame, 11);
  EXPECT_NEAR(r.nearest_pose_pa_mm, 0, 1e-6);
  EXPECT_EQ(r.nearest_2d_frame, 11);
  EXPECT_EQ(r.nearest_2d_view, "side");
  EXPECT_NEAR(r.nearest_2d_root_relative_mm, 0, 1e-6);
  EXPECT_NEAR(r.nearest_2d_pa_mm, 0, 1e-6);
  EXPECT_EQ(c.training_frames, 3);
  EXPECT_EQ(c.training_views, 2);
}

TEST(TrainingSetComparison, TheMeanPoseIsTheMeanInTheHeadingFrame) {
  TrainingPoses t = training();
  // Two training frames: pose A at heading 0 and the same pose A' = A + d turned by 90°
  // (its heading frame undoes the turn, so the mean is A + d/2 there).
  t.frames.resize(2), t.body25.resize(2), t.pivot.resize(2), t.root_rotation.resize(2), t.cameras.resize(2);
  const Eigen::RowVector3d d(0.1, 0, 0);
  const Vertices A = t.body25[0];
  t.body25[1] = ((turn_y(std::numbers::pi / 2) * ((A.rowwise() + d).rowwise() - t.pivot[1].transpose()).transpose())
                     .colwise() +
                 t.pivot[1])
                    .transpose();
  t.root_rotation[1] = turn_y(std::numbers::pi / 2);
  // The test: pose A itself, turned by 0.3 and moved; the mean pose placed with its heading.
  const TestFramePose q = test_of(t, 0, 0.3, {1, 0, 1});
  const TrainingSetComparison c = compare_with_training_set(t, {q}, 1.0);
  // Every mapped keypoint is d/2 = 50 mm off; the Procrustes alignment removes a shift whole.
  EXPECT_NEAR(c.frames[0].mean_pose_root_relative_mm, 50, 1e-6);
  EXPECT_NEAR(c.frames[0].mean_pose_pa_mm, 0, 1e-6);
  EXPECT_NEAR(c.mean_pose_root_relative_mm, 50, 1e-6);
}

TEST(TrainingSetComparison, TooFewDetectionsLeaveTheRetrievalOut) {
  const TrainingPoses t = training();
  TestFramePose q = test_of(t, 2, 0, {0, 0, 0});
  q.detections.col(2).setZero();
  q.detections(3, 2) = q.detections(5, 2) = 0.9;  // two keypoints: too few
  const TrainingSetComparison c = compare_with_training_set(t, {q}, 1.0);
  EXPECT_TRUE(std::isnan(c.frames[0].nearest_2d_root_relative_mm));
  EXPECT_TRUE(std::isnan(c.nearest_2d_root_relative_mm));
  EXPECT_EQ(c.frames[0].nearest_pose_frame, 12);  // the 3D comparison needs no detections
}

TEST(TrainingSetComparison, NormalizedPointsForgetPositionAndSize) {
  Eigen::MatrixX2d p(4, 2);
  p << 0, 0, 2, 0, 2, 2, 100, 100;  // the last row is not used
  const std::vector<char> use = {1, 1, 1, 0};
  const Eigen::MatrixX2d a = normalized_points_2d(p, use);
  Eigen::MatrixX2d q = p * 3;
  q.col(0).array() += 50;
  const Eigen::MatrixX2d b = normalized_points_2d(q, use);
  EXPECT_TRUE(a.topRows(3).isApprox(b.topRows(3), 1e-12));
  EXPECT_NEAR(a.topRows(3).colwise().sum().norm(), 0, 1e-12);
  EXPECT_NEAR(a.topRows(3).squaredNorm() / 3, 1, 1e-12);
  EXPECT_EQ(a(3, 0), 100);
}
