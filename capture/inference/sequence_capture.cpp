#include "capture/inference/sequence_capture.h"

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <filesystem>

#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/inference/capture_config.h"
#include "capture/model/pose_refinement.h"
#include "capture/inference/root_placement.h"
#include "capture/inference/sequence_input.h"
#include "capture/inference/silhouette_translation.h"
#include "capture/inference/temporal_filter.h"
#include "graph/atomic_file.h"
#include "geometry/mesh_io.h"
#include "capture/io/openpose.h"
#include "capture/io/png_file.h"
#include "capture/motion/skeleton_bvh.h"
#include "capture/render/renderer.h"
#include "capture/garment/garment_collision_resolution.h"
#include "capture/garment/garment_config.h"
#include "capture/model/capture_networks.h"
#include "capture/model/model_folder.h"
#include "graph/autograd.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

// Seconds per part; lap() charges the time since the last lap to a part.
struct PartClock {
  std::map<std::string, double> seconds;
  Clock::time_point t = Clock::now();
  void lap(const std::string& part) {
    const auto now = Clock::now();
    seconds[part] += std::chrono::duration<double>(now - t).count();
    t = now;
  }
};

// What pass 1 keeps of a frame for pass 2.
struct FrameRecord {
  int id = 0;
  std::string name;
  Camera camera;
  Body25 detections = Body25::Zero();
  int mapped_detections = 0;  // detected keypoints the character maps
  cv::Rect box;               // the mask's bounding box (empty: no foreground)
};

// What the writers need of a frame.
struct FrameOutput {
  int id = 0;
  Camera camera;
  Vertices body, cloth;
  cv::Mat image;  // the input frame (overlays and video), then the overlay drawn on it
};

Vertices rows_of(const Tensor& t, int64_t b) {  // [B,V,3] → V×3 of sample b
  const int64_t V = t.size(1);
  const Tensor f = t.to(DType::F64);
  const double* p = f.data<double>() + b * V * 3;
  return Eigen::Map<const Vertices>(p, V, 3);
}

class OverlayVideo {
 public:
  OverlayVideo(const fs::path& out, double fps) : out_(out), fps_(fps) {}
  void add(const cv::Mat& frame) {
    if (failed_) return;
    if (!writer_.isOpened()) {
      size_ = frame.size();
      for (const auto& [ext, fourcc] : {std::pair<const char*, int>{".mp4", cv::VideoWriter::fourcc('m', 'p', '4', 'v')},
                                        {".avi", cv::VideoWriter::fourcc('M', 'J', 'P', 'G')}}) {
        ext_ = ext;
        if (writer_.open(partial().string(), fourcc, fps_, size_)) break;
      }
      if (!writer_.isOpened()) {
        spdlog::warn("no video encoder available (MP4 or MJPG): the overlays stay PNG only");
        failed_ = true;
        return;
      }
    }
    if (frame.size() == size_) {
      writer_.write(frame);
    } else {
      cv::Mat resized;
      cv::resize(frame, resized, size_);
      writer_.write(resized);
    }
  }
  // The finished file ("" when none was written).
  std::string finish() {
    if (!writer_.isOpened()) return "";
    writer_.release();
    const fs::path final_path = out_ / ("overlay" + ext_);
    fs::rename(partial(), final_path);
    return final_path.string();
  }
  ~OverlayVideo() {
    if (writer_.isOpened()) {
      writer_.release();
      std::error_code ec;
      fs::remove(partial(), ec);
    }
  }

 private:
  fs::path partial() const { return out_ / ("overlay.partial" + ext_); }
  fs::path out_;
  double fps_;
  cv::VideoWriter writer_;
  cv::Size size_;
  std::string ext_;
  bool failed_ = false;
};


using Progress = std::function<void(const std::string&, int, int)>;

// What the stages share: the options, the configuration, the character, the output folder,
// the clock and the progress callback.
struct CaptureContext {
  const CaptureOptions& o;
  const CaptureConfig& cfg;
  const Character& character;
  const fs::path& out;
  PartClock& clock;
  const Progress& progress;
};

// What pass 1 gives pass 2: per frame its record and the networks' outputs.
struct NetworkOutputs {
  std::vector<FrameRecord> frames;
  std::vector<Eigen::VectorXd> pose_rows, deformation_rows;
};

