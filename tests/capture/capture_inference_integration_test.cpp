// `weft infer` (capture/inference/sequence_capture.h) on a view of the tiny dataset with a
// model folder holding untrained networks (PoseNet's last layer given a random bias, so
// the pose and root rotation are far from the rest pose; PADefNet zero, so the meshes are
// the skinned template): every file is written, pose.motion and pose.bvh put the
// skeleton exactly where the meshes are, the silhouette places a body where it was
// rendered, and bad inputs stop with an error naming the file before capture.json exists.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <random>

#include "capture/character/skeletool_io.h"
#include "capture/adaptation/domain_adaptation.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/inference/sequence_capture.h"
#include "capture/inference/silhouette_translation.h"
#include "geometry/mesh_io.h"
#include "capture/motion/bvh.h"
#include "capture/render/renderer.h"
#include "capture/studio/synthetic_studio.h"
#include "capture/model/capture_networks.h"
#include "capture/training/loss_log.h"
#include "capture/model/model_folder.h"
#include "graph/autograd.h"
#include "nn/checkpoint.h"
#include "tests/capture/shared_fixture.h"
#include "tests/capture/test_files.h"

using namespace weft;
using namespace weft::capture;
namespace fs = std::filesystem;
using weft::capture::testing::expect_error;
using weft::capture::testing::repo_file;

namespace {

fs::path infer_scratch_root() { return weft::capture::testing::process_scratch("infer"); }

struct Fixture {
  fs::path data, model;
};

// The tiny dataset and a model folder of untrained networks for it (shared_fixture.h).
const Fixture& fixture() {
  static std::unique_ptr<Fixture> f;
  if (!f) {
    f = std::make_unique<Fixture>();
    f->data = weft::capture::testing::tiny_dataset();
    f->model = weft::capture::testing::shared_fixture("untrained_model", [&](const fs::path& dir) {
      const std::string config = repo_file("configs/train/tiny.yaml");
      fs::copy_file(config, dir / "config.yaml");
      write_model_folder(dir.string(), config, f->data.string());
      const TrainingConfig cfg = load_training_config(config);
      const Character character = load_character((dir / "character" / "character.yaml").string());
      CaptureNetworks nets(character, cfg.network, cfg.seed);
      std::mt19937 rng(5);
      std::uniform_real_distribution<double> u(-1.0, 1.0);
      weft::Tensor& bias = nets.pose_net->fc->bias;
      for (int64_t k = 0; k < bias.numel(); ++k) bias.set({k}, u(rng));
      weft::nn::save_weights((dir / "model.safetensors").string(), nets);
    });
  }
  return *f;
}

// The fixture's model capturing one view of the tiny dataset, with its keypoints (or,
// with keypoints = false, translated from the silhouette); the output folder is the test's.
CaptureOptions view_capture(const Fixture& f, const std::string& view, bool keypoints = true) {
  CaptureOptions o;
  o.model = f.model.string();
  o.input = (f.data / "images" / view).string();
  o.camera = (f.data / "cameras.yaml").string();
  o.camera_name = view;
  if (keypoints) o.keypoints = (f.data / "keypoints" / view).string();
  return o;
}

}  // namespace

