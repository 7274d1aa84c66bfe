#include "capture/training/virtual_poses.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "capture/io/portable_random.h"
#include "capture/motion/motion_retarget.h"
#include "capture/motion/procedural_motion.h"
#include "capture/render/renderer.h"
#include "capture/studio/synthetic_studio.h"
#include "graph/error.h"

namespace weft::capture {

VirtualPoseConfig parse_virtual_pose_config(const StrictYaml& y, const YAML::Node& n) {
  VirtualPoseConfig c;
  if (!n.IsMap()) y.fail_at(n, "virtual_poses", "expected a mapping (motions, mapping, fps, batch_size, views, ...)");
  y.numbers(n, "virtual_poses.", {{"fps", &c.fps, 0.1, 1000}, {"floor_shift_m", &c.floor_shift_m, 0, 100}},
            {{"batch_size", &c.batch_size, 1, 4096}, {"views", &c.views, 1, 1000}},
            {"motions", "mapping", "keypoints"});
  if (!n["motions"] || !n["motions"].IsSequence() || n["motions"].size() == 0)
    y.fail_at(n["motions"] ? n["motions"] : n, "virtual_poses.motions",
              "expected a list of procedural motion specs (configs/motions/*.yaml)");
  for (size_t i = 0; i < n["motions"].size(); ++i)
    c.motions.push_back(y.path(n["motions"][i], "virtual_poses.motions[" + std::to_string(i) + "]"));
  if (!n["mapping"]) y.fail_at(n, "virtual_poses.mapping", "missing: the retarget mapping onto the character");
  c.mapping = y.path(n["mapping"], "virtual_poses.mapping");
  if (n["keypoints"]) parse_keypoint_noise(y, n["keypoints"], c.keypoints, "virtual_poses.keypoints");
  return c;
}

namespace {

// Where the cameras look on the floor: the horizontal point nearest (least squares) to the
// views' optical axes, each seen from above; with one view (or parallel axes), the point
// 3 m along the view's axis. The virtual person stands there.
Eigen::Vector2d floor_centre(const std::vector<const Camera*>& cameras, double unit) {
  Eigen::Matrix2d A = Eigen::Matrix2d::Zero();
  Eigen::Vector2d rhs = Eigen::Vector2d::Zero();
  Eigen::Vector2d first_origin = Eigen::Vector2d::Zero(), first_axis = Eigen::Vector2d::UnitY();
  for (size_t i = 0; i < cameras.size(); ++i) {
    const Camera& c = *cameras[i];
    const Eigen::Vector3d o = -c.R.transpose() * c.t, axis = c.R.row(2).transpose();  // centre, optical axis
    Eigen::Vector2d d(axis.x(), axis.z()), o2(o.x(), o.z());
    if (d.norm() < 1e-9) continue;  // looking straight down: no horizontal axis
    d.normalize();
    if (i == 0) first_origin = o2, first_axis = d;
    const Eigen::Matrix2d P = Eigen::Matrix2d::Identity() - d * d.transpose();
    A += P;
    rhs += P * o2;
  }
  if (std::abs(A.determinant()) > 1e-6) return A.ldlt().solve(rhs);
  return first_origin + 3.0 * unit * first_axis;
}

// Only the crop's geometry is drawn from the augmentation: colours and photos belong to images.
AugmentationOptions crop_geometry_only(const AugmentationOptions& a) {
  AugmentationOptions g;
  g.shift = a.shift;
  g.scale = a.scale;
  return g;
}

}  // namespace

VirtualPoses::VirtualPoses(const Character& character, const VirtualPoseConfig& config,
                           const MultiviewSupervision& supervision, std::vector<int> camera_frames, int input_size,
                           double margin, const AugmentationOptions& augmentation,
                           const std::function<void(int, int)>& progress)
    : character_(character), config_(config), supervision_(supervision), camera_frames_(std::move(camera_frames)),
      input_size_(input_size), margin_(margin), augmentation_(crop_geometry_only(augmentation)) {
  WEFT_CHECK(config_.enabled(), "virtual poses: no motions");
  WEFT_CHECK(!camera_frames_.empty(), "virtual poses: no frames to take cameras from");
  config_.keypoints.metres_per_unit = character.metres_per_unit;
  validate_keypoint_noise(config_.keypoints, "virtual_poses.keypoints");

  const RetargetMapping mapping = load_retarget_mapping(config_.mapping);
  std::vector<Eigen::MatrixXd> parts;
  int rows = 0;
  for (const std::string& spec : config_.motions) {
    const BvhMotion source = generate_motion(load_motion_spec(spec), config_.fps);
    RetargetOptions o;
    o.fps = config_.fps;
    o.progress = progress;
    parts.push_back(retarget_motion(source, mapping, character, o).motion.dofs);
    rows += int(parts.back().rows());
  }
  dofs_.resize(rows, character.skeleton.num_dofs());
  int at = 0;
  for (const Eigen::MatrixXd& p : parts) {
    dofs_.middleRows(at, p.rows()) = p;
    at += int(p.rows());
  }
  WEFT_CHECK(rows > 0, "virtual poses: the motions gave no frames");
}

VirtualBatch VirtualPoses::batch(uint64_t seed, int64_t step) const {
  const int B = config_.batch_size, S = input_size_;
  const int all_views = supervision_.views();
  const int V = std::min(config_.views, all_views);
  const double unit = 1.0 / character_.metres_per_unit;  // metres → character units
  std::vector<std::vector<KeypointView>> views(B);
  std::vector<Camera> crops(B);
  std::vector<Body25> inputs(B, Body25::Zero());
  std::vector<std::string> names(B);
  tbb::parallel_for(0, B, [&](int b) {
    const uint64_t sample_seed = mix_seed(mix_seed(seed, 0x7669727475616cull, uint64_t(step)), uint64_t(b), 0);
    PortableRandom rng(sample_seed);
    const int pose = std::min(poses() - 1, int(rng.uniform() * poses()));
    const double yaw = rng.uniform(0, 2 * M_PI);
    const double r = config_.floor_shift_m * unit * std::sqrt(rng.uniform()), a = rng.uniform(0, 2 * M_PI);
    const int frame = camera_frames_[std::min(camera_frames_.size() - 1, size_t(rng.uniform() * camera_frames_.size()))];
    std::vector<int> order(all_views);
    std::iota(order.begin(), order.end(), 0);
    for (int i = 0; i < V; ++i) {  // the first V of a uniform shuffle
      const int j = i + std::min(all_views - 1 - i, int(rng.uniform() * (all_views - i)));
      std::swap(order[i], order[j]);
    }

    PosedCharacter posed = pose_character(character_, dofs_.row(pose).transpose());
    // Turned about its own vertical axis (through the body's mean) and moved on the floor to
    // where the cameras look, give or take floor_shift_m.
    const Eigen::RowVector3d mean = posed.body.colwise().mean();
    const Eigen::RowVector3d centre(mean.x(), 0, mean.z());
    const Eigen::Matrix3d R = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitY()).toRotationMatrix();
    std::vector<const Camera*> cameras;
    for (int v = 0; v < all_views; ++v) cameras.push_back(&supervision_.camera(frame, v));
    const Eigen::Vector2d target = floor_centre(cameras, unit);
    const Eigen::RowVector3d moved(target.x() + r * std::cos(a), 0, target.y() + r * std::sin(a));
    auto place = [&](Vertices& X) {
      if (X.rows() == 0) return;
      X = ((X.rowwise() - centre) * R.transpose()).rowwise() + moved;
    };
    place(posed.body);
    place(posed.cloth);
    place(posed.body25);  // NaN rows (unmapped keypoints) stay NaN

    std::vector<RenderMesh> meshes{{&character_.body.mesh, &posed.body, 1}};
    if (character_.has_cloth()) meshes.push_back({&character_.cloth->mesh, &posed.cloth, 2});
    for (int i = 0; i < V; ++i) {
      const Camera& camera = supervision_.camera(frame, order[i]);
      const RenderResult image = render(camera, meshes);
      const Body25 detections =
          synthesize_keypoints(camera, posed.body25, image.depth, config_.keypoints, mix_seed(sample_seed, 1 + i, 0));
      views[b].push_back({camera, detections});
      if (i > 0) continue;
      CropWindow crop = choose_crop(image.mask, detections, S, margin_);
      if (augmentation_.enabled()) move_crop(crop, draw_augmentation(augmentation_, 0, mix_seed(sample_seed, 0, 1)), S);
      crops[b] = crop_camera(camera, crop, S);
      names[b] = camera.name;
      for (int j = 0; j < kBody25Count; ++j) {
        if (!(detections(j, 2) > 0)) continue;
        const Eigen::Vector2d p = crop.to_crop(detections.row(j).head<2>().transpose());
        inputs[b].row(j) << p.x(), p.y(), detections(j, 2);
      }
    }
  });
  VirtualBatch out;
  std::vector<double> k;
  k.reserve(size_t(B) * kBody25Count * 3);
  for (int b = 0; b < B; ++b)
    for (int j = 0; j < kBody25Count; ++j)
      for (int c = 0; c < 3; ++c) k.push_back(inputs[b](j, c));
  out.input.keypoints = Tensor::from_data({B, kBody25Count, 3}, k, DType::F32);
  out.input.cameras = std::move(crops);
  out.input.views = std::move(names);
  out.input.indices.resize(B);
  std::iota(out.input.indices.begin(), out.input.indices.end(), 0);
  out.input.frames.assign(B, -1);
  out.input.whole_size = B;
  out.views = std::move(views);
  return out;
}

}  // namespace weft::capture