// What the model's person detector gave a frame, kept so that the capture can be looked at
// and repeated: OUT/detections/keypoints/<name>_keypoints.json (OpenPose) and
// OUT/detections/masks/<name>.png, as `weft detect` writes them; only the inputs the
// detector made (not those read from --keypoints or --masks).
void write_detector_inputs(const fs::path& out, const SequenceInput& input, const SequenceFrame& f) {
  if (input.keypoints_from() == InputSource::detector) {
    OpenPoseFrame json;
    if (f.has_detections) json.people.push_back(f.detections);
    write_openpose_json((out / kDetectionsFolder / "keypoints" / (f.frame.name + "_keypoints.json")).string(), json);
  }
  if (input.masks_from() == InputSource::detector)
    write_png_atomically((out / kDetectionsFolder / "masks" / (f.frame.name + ".png")).string(), f.mask);
}

// Pass 1: crops and both networks, batched.
NetworkOutputs run_networks(const CaptureContext& c, const NetworkConfig& network, CaptureNetworks& nets,
                            const std::vector<double>& keypoint_mask, SequenceInput& input) {
  const CaptureOptions& o = c.o;
  PartClock& clock = c.clock;
  DatasetOptions crop_options;
  crop_options.input_size = network.input_size;
  crop_options.margin = network.margin;
  NetworkOutputs net;
  std::vector<FrameRecord>& frames = net.frames;
  const int total = o.max_frames >= 0 ? std::min(o.max_frames, input.source().size()) : input.source().size();
  bool more = true;
  while (more) {
    std::vector<Sample> samples;
    while (int(samples.size()) < c.cfg.batch_size) {
      if (o.max_frames >= 0 && int(frames.size()) >= o.max_frames) { more = false; break; }
      SequenceFrame f;
      if (!input.next(f, &clock.seconds)) { more = false; break; }
      FrameRecord r;
      r.id = f.frame.id;
      r.name = f.frame.name;
      r.camera = f.camera;
      r.box = cv::boundingRect(f.mask);
      r.detections = f.detections;
      r.mapped_detections = mapped_detection_count(r.detections, keypoint_mask);
      write_detector_inputs(c.out, input, f);
      clock.lap("write");
      samples.push_back(prepare_sample(f.frame.bgr, f.mask, r.detections, r.camera, crop_options));
      frames.push_back(r);
      clock.lap("crop");
      if (c.progress) c.progress("networks", int(frames.size()), std::max(total, int(frames.size())));
    }
    if (samples.empty()) break;
    const Batch batch = make_batch(samples);
    NoGradGuard no_grad;
    const Tensor pose = nets.pose(batch).to(DType::F64);
    const Tensor deformation = nets.deformation_net->forward(batch.images).to(DType::F64);
    for (int b = 0; b < batch.size(); ++b) {
      net.pose_rows.push_back(Eigen::Map<const Eigen::VectorXd>(pose.data<double>() + b * pose.size(1), pose.size(1)));
      net.deformation_rows.push_back(
          Eigen::Map<const Eigen::VectorXd>(deformation.data<double>() + b * deformation.size(1), deformation.size(1)));
    }
    clock.lap("networks");
  }
  WEFT_CHECK(!frames.empty(), o.input, ": no frames read");
  return net;
}

// The networks' outputs after the temporal filter: a row per frame.
struct FilteredOutputs {
  Eigen::MatrixXd pose, deformation;
};

// The temporal filter on the network outputs.
FilteredOutputs filter_outputs(const NetworkOutputs& net, const CaptureConfig& cfg) {
  std::vector<int> ids;
  for (const FrameRecord& r : net.frames) ids.push_back(r.id);
  auto stack = [](const std::vector<Eigen::VectorXd>& rows) {
    Eigen::MatrixXd m(Eigen::Index(rows.size()), rows[0].size());
    for (size_t i = 0; i < rows.size(); ++i) m.row(Eigen::Index(i)) = rows[i].transpose();
    return m;
  };
  FilteredOutputs out;
  out.pose = gaussian_filter_frames(stack(net.pose_rows), ids, cfg.filter_sigma_frames, cfg.filter_radius_frames);
  out.deformation =
      gaussian_filter_frames(stack(net.deformation_rows), ids, cfg.filter_sigma_frames, cfg.filter_radius_frames);
  return out;
}