TEST(Infer, WritesEveryFileAndThePoseFilesPutTheSkeletonWhereTheMeshesAre) {
  const Fixture& f = fixture();
  CaptureOptions o = view_capture(f, "cam02");
  o.out = (infer_scratch_root() / "capture").string();
  int networks_calls = 0, mesh_calls = 0;
  const CaptureSummary s = capture_sequence(o, [&](const std::string& pass, int, int total) {
    EXPECT_EQ(total, 6);
    ++(pass == "networks" ? networks_calls : mesh_calls);
  });
  EXPECT_EQ(s.frames, 6);
  EXPECT_EQ(s.translations_from_keypoints, 6);
  EXPECT_EQ(networks_calls, 6);
  EXPECT_EQ(mesh_calls, 6);
  for (const char* part : {"read", "segment", "crop", "networks", "filter", "deform", "place", "write"})
    EXPECT_TRUE(s.part_seconds.count(part)) << part;

  const fs::path out(o.out);
  std::ifstream in(out / "capture.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["format"], "weft-capture/1");
  EXPECT_EQ(j["view"], "cam02");
  ASSERT_EQ(j["frames"].size(), 6u);
  const Character character = load_character(j["character"].get<std::string>());
  const Motion motion = read_motion((out / "pose.motion").string(), character.skeleton.num_dofs());
  ASSERT_EQ(motion.num_frames(), 6);
  const BvhMotion bvh = read_bvh((out / "pose.bvh").string());
  ASSERT_EQ(bvh.num_frames(), 6);
  const PoseParametrisation param = pose_parametrisation(character);
  const int pivot_bvh = bvh.joint_index(character.skeleton.joints[size_t(param.pivot_joint)].name);
  ASSERT_GE(pivot_bvh, 0);
  double largest_turn = 0;
  for (int i = 0; i < 6; ++i) {
    char id[8];
    std::snprintf(id, sizeof(id), "%04d", i);
    EXPECT_EQ(j["frames"][size_t(i)]["id"], i);
    EXPECT_EQ(j["frames"][size_t(i)]["translation_from"], "keypoints");
    for (const char* ext : {".ply", ".obj"}) {
      EXPECT_TRUE(fs::exists(out / "meshes" / (std::string("body_") + id + ext))) << id << ext;
      EXPECT_TRUE(fs::exists(out / "meshes" / (std::string("cloth_") + id + ext))) << id << ext;
    }
    EXPECT_TRUE(fs::exists(out / "overlays" / (std::string(id) + ".png")));
    const TriangleMesh body = read_ply((out / "meshes" / (std::string("body_") + id + ".ply")).string());
    const TriangleMesh cloth = read_ply((out / "meshes" / (std::string("cloth_") + id + ".ply")).string());
    ASSERT_EQ(body.num_vertices(), character.body.mesh.num_vertices());
    ASSERT_EQ(cloth.num_vertices(), character.cloth->mesh.num_vertices());
    EXPECT_EQ(body.F, character.body.mesh.F);
    // PADefNet is zero: the meshes are the template skinned by pose.motion's dofs, root
    // chain included (RootPlacement reproduces the networks' rigid placement).
    const PosedCharacter posed = pose_character(character, motion.dofs.row(i).transpose());
    EXPECT_LT((posed.body - body.V).rowwise().norm().maxCoeff(), 2e-4) << "frame " << i;
    EXPECT_LT((posed.cloth - cloth.V).rowwise().norm().maxCoeff(), 2e-4) << "frame " << i;
    // The BVH's pivot joint is the skeleton's, and capture.json's pivot too.
    const Eigen::Vector3d pivot = posed.joints[size_t(param.pivot_joint)].translation();
    EXPECT_LT((bvh_global_transforms(bvh, i)[size_t(pivot_bvh)].translation() - pivot).norm(), 1e-6);
    const auto& p = j["frames"][size_t(i)]["pivot"];
    EXPECT_LT((Eigen::Vector3d(p[0], p[1], p[2]) - pivot).norm(), 1e-5);
    const Eigen::Matrix3d turn = posed.joints[size_t(param.pivot_joint)].linear() *
                                 character.bind[size_t(param.pivot_joint)].linear().transpose();
    largest_turn = std::max(largest_turn, Eigen::AngleAxisd(turn).angle());
  }
  EXPECT_GT(largest_turn, 0.3) << "the random PoseNet bias should turn the root away from the rest pose";
  const bool video = fs::exists(out / "overlay.mp4") || fs::exists(out / "overlay.avi");
  EXPECT_TRUE(video);
  EXPECT_FALSE(fs::exists(out / "overlay.partial.mp4"));
}

TEST(Infer, TheSilhouettePlacesABodyWhereItWasRendered) {
  const Fixture& f = fixture();
  const Character character = load_character((f.model / "character" / "character.yaml").string());
  const std::vector<Camera> cameras = read_cameras_yaml((f.data / "cameras.yaml").string());
  Vertices relative = pose_character(character, character.rest_dofs).body;
  relative.rowwise() -= relative.colwise().mean();
  for (const Camera& camera : {cameras[0], cameras[3]}) {
    for (const Eigen::Vector3d& truth : {Eigen::Vector3d(0.1, 0.9, -0.2), Eigen::Vector3d(-0.3, 0.8, 0.4)}) {
      const Vertices placed = relative.rowwise() + truth.transpose();
      const RenderResult r = render(camera, {{&character.body.mesh, &placed, 1}});
      const Eigen::Vector3d t = translation_from_silhouette(camera, relative, cv::boundingRect(r.mask));
      // At 3 m a pixel is about 1 cm across and the body about 150 px tall: a pixel of box
      // height is 2 cm of depth.
      const Eigen::Vector3d along = (camera.R.transpose() * Eigen::Vector3d::UnitZ());
      const Eigen::Vector3d error = t - truth;
      EXPECT_LT(std::abs(error.dot(along)), 0.04) << camera.name;
      EXPECT_LT((error - error.dot(along) * along).norm(), 0.015) << camera.name;
    }
  }
}

TEST(Infer, BadInputsNameTheFileAndLeaveNoCapture) {
  const Fixture& f = fixture();
  const fs::path root = infer_scratch_root() / "bad";
  fs::create_directories(root);
  CaptureOptions o = view_capture(f, "cam02", false);
  o.out = (root / "out").string();

  // A video OpenCV cannot open.
  CaptureOptions video = o;
  video.input = (root / "clip.mp4").string();
  std::ofstream(video.input) << "not a video";
  expect_error([&] { capture_sequence(video); }, {"clip.mp4", "cannot be opened as a video"});
  // A camera for another image size.
  std::vector<Camera> cameras = read_cameras_yaml(o.camera);
  for (Camera& c : cameras) c.width = c.height = 128;
  CaptureOptions camera = o;
  camera.camera = (root / "small_cameras.yaml").string();
  write_cameras_yaml(camera.camera, cameras);
  expect_error([&] { capture_sequence(camera); }, {"small_cameras.yaml", "cam02", "128x128", "256x256"});
  // A camera the file does not have.
  CaptureOptions name = o;
  name.camera_name = "cam99";
  expect_error([&] { capture_sequence(name); }, {"cameras.yaml", "cam99"});
  // A model folder without weights, and a folder that is no model.
  const fs::path empty_model = root / "model_without_weights";
  fs::create_directories(empty_model);
  for (const char* file : {"model.yaml", "config.yaml"}) fs::copy_file(f.model / file, empty_model / file);
  fs::copy(f.model / "character", empty_model / "character", fs::copy_options::recursive);
  CaptureOptions weights = o;
  weights.model = empty_model.string();
  expect_error([&] { capture_sequence(weights); }, {"model_without_weights", "no model.safetensors"});
  CaptureOptions no_model = o;
  no_model.model = root.string();
  expect_error([&] { capture_sequence(no_model); }, {"no model.yaml"});
  EXPECT_FALSE(fs::exists(fs::path(o.out) / "capture.json"));
}

// --weights: the folder's own weights named explicitly capture exactly what the folder
// does; other weights of the same networks capture something else; a missing file is an
// error naming it.
TEST(Infer, WeightsReplaceTheFoldersAndAMissingFileIsNamed) {
  const Fixture& f = fixture();
  const fs::path root = infer_scratch_root() / "weights";
  fs::create_directories(root);
  CaptureOptions o = view_capture(f, "cam02");
  o.max_frames = 2;
  auto capture_to = [&](const std::string& name, const std::string& weights) {
    CaptureOptions c = o;
    c.weights = weights;
    c.out = (root / name).string();
    capture_sequence(c);
    return weft::capture::testing::slurp(root / name / "pose.motion");
  };
  const std::string folder = capture_to("folder", "");
  EXPECT_EQ(capture_to("same", (f.model / "model.safetensors").string()), folder);
  // Other weights: PoseNet's output bias moved.
  const ModelFolder m = read_model_folder(f.model.string());
  const Character character = load_character(m.character);
  CaptureNetworks nets(character, m.network, m.seed);
  load_capture_networks(m.weights, nets);
  weft::Tensor& bias = nets.pose_net->fc->bias;
  for (int64_t k = 0; k < bias.numel(); ++k) bias.set({k}, 0.3);
  const fs::path other = root / "other.safetensors";
  weft::nn::save_weights(other.string(), nets);
  EXPECT_NE(capture_to("other", other.string()), folder);
  CaptureOptions missing = o;
  missing.weights = (root / "no_such.safetensors").string();
  missing.out = (root / "missing").string();
  expect_error([&] { capture_sequence(missing); }, {"--weights", "no_such.safetensors"});
}

TEST(Adapt, RefinesTheModelOnTheSequenceAndResumesExactly) {
  const Fixture& f = fixture();
  AdaptOptions o;
  o.model = f.model.string();
  o.input = (f.data / "images" / "cam05").string();
  o.camera = (f.data / "cameras.yaml").string();
  o.camera_name = "cam05";
  o.keypoints = (f.data / "keypoints" / "cam05").string();
  o.masks = (f.data / "masks" / "cam05").string();
  o.iterations = 6;
  o.out = (infer_scratch_root() / "adapted").string();
  const AdaptSummary s = adapt_model(o);
  EXPECT_EQ(s.frames, 6);
  EXPECT_EQ(s.training.last_step, 12);
  // The sequence became a one-view dataset, and OUT a model folder weft infer can use.
  const DatasetInfo info = read_dataset_info(s.sequence);
  EXPECT_EQ(info.views, (std::vector<std::string>{"cam05"}));
  EXPECT_EQ(info.splits.at("train").size(), 6u);
  const ModelFolder adapted = read_model_folder(o.out);
  EXPECT_EQ(model_training_config(adapted).stages[0].steps, 6);
  // PoseNet's stage lowers L_lm on the sequence's own detections.
  const std::vector<LossRow> rows = read_loss_log((fs::path(o.out) / "losses.csv").string());
  ASSERT_EQ(rows.size(), 12u);
  EXPECT_LT(rows[5].terms.at("landmarks"), rows[0].terms.at("landmarks"));

  // Interrupted after step 3 and resumed: the same losses as the uninterrupted run.
  AdaptOptions interrupted = o;
  interrupted.out = (infer_scratch_root() / "adapted_resumed").string();
  interrupted.stop_after = 3;
  adapt_model(interrupted);
  interrupted.stop_after = -1;
  interrupted.resume = true;
  adapt_model(interrupted);
  EXPECT_EQ(weft::capture::testing::slurp(fs::path(interrupted.out) / "losses.csv"),
            weft::capture::testing::slurp(fs::path(o.out) / "losses.csv"));

  // Without detections there is nothing to adapt to.
  AdaptOptions no_keypoints = o;
  no_keypoints.keypoints.clear();
  expect_error([&] { adapt_model(no_keypoints); }, {"--keypoints"});
}

// The adapted model rebuilds the model's networks: a lifting PoseNet (no image network,
// its own branch shape) stays one. (weft adapt once wrote only some network keys, so a
// lifter came back with an untrained image network beside its branch.) Its simulation loss
// keeps the model's settings too (it once kept only three of them).
TEST(Adapt, KeepsTheModelsNetworks) {
  const Fixture& f = fixture();
  const fs::path lifter = infer_scratch_root() / "lifter_model";
  fs::create_directories(lifter);
  {
    std::string config = weft::capture::testing::slurp(repo_file("configs/train/tiny.yaml"));
    const std::string network = "network: {backbone: resnet18, input_size: 64}";
    ASSERT_NE(config.find(network), std::string::npos);
    config.replace(config.find(network), network.size(),
                   "network: {backbone: resnet18, input_size: 64, keypoint_input: true, image_input: false, "
                   "lift_width: 48, lift_layers: 3}");
    const std::string physics = "physics: {window_frames: 3, max_iterations: 60, tolerance: 1.0e-2}";
    ASSERT_NE(config.find(physics), std::string::npos);
    config.replace(config.find(physics), physics.size(),
                   "physics: {window_frames: 3, max_iterations: 60, tolerance: 1.0e-2, ray_stiffness: 40, "
                   "ray_max_pixels: 4, freeze_batch_norm: false}");
    std::ofstream(lifter / "config.yaml") << config;
  }
  write_model_folder(lifter.string(), (lifter / "config.yaml").string(), f.data.string());
  const TrainingConfig cfg = load_training_config((lifter / "config.yaml").string());
  const Character character = load_character((lifter / "character" / "character.yaml").string());
  CaptureNetworks nets(character, cfg.network, cfg.seed);
  weft::nn::save_weights((lifter / "model.safetensors").string(), nets);
  const ModelFolder model = read_model_folder(lifter.string());
  ASSERT_FALSE(model.network.image_input);
  AdaptOptions o;
  o.model = lifter.string();
  o.input = (f.data / "images" / "cam05").string();
  o.camera = (f.data / "cameras.yaml").string();
  o.camera_name = "cam05";
  o.keypoints = (f.data / "keypoints" / "cam05").string();
  o.masks = (f.data / "masks" / "cam05").string();
  o.iterations = 1;
  o.out = (infer_scratch_root() / "lifter_adapted").string();
  adapt_model(o);
  const NetworkConfig adapted = read_model_folder(o.out).network;
  EXPECT_FALSE(adapted.image_input);
  EXPECT_TRUE(adapted.keypoint_input);
  EXPECT_EQ(adapted.lift_width, 48);
  EXPECT_EQ(adapted.lift_layers, 3);
  EXPECT_EQ(network_config_yaml(adapted), network_config_yaml(model.network));
  const PhysicsConfig adapted_physics = load_training_config((fs::path(o.out) / "config.yaml").string()).physics;
  EXPECT_EQ(adapted_physics.ray_stiffness, 40);
  EXPECT_EQ(adapted_physics.ray_max_pixels, 4);
  EXPECT_FALSE(adapted_physics.freeze_batch_norm);
  EXPECT_EQ(physics_config_yaml(adapted_physics), physics_config_yaml(cfg.physics));
}

TEST(ModelFolder, CarriesTheSimulationOfItsDataset) {
  // model.yaml holds the training dataset's simulation section, which is the recipe's: the
  // folder needs neither the recipe nor the dataset to resolve collisions.
  const Fixture& f = fixture();
  const ModelFolder model = read_model_folder(f.model.string());
  ASSERT_TRUE(model.simulation.has_value());
  EXPECT_EQ(*model.simulation, read_dataset_simulation(f.data.string()));
  EXPECT_EQ(*model.simulation, load_synth_config(repo_file("configs/synth/tiny.yaml")).simulation);
}

TEST(Infer, ResolvesCollisionsWhenAsked) {
  const Fixture& f = fixture();
  CaptureOptions o = view_capture(f, "cam04");
  o.resolve_collisions = true;
  o.out = (infer_scratch_root() / "resolved").string();
  const CaptureSummary s = capture_sequence(o);
  EXPECT_TRUE(s.part_seconds.count("collisions"));
  EXPECT_LE(s.penetration_after, 1e-3 / s.metres_per_unit);  // ≤ 1 mm
  std::ifstream in(fs::path(o.out) / "capture.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_TRUE(j["collisions_resolved"].get<bool>());
  for (const auto& frame : j["frames"]) {
    EXPECT_LE(frame["collisions"]["max_depth_after"].get<double>(), frame["collisions"]["max_depth_before"].get<double>() + 1e-12);
  }
}

// refine: each frame's PoseNet output moves to fit the input view's detections (here an
// untrained network's, far from them): their error falls, capture.json records it, and a
// heavy prior holds the network's output.
TEST(Infer, FittingThePosesToTheDetectionsBringsTheSkeletonToThem) {
  const Fixture& f = fixture();
  const fs::path root = infer_scratch_root() / "refine";
  fs::create_directories(root);
  auto capture = [&](const std::string& name, const std::string& refine) {
    CaptureOptions o = view_capture(f, "cam02");
    o.config = (root / (name + ".yaml")).string();
    std::ofstream(o.config) << "refine: " << refine << "\noutput: {overlays: false, video: false}\n";
    o.out = (root / name).string();
    const CaptureSummary s = capture_sequence(o);
    std::ifstream in(root / name / "capture.json");
    const nlohmann::json j = nlohmann::json::parse(in);
    EXPECT_EQ(j["refine"]["frames"], s.refinement.frames) << name;
    EXPECT_DOUBLE_EQ(j["refine"]["keypoint_error_after_px"].get<double>(), s.refinement.error_after_px) << name;
    return s.refinement;
  };
  const PoseRefinementSummary fitted = capture("fitted", "{iterations: 150, prior: 0, lr: 0.05}");
  EXPECT_EQ(fitted.frames, 6);
  EXPECT_GT(fitted.error_before_px, 5.0) << "the untrained network misses the detections";
  EXPECT_LT(fitted.error_after_px, 0.5 * fitted.error_before_px);
  const PoseRefinementSummary held = capture("held", "{iterations: 150, prior: 1.0e+6, lr: 0.05}");
  EXPECT_NEAR(held.error_before_px, fitted.error_before_px, 1e-9) << "the same network output";
  EXPECT_GT(held.error_after_px, 0.9 * held.error_before_px) << "the prior keeps the network's pose";
  EXPECT_EQ(capture("off", "{iterations: 0}").frames, 0);
}

// refine.depth_prior: fitting the rest pose to a frame's detections moves the keypoints'
// depths (relative to MidHip, along the camera's axis) far less with the depth prior than
// without, while both still bring the skeleton to the detections.
TEST(Infer, TheDepthPriorLeavesTheDepthTheDetectionsCannotSee) {
  const Fixture& f = fixture();
  const Character character = load_character((f.model / "character" / "character.yaml").string());
  const TrainingConfig cfg = load_training_config((f.model / "config.yaml").string());
  const CaptureModel model(character, cfg.network);
  const DatasetInfo info = read_dataset_info(f.data.string());
  std::map<std::string, Camera> cameras;
  for (Camera& c : read_cameras_yaml((f.data / "cameras.yaml").string())) cameras[c.name] = c;
  std::vector<KeypointView> views;
  for (int frame : {0, 3})
    views.push_back({cameras.at(dataset_camera_name(info, frame, "cam02")),
                     read_dataset_keypoints(dataset_keypoints_path(info, frame, "cam02"))});
  const std::vector<Eigen::VectorXd> rest(views.size(), Eigen::VectorXd::Zero(model.pose_outputs()));
  // Keypoint depths relative to MidHip (metres) of outputs, for frame b.
  auto depths = [&](const std::vector<Eigen::VectorXd>& outputs, size_t b) {
    std::vector<std::vector<KeypointView>> one{{views[b]}};
    SampleViews placed;
    placed.input_rotations = {views[b].camera.R};
    placed.translation = root_translation_terms(one, model.keypoint_mask(), weft::DType::F32);
    std::vector<double> o(outputs[b].data(), outputs[b].data() + outputs[b].size());
    weft::NoGradGuard no_grad;
    const Vertices k = sample_vertices(
        model.predict(weft::Tensor::from_data({1, int64_t(o.size())}, o, weft::DType::F32), weft::Tensor(), placed, false)
            .keypoints, 0);
    Eigen::VectorXd z(kBody25Count);
    for (int m = 0; m < kBody25Count; ++m) z(m) = views[b].camera.R.row(2).dot(k.row(m) - k.row(8)) * character.metres_per_unit;
    return z;
  };
  PoseRefinementConfig rc;
  rc.iterations = 200, rc.prior = 0, rc.lr = 0.05, rc.depth_prior = 0;
  std::vector<Eigen::VectorXd> free = rest, held = rest;
  const PoseRefinementSummary a = refine_pose_outputs(model, views, free, rc);
  rc.depth_prior = 100;
  const PoseRefinementSummary b = refine_pose_outputs(model, views, held, rc);
  EXPECT_LT(a.error_after_px, 0.5 * a.error_before_px);
  EXPECT_LT(b.error_after_px, 0.7 * b.error_before_px) << "the image plane still fits";
  double moved_free = 0, moved_held = 0;
  for (size_t i = 0; i < views.size(); ++i) {
    const Eigen::VectorXd z0 = depths(rest, i);
    moved_free += (depths(free, i) - z0).norm(), moved_held += (depths(held, i) - z0).norm();
  }
  std::printf("keypoint depth change (m, norm over keypoints, sum over frames): free %.4f, depth prior %.4f\n", moved_free,
              moved_held);
  EXPECT_GT(moved_free, 0.05);
  EXPECT_LT(moved_held, 0.3 * moved_free);
}