// The garment's collision resolver with --resolve-collisions, else none.
std::unique_ptr<GarmentCollisionResolver> collision_resolver(const CaptureOptions& o, const ModelFolder& model,
                                                             const Character& character) {
  if (!o.resolve_collisions) return nullptr;
  WEFT_CHECK(character.has_cloth(), model.character, ": --resolve-collisions needs a garment");
  WEFT_CHECK(model.simulation.has_value(), o.model,
             "/model.yaml: missing key 'simulation', so no garment material for --resolve-collisions (the model "
             "was trained on a dataset without one: regenerate it with weft synth and train again)");
  return std::make_unique<GarmentCollisionResolver>(character, *model.simulation);
}

// The deformation layer on frames [start, start + B): the filtered outputs, each frame's
// input rotation and its root translation from the keypoint rays (frames with two or more
// mapped detections).
CapturePrediction deform_batch(const CaptureModel& capture_model, const FilteredOutputs& filtered,
                               const std::vector<FrameRecord>& frames, int start, int B) {
  std::vector<double> pose_values, deformation_values;
  std::vector<Eigen::Matrix3d> rotations;
  std::vector<std::vector<KeypointView>> views(static_cast<size_t>(B));
  for (int b = 0; b < B; ++b) {
    const FrameRecord& r = frames[size_t(start + b)];
    for (Eigen::Index k = 0; k < filtered.pose.cols(); ++k) pose_values.push_back(filtered.pose(start + b, k));
    for (Eigen::Index k = 0; k < filtered.deformation.cols(); ++k)
      deformation_values.push_back(filtered.deformation(start + b, k));
    rotations.push_back(r.camera.R);
    if (r.mapped_detections >= 2) views[size_t(b)].push_back({r.camera, r.detections});
  }
  SampleViews placed;
  placed.input_rotations = rotations;
  placed.translation = root_translation_terms(views, capture_model.keypoint_mask(), DType::F32);
  const Tensor pose = Tensor::from_data({B, filtered.pose.cols()}, pose_values, DType::F32);
  const Tensor deformation = Tensor::from_data({B, filtered.deformation.cols()}, deformation_values, DType::F32);
  NoGradGuard no_grad;
  return capture_model.predict(pose, deformation, placed, true);
}

// Resolves the cloth's collisions with the body; the summary keeps the deepest penetration
// before and after. The frame's record of it for capture.json (character units).
nlohmann::json resolve_frame_collisions(GarmentCollisionResolver& resolver, double metres_per_unit,
                                        const Vertices& body, Vertices& cloth, CaptureSummary& summary) {
  const GarmentCollisionResolution resolved = resolver.resolve(body, cloth);
  cloth = resolved.cloth;
  const double to_units = 1.0 / metres_per_unit;
  summary.penetration_before = std::max(summary.penetration_before, resolved.pass.before.max_depth * to_units);
  summary.penetration_after = std::max(summary.penetration_after, resolved.pass.after.max_depth * to_units);
  return {{"max_depth_before", resolved.pass.before.max_depth * to_units},
          {"max_depth_after", resolved.pass.after.max_depth * to_units},
          {"vertices_inside_before", resolved.pass.before.vertices_inside},
          {"vertices_inside_after", resolved.pass.after.vertices_inside}};
}

// What pass 2 gives the files at the end: the motion, the skeleton's global transforms per
// frame and the frame list of capture.json.
struct PlacedFrames {
  Motion motion;
  std::vector<Transforms> globals;
  nlohmann::json frame_list = nlohmann::json::array();
};

// Frame i's dofs: the root chain placed at the predicted rotation and translation, from the
// previous frame's dofs.
void place_root(const RootPlacement& placement, const Skeleton& skeleton, const FrameRecord& r, int i,
                const Eigen::VectorXd& rest_root, const Eigen::Matrix3d& rotation,
                const Eigen::Vector3d& translation, PlacedFrames& placed) {
  Motion& motion = placed.motion;
  Eigen::VectorXd previous;
  if (i > 0) previous = motion.dofs.row(i - 1).transpose();
  double residual = 0;
  motion.dofs.row(i) = placement.place(rest_root, rotation, translation, i > 0 ? &previous : nullptr, &residual).transpose();
  if (residual > 1e-6) spdlog::warn("frame {}: the root chain reproduces the placement only to {:.2g}", r.name, residual);
  motion.frame_ids.push_back(r.id);
  placed.globals.push_back(forward_kinematics(skeleton, motion.dofs.row(i).transpose()));
}

// A batch's files, frames in parallel (the networks are done: both cores are free): the
// meshes in every format and, where the frame was read again, the overlay drawn on it.
void write_batch_files(const CaptureContext& c, std::vector<FrameOutput>& outputs) {
  const Character& character = c.character;
  const CaptureConfig& cfg = c.cfg;
  const fs::path& out = c.out;
  const RenderOptions render_options;
  tbb::parallel_for(0, int(outputs.size()), [&](int b) {
    FrameOutput& w = outputs[size_t(b)];
    const std::string id = dataset_frame_name(w.id);
    TriangleMesh body_mesh = character.body.mesh, cloth_mesh;
    body_mesh.colors.resize(0, 3);
    body_mesh.V = w.body;
    if (w.cloth.rows()) {
      cloth_mesh = character.cloth->mesh;
      cloth_mesh.colors.resize(0, 3);
      cloth_mesh.V = w.cloth;
    }
    for (const std::string& format : cfg.mesh_formats) {
      write_mesh((out / "meshes" / ("body_" + id + "." + format)).string(), body_mesh);
      if (w.cloth.rows()) write_mesh((out / "meshes" / ("cloth_" + id + "." + format)).string(), cloth_mesh);
    }
    if (w.image.empty()) return;
    std::vector<RenderMesh> meshes = {{&character.body.mesh, &w.body, 1}};
    meshes[0].color = cv::Scalar(200, 170, 140);
    if (w.cloth.rows()) {
      meshes.push_back({&character.cloth->mesh, &w.cloth, 2});
      meshes[1].color = cv::Scalar(60, 120, 230);
    }
    const RenderResult drawn = render(w.camera, meshes, render_options);
    cv::Mat blended;
    cv::addWeighted(drawn.rgb, cfg.overlay_alpha, w.image, 1 - cfg.overlay_alpha, 0, blended);
    blended.copyTo(w.image, drawn.mask);
    if (cfg.overlays) write_png_atomically((out / "overlays" / (id + ".png")).string(), w.image);
  });
}

// Pass 2: the deformation layer, placement and files, batch by batch; the video gains the
// overlays.
PlacedFrames place_and_write(const CaptureContext& c, const CaptureModel& capture_model,
                             const std::vector<FrameRecord>& frames, const FilteredOutputs& filtered,
                             GarmentCollisionResolver* resolver, FrameSource& source, OverlayVideo& video,
                             CaptureSummary& summary) {
  const Character& character = c.character;
  const CaptureConfig& cfg = c.cfg;
  PartClock& clock = c.clock;
  const int n = int(frames.size());
  source.rewind();
  const RootPlacement placement(character);
  PlacedFrames placed;
  placed.motion.dofs.resize(n, character.skeleton.num_dofs());
  int written = 0;
  for (int start = 0; start < n; start += cfg.batch_size) {
    const int B = std::min(cfg.batch_size, n - start);
    const CapturePrediction p = deform_batch(capture_model, filtered, frames, start, B);
    const Tensor dofs = p.dofs.to(DType::F64), R = p.rotation.to(DType::F64),
                 t = p.translation.to(DType::F64);
    clock.lap("deform");
    std::vector<FrameOutput> outputs(static_cast<size_t>(B));
    for (int b = 0; b < B; ++b) {
      const FrameRecord& r = frames[size_t(start + b)];
      Vertices body = rows_of(p.body, b);
      Vertices cloth = character.has_cloth() ? rows_of(p.cloth, b) : Vertices();
      Eigen::Vector3d translation = Eigen::Map<const Eigen::Vector3d>(t.data<double>() + 3 * b);
      const bool from_keypoints = r.mapped_detections >= 2;
      if (!from_keypoints && !r.box.empty()) {
        // No rays constrained the solve: the translation is 0; place it by the silhouette.
        const Eigen::Vector3d shift = translation_from_silhouette(r.camera, body, r.box) ;
        body.rowwise() += shift.transpose();
        if (cloth.rows()) cloth.rowwise() += shift.transpose();
        translation += shift;
      }
      ++(from_keypoints ? summary.translations_from_keypoints : summary.translations_from_silhouette);
      clock.lap("deform");
      nlohmann::json collisions;
      if (resolver) {
        collisions = resolve_frame_collisions(*resolver, character.metres_per_unit, body, cloth, summary);
        clock.lap("collisions");
      }
      Eigen::Matrix3d rotation;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) rotation(i, j) = R.data<double>()[b * 9 + i * 3 + j];
      const Eigen::VectorXd rest_root = Eigen::Map<const Eigen::VectorXd>(dofs.data<double>() + b * dofs.size(1), dofs.size(1));
      place_root(placement, character.skeleton, r, start + b, rest_root, rotation, translation, placed);
      clock.lap("place");

      FrameOutput& w = outputs[size_t(b)];
      w.id = r.id;
      w.camera = r.camera;
      w.body = std::move(body);
      w.cloth = std::move(cloth);
      if (cfg.overlays || cfg.video) {
        InputFrame f;
        WEFT_CHECK(source.next(f) && f.id == r.id, c.o.input, ": frame ", r.name, " could not be read again");
        w.image = f.bgr;
      }
      placed.frame_list.push_back({{"id", r.id},
                                   {"source", r.name},
                                   {"pivot", {translation.x(), translation.y(), translation.z()}},
                                   {"translation_from", from_keypoints ? "keypoints" : r.box.empty() ? "none" : "silhouette"}});
      if (resolver) placed.frame_list.back()["collisions"] = collisions;
      clock.lap("read");
    }
    write_batch_files(c, outputs);
    for (int b = 0; b < B; ++b) {
      if (cfg.video && !outputs[size_t(b)].image.empty()) video.add(outputs[size_t(b)].image);
      if (c.progress) c.progress("meshes", ++written, n);
    }
    clock.lap("write");
  }
  return placed;
}

// capture.json: what was captured from what, the frame list and the timing.
void write_capture_json(const CaptureContext& c, const ModelFolder& model, const SequenceInput& input, double fps,
                        const std::string& video_path, const nlohmann::json& frame_list,
                        const CaptureSummary& summary) {
  const CaptureOptions& o = c.o;
  nlohmann::json j;
  j["format"] = "weft-capture/1";
  j["model"] = fs::absolute(o.model).lexically_normal().string();
  j["weights"] = fs::absolute(model.weights).lexically_normal().string();
  j["character"] = fs::absolute(model.character).lexically_normal().string();
  j["metres_per_unit"] = c.character.metres_per_unit;
  j["input"] = fs::absolute(o.input).lexically_normal().string();
  j["camera"] = fs::absolute(o.camera).lexically_normal().string();
  j["view"] = input.cameras().name();
  j["masks"] = o.masks;
  j["keypoints"] = o.keypoints;
  j["masks_from"] = input_source_name(input.masks_from());
  j["keypoints_from"] = input_source_name(input.keypoints_from());
  const bool detected = input.masks_from() == InputSource::detector || input.keypoints_from() == InputSource::detector;
  j["detections"] = detected ? kDetectionsFolder : "";
  j["fps"] = fps;
  j["filter"] = {{"sigma_frames", c.cfg.filter_sigma_frames}, {"radius_frames", c.cfg.filter_radius_frames}};
  const PoseRefinementConfig& rc = c.cfg.refine;
  j["refine"] = {{"iterations", rc.iterations}, {"prior", rc.prior}, {"depth_prior", rc.depth_prior}, {"lr", rc.lr},
                 {"frames", summary.refinement.frames}, {"keypoint_error_before_px", summary.refinement.error_before_px},
                 {"keypoint_error_after_px", summary.refinement.error_after_px}};
  j["collisions_resolved"] = o.resolve_collisions;
  j["video"] = video_path.empty() ? "" : fs::path(video_path).filename().string();
  j["frames"] = frame_list;
  j["timing"] = {{"seconds", summary.seconds}, {"frames_per_second", summary.fps()}, {"parts", c.clock.seconds}};
  write_text_atomically((c.out / "capture.json").string(), j.dump(1) + "\n");
}
}  // namespace

CaptureSummary capture_sequence(const CaptureOptions& o,
                                const std::function<void(const std::string&, int, int)>& progress) {
  const auto t0 = Clock::now();
  PartClock clock;
  ModelFolder model = read_model_folder(o.model);
  if (!o.weights.empty()) {
    WEFT_CHECK(fs::is_regular_file(o.weights), "weft infer: --weights ", o.weights, ": no such file");
    model.weights = o.weights;
  }
  const CaptureConfig cfg = o.config.empty() ? CaptureConfig{} : load_capture_config(o.config);
  const Character character = load_character(model.character);
  CaptureNetworks nets(character, model.network, model.seed);
  load_capture_networks(model.weights, nets);
  nets.pose_net->train(false);
  nets.deformation_net->train(false);
  const CaptureModel capture_model(character, model.network);
  // Without --masks or --keypoints the model's person detector finds them, when it has one.
  SequenceInputOptions in{o.input, o.camera, o.camera_name, o.masks, o.keypoints, cfg.keying};
  if (in.wants_detector()) in.detector = nets.detector.get();
  SequenceInput input(in);
  WEFT_CHECK(!o.out.empty(), "weft infer: no output folder");
  const fs::path out(o.out);
  fs::create_directories(out / "meshes");
  if (cfg.overlays) fs::create_directories(out / "overlays");
  fs::remove_all(out / kDetectionsFolder);  // a previous capture's, possibly from other inputs
  if (input.keypoints_from() == InputSource::detector) fs::create_directories(out / kDetectionsFolder / "keypoints");
  if (input.masks_from() == InputSource::detector) fs::create_directories(out / kDetectionsFolder / "masks");
  const double fps = o.fps > 0 ? o.fps : input.source().fps() > 0 ? input.source().fps() : 30.0;
  spdlog::info("model {} ({} at {}², weights {}); character {}: {} body + {} cloth vertices", o.model,
               model.network.backbone, model.network.input_size, model.weights, character.name,
               character.body.mesh.num_vertices(), character.has_cloth() ? character.cloth->mesh.num_vertices() : 0);
  spdlog::info("{}", input.describe());
  clock.lap("load");
  const CaptureContext c{o, cfg, character, out, clock, progress};

  NetworkOutputs net = run_networks(c, model.network, nets, capture_model.keypoint_mask(), input);
  CaptureSummary summary;
  if (cfg.refine.iterations > 0) {
    std::vector<KeypointView> views;
    for (const FrameRecord& r : net.frames) views.push_back({r.camera, r.detections});
    summary.refinement = refine_pose_outputs(capture_model, views, net.pose_rows, cfg.refine);
    const PoseRefinementSummary& rs = summary.refinement;
    spdlog::info("poses fitted to the input view's detections: {} frames, mean keypoint error {:.2f} -> {:.2f} px "
                 "({} Adam steps, prior {:g}, {:.1f} s)",
                 rs.frames, rs.error_before_px, rs.error_after_px, cfg.refine.iterations, cfg.refine.prior, rs.seconds);
    clock.lap("refine");
  }
  const FilteredOutputs filtered = filter_outputs(net, cfg);
  clock.lap("filter");
  const std::unique_ptr<GarmentCollisionResolver> resolver = collision_resolver(o, model, character);

  summary.frames = int(net.frames.size());
  summary.metres_per_unit = character.metres_per_unit;
  OverlayVideo video(out, fps);
  const PlacedFrames placed =
      place_and_write(c, capture_model, net.frames, filtered, resolver.get(), input.source(), video, summary);
  write_motion((out / "pose.motion").string(), placed.motion);
  write_bvh((out / "pose.bvh").string(), skeleton_motion_bvh(character.skeleton, placed.globals, 1.0 / fps));
  const std::string video_path = video.finish();
  clock.lap("write");

  summary.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  summary.part_seconds = clock.seconds;
  write_capture_json(c, model, input, fps, video_path, placed.frame_list, summary);
  return summary;
}

}  // namespace weft::capture
