#include "capture/studio/synthetic_studio.h"

#include <tbb/parallel_for.h>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <mutex>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "capture/character/character.h"
#include "capture/character/skeletool_io.h"
#include "capture/dataset/synthetic_dataset.h"
#include "capture/io/camera.h"
#include "geometry/mesh_io.h"
#include "capture/io/openpose.h"
#include "capture/io/png_file.h"
#include "files/strict_yaml.h"
#include "files/text_reader.h"
#include "capture/motion/bvh.h"
#include "capture/motion/motion_retarget.h"
#include "capture/motion/procedural_motion.h"
#include "capture/garment/garment_simulator.h"
#include "graph/atomic_file.h"
#include "graph/error.h"
#include "physics/cloth_metrics.h"
#include "physics/cloth_simulator.h"
#include "physics/scene.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// mix_seed's stream for the wild camera takes of clips after the first; keypoint noise
// uses streams (view, frame), with small view ids.
constexpr uint64_t kWildTakeStream = 0x57494c4454414b45ull;  // "WILDTAKE"

// ------------------------------------------------------------------ config

// `key` names the section in messages: "motion", or "motions[k]" in a list of clips.
void parse_motion(const StrictYaml& y, const YAML::Node& n, const std::string& key, SynthMotionConfig& m) {
  if (!n.IsMap()) y.fail_at(n, key, "expected a motion section (procedural, bvh or skeletool, mapping, fps, ...)");
  const std::string k = key + ".";
  y.check_keys(n, k, {"procedural", "bvh", "mapping", "skeletool", "fps", "start", "frames", "stride", "in_place_s"});
  int sources = 0;
  if (n["procedural"]) m.procedural = y.path(n["procedural"], k + "procedural"), ++sources;
  if (n["bvh"]) m.bvh = y.path(n["bvh"], k + "bvh"), ++sources;
  if (n["skeletool"]) m.skeletool = y.path(n["skeletool"], k + "skeletool"), ++sources;
  if (sources != 1) y.fail_at(n, key, "expected exactly one of procedural, bvh or skeletool");
  if (n["mapping"]) m.mapping = y.path(n["mapping"], k + "mapping");
  if (m.skeletool.empty() && m.mapping.empty())
    y.fail_at(n, k + "mapping", "a procedural or BVH motion needs a retarget mapping (configs/retarget/*.yaml)");
  if (n["fps"]) m.fps = y.number(n["fps"], k + "fps", 1, 1000);
  if (n["start"]) m.start_s = y.number(n["start"], k + "start", 0, 1e6);
  if (n["frames"]) m.frames = static_cast<int>(y.number(n["frames"], k + "frames", 1, 1e6));
  if (n["stride"]) m.stride = static_cast<int>(y.number(n["stride"], k + "stride", 1, 1000));
  if (n["in_place_s"]) m.in_place_s = y.number(n["in_place_s"], k + "in_place_s", 0, 100);
}

// `motion:` (one clip) or `motions:` (a list of clips, each a motion section, one fps).
void parse_motions(const StrictYaml& y, const YAML::Node& root, SynthConfig& c) {
  const YAML::Node one = root["motion"], list = root["motions"];
  if (one && list)
    y.fail_at(list, "motions", "give either motion (one clip) or motions (a list of clips), not both");
  if (one) {
    c.motions.assign(1, SynthMotionConfig{});
    parse_motion(y, one, "motion", c.motions[0]);
    return;
  }
  if (!list) y.fail_at(root, "motion", "missing: the motion section (or motions: a list of them)");
  if (!list.IsSequence() || list.size() == 0)
    y.fail_at(list, "motions", "expected a list of motion sections (- {procedural: ..., mapping: ..., frames: ...})");
  c.motion_list = true;
  c.motions.assign(list.size(), SynthMotionConfig{});
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string key = "motions[" + std::to_string(i) + "]";
    parse_motion(y, list[i], key, c.motions[i]);
    // One dataset has one frame rate (dataset.yaml's fps, the simulator's time step).
    if (c.motions[i].fps != c.motions[0].fps) {
      std::ostringstream msg;
      msg << "every clip needs the same fps: motions[0] is at " << c.motions[0].fps << ", this one at "
          << c.motions[i].fps;
      y.fail_at(list[i]["fps"] ? list[i]["fps"] : list[i], key + ".fps", msg.str());
    }
  }
}

void parse_render(const StrictYaml& y, const YAML::Node& n, SynthRenderConfig& r) {
  y.check_keys(n, "render.", {"background", "photos", "lighting", "supersample", "dt_scale", "body_texture"});
  if (n["body_texture"]) r.body_texture = y.path(n["body_texture"], "render.body_texture");
  if (n["background"]) {
    const std::string b = y.get<std::string>(n["background"], "render.background", "green, clutter or photos");
    if (b == "green") r.background = BackgroundKind::solid;
    else if (b == "clutter") r.background = BackgroundKind::clutter;
    else if (b == "photos") r.background = BackgroundKind::image;
    else y.fail_at(n["background"], "render.background", "expected green, clutter or photos, found '" + b + "'");
  }
  if (n["photos"]) {
    if (r.background != BackgroundKind::image) y.fail_at(n["photos"], "render.photos", "needs background: photos");
    const std::string where = y.get<std::string>(n["photos"], "render.photos", "a folder or file of photos");
    const std::string full = (y.dir / where).lexically_normal().string();
    try {
      r.photos = list_photos(full, y.file + ": render.photos");
    } catch (const Error&) {
      y.fail_at(n["photos"], "render.photos",
                "no .jpg, .jpeg or .png photo at " + full +
                    " (Debian's mate-backgrounds has /usr/share/backgrounds/mate/nature: scripts/setup.sh installs it)");
    }
  }
  if (r.background == BackgroundKind::image && r.photos.empty())
    y.fail_at(n["background"], "render.background", "photos needs render.photos: a folder or file of photos");
  if (n["lighting"]) r.lighting = parse_studio_lighting(y, n["lighting"], "render.lighting");
  if (n["supersample"]) {
    r.supersample = static_cast<int>(y.number(n["supersample"], "render.supersample", 1, 7));
    if (r.supersample % 2 == 0) y.fail_at(n["supersample"], "render.supersample", "expected an odd number 1..7");
  }
  if (n["dt_scale"]) r.dt_scale = y.number(n["dt_scale"], "render.dt_scale", 1, 256);
}

Eigen::Vector3d vec3(const StrictYaml& y, const YAML::Node& n, const std::string& key) {
  if (!n.IsSequence() || n.size() != 3) y.fail_at(n, key, "expected [x, y, z] in metres");
  return {y.number(n[0], key), y.number(n[1], key), y.number(n[2], key)};
}

void parse_camera_setup(const StrictYaml& y, const YAML::Node& n, SynthCameraConfig& c) {
  if (n["rig"]) {
    const std::string r = y.get<std::string>(n["rig"], "cameras.rig", "studio or wild");
    if (r == "studio") c.kind = CameraRigKind::studio;
    else if (r == "wild") c.kind = CameraRigKind::wild;
    else y.fail_at(n["rig"], "cameras.rig", "expected studio or wild, found '" + r + "'");
  }
  if (c.kind == CameraRigKind::studio) {
    StudioRigConfig& s = c.studio;
    y.numbers(n, "cameras.",
                      {{"vertical_fov_deg", &s.vertical_fov_deg, 1, 170},
                       {"radius_m", &s.radius_m, 0.1, 100},
                       {"height_m", &s.height_m, -100, 100},
                       {"first_azimuth_deg", &s.first_azimuth_deg, -360, 360},
                       {"ring_spacing_m", &s.ring_spacing_m, 0, 100},
                       {"k1", &s.k1, -1, 1}},
                      {{"views", &s.views, 1, 72}, {"width", &s.width, 16, 8192}, {"height", &s.height, 16, 8192},
                       {"rings", &s.rings, 0, 72}},
                      {"rig", "target_m"});
    if (n["target_m"]) s.target_m = vec3(y, n["target_m"], "cameras.target_m");
  } else {
    WildCameraConfig& w = c.wild;
    y.numbers(n, "cameras.",
                      {{"vertical_fov_deg", &w.vertical_fov_deg, 1, 170},
                       {"radius_start_m", &w.radius_start_m, 0.1, 100},
                       {"radius_end_m", &w.radius_end_m, 0.1, 100},
                       {"height_m", &w.height_m, -100, 100},
                       {"start_azimuth_deg", &w.start_azimuth_deg, -360, 360},
                       {"arc_deg", &w.arc_deg, -720, 720},
                       {"shake_position_m", &w.shake_position_m, 0, 1},
                       {"shake_rotation_deg", &w.shake_rotation_deg, 0, 30},
                       {"shake_frequency_hz", &w.shake_frequency_hz, 0, 100},
                       {"k1", &w.k1, -1, 1},
                       {"exposure_min", &w.exposure_min, 0.01, 10},
                       {"exposure_max", &w.exposure_max, 0.01, 10},
                       {"exposure_frequency_hz", &w.exposure_frequency_hz, 0, 100},
                       {"follow_smoothing_s", &w.follow_smoothing_s, 0, 100}},
                      {{"width", &w.width, 16, 8192}, {"height", &w.height, 16, 8192}},
                      {"rig", "target_m", "follow_subject"});
    if (n["target_m"]) w.target_m = vec3(y, n["target_m"], "cameras.target_m");
    if (n["follow_subject"]) w.follow_subject = y.get<bool>(n["follow_subject"], "cameras.follow_subject", "true or false");
    if (w.exposure_min > w.exposure_max) y.fail_at(n, "cameras.exposure_min", "must not exceed exposure_max");
  }
}


void parse_splits(const StrictYaml& y, const YAML::Node& n, SynthConfig& c) {
  y.check_keys(n, "splits.", {"val", "test", "place"});
  if (n["val"]) c.val_fraction = y.number(n["val"], "splits.val", 0, 1);
  if (n["test"]) c.test_fraction = y.number(n["test"], "splits.test", 0, 1);
  if (n["place"]) c.split_place = y.number(n["place"], "splits.place", 0, 1);
  if (c.val_fraction + c.test_fraction > 1) y.fail_at(n, "splits", "val + test must not exceed 1");
}

// ------------------------------------------------------------------ motion

// Clip `clip`'s motion frames from its start to its last dataset frame (stride included).
Motion load_dataset_motion(const SynthConfig& cfg, size_t clip, const Character& character,
                           const std::function<void(const SynthProgress&)>& progress) {
  const SynthMotionConfig& m = cfg.motions[clip];
  const std::string key = cfg.motion_key(clip);
  // One bar per clip: each retargeting counts its own frames.
  const std::string stage = cfg.motions.size() == 1 ? "motion"
                                                    : "motion " + std::to_string(clip + 1) + "/" +
                                                          std::to_string(cfg.motions.size());
  const int needed = (m.frames - 1) * m.stride + 1;  // motion frames at m.fps
  if (!m.skeletool.empty()) {
    Motion all = read_motion(m.skeletool, character.skeleton.num_dofs());
    const int first = static_cast<int>(std::lround(m.start_s * m.fps));
    WEFT_CHECK(first + needed <= all.num_frames(), m.skeletool, ": ", all.num_frames(), " frames, but ", cfg.file,
               " asks for ", needed, " from frame ", first, " (", key, ".start ", m.start_s, " s at ", m.fps, " fps)");
    Motion out;
    out.dofs = all.dofs.middleRows(first, needed);
    for (int i = 0; i < needed; ++i) out.frame_ids.push_back(i);
    return out;
  }
  BvhMotion source;
  if (!m.procedural.empty()) {
    source = generate_motion(load_motion_spec(m.procedural), m.fps);
  } else {
    source = read_bvh(m.bvh);
  }
  const double duration = source.frame_time_s * (source.num_frames() - 1);
  const double end_s = m.start_s + (needed - 1) / m.fps;
  WEFT_CHECK(end_s <= duration + 1e-9, cfg.file, ": ", key, ".frames ", m.frames, " (stride ", m.stride, ") from ",
             m.start_s, " s need ", end_s, " s of motion, but ", source.source.empty() ? m.procedural : source.source,
             " lasts ", duration, " s");
  RetargetOptions o;
  o.fps = m.fps;
  o.start_s = m.start_s;
  o.end_s = end_s + 0.5 / m.fps;
  o.progress = [&](int done, int total) {
    if (progress) progress({stage, done, total});
  };
  RetargetResult r = retarget_motion(source, load_retarget_mapping(m.mapping), character, o);
  WEFT_CHECK(r.motion.num_frames() >= needed, cfg.file, ": ", key, ": retargeting gave ", r.motion.num_frames(),
             " frames, ", needed, " needed");
  Motion out;
  out.dofs = r.motion.dofs.topRows(needed);
  for (int i = 0; i < needed; ++i) out.frame_ids.push_back(i);
  return out;
}

// Takes the root's horizontal path, smoothed over sigma_frames, away from dofs (frames × D):
// the root translations are the dofs driving only prismatic joints with nothing but
// prismatic joints above them, so their axes are world axes (Y up) and a shift of the
// whole body is a linear map of them.
void take_away_horizontal_path(const Skeleton& skeleton, Eigen::MatrixXd& dofs, double sigma_frames,
                               const std::string& where) {
  std::vector<bool> translation_only(skeleton.num_joints());
  for (int j = 0; j < skeleton.num_joints(); ++j) {
    const Joint& joint = skeleton.joints[j];
    translation_only[j] =
        joint.type == JointType::prismatic && (joint.parent < 0 || translation_only[joint.parent]);
  }
  std::vector<int> root;
  std::vector<Eigen::Vector3d> columns;  // world displacement per unit of each root dof
  for (int d = 0; d < skeleton.num_dofs(); ++d) {
    const Dof& dof = skeleton.dofs[d];
    bool only = !dof.joints.empty();
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const DofInfluence& inf : dof.joints) {
      only = only && translation_only[inf.joint];
      c += inf.weight * skeleton.joints[inf.joint].axis;
    }
    if (only) root.push_back(d), columns.push_back(c);
  }
  Eigen::MatrixXd A(3, root.size());
  for (size_t i = 0; i < root.size(); ++i) A.col(i) = columns[i];
  Eigen::MatrixXd horizontal(2, root.size());
  horizontal << A.row(0), A.row(2);
  WEFT_CHECK(!root.empty() && horizontal.fullPivLu().rank() == 2, where,
             ": the character's skeleton has no root translation dofs that move it over the ground (x and z)");
  const Eigen::MatrixXd pinv = A.completeOrthogonalDecomposition().pseudoInverse();
  std::vector<Eigen::Vector3d> track(dofs.rows());
  for (int f = 0; f < dofs.rows(); ++f) {
    Eigen::VectorXd q(root.size());
    for (size_t i = 0; i < root.size(); ++i) q[i] = dofs(f, root[i]);
    track[f] = A * q;
    track[f].y() = 0;  // heights (a jump, a squat) stay
  }
  const std::vector<Eigen::Vector3d> path = smooth_track(track, sigma_frames);
  for (int f = 0; f < dofs.rows(); ++f) {
    const Eigen::VectorXd dq = pinv * -path[f];
    for (size_t i = 0; i < root.size(); ++i) dofs(f, root[i]) += dq[i];
  }
}

// ------------------------------------------------------------------ helpers

std::string frame_file(const fs::path& dir, const std::string& view, int frame, const char* suffix) {
  return (dir / view / (dataset_frame_name(frame) + suffix)).string();
}

void make_dir(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  WEFT_CHECK(!ec && fs::is_directory(dir), dir.string(), ": cannot create the directory (", ec.message(), ")");
}

// Distance transform as 16-bit fixed point (docs/DATASET.md).
cv::Mat quantize_dt(const cv::Mat& dt, double scale) {
  cv::Mat out(dt.size(), CV_16UC1);
  for (int y = 0; y < dt.rows; ++y) {
    const float* src = dt.ptr<float>(y);
    uint16_t* dst = out.ptr<uint16_t>(y);
    for (int x = 0; x < dt.cols; ++x) dst[x] = static_cast<uint16_t>(std::min(65535.0, std::round(src[x] * scale)));
  }
  return out;
}

TriangleMesh with_vertices(const TriangleMesh& mesh, const Vertices& V) {
  TriangleMesh out;
  out.V = V;
  out.F = mesh.F;
  return out;
}

// A contact sheet (at most 4 columns, tiles of at most 256 px) with keypoints drawn (green
// visible, orange low confidence) and mask outlines: every view of the middle frame, or
// with fewer than 4 views (a moving camera) up to 8 frames spread over the sequence.
cv::Mat preview_sheet(const fs::path& out, const std::vector<std::string>& views, int frames) {
  std::vector<std::pair<int, int>> tiles;  // (view, frame)
  if (views.size() >= 4) {
    for (int v = 0; v < static_cast<int>(views.size()); ++v) tiles.push_back({v, frames / 2});
  } else {
    const int shown = std::min(frames, 8);
    for (int v = 0; v < static_cast<int>(views.size()); ++v)
      for (int i = 0; i < shown; ++i) tiles.push_back({v, shown > 1 ? i * (frames - 1) / (shown - 1) : 0});
  }
  const int n = static_cast<int>(tiles.size()), cols = std::min(n, 4), rows = (n + cols - 1) / cols;
  cv::Mat sheet;
  for (int t = 0; t < n; ++t) {
    const int v = tiles[t].first, frame = tiles[t].second;
    cv::Mat image = cv::imread(frame_file(out / "images", views[v], frame, ".png"), cv::IMREAD_COLOR);
    const cv::Mat mask = cv::imread(frame_file(out / "masks", views[v], frame, ".png"), cv::IMREAD_GRAYSCALE);
    WEFT_CHECK(!image.empty() && !mask.empty(), out.string(), ": cannot read back frame ", frame, " of ", views[v]);
    std::vector<std::vector<cv::Point>> contours;
    cv::findContours(mask, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    cv::drawContours(image, contours, -1, cv::Scalar(255, 255, 255), 1);
    const OpenPoseFrame kp = read_openpose_json(frame_file(out / "keypoints", views[v], frame, "_keypoints.json"));
    for (const Body25& p : kp.people)
      for (int k = 0; k < kBody25Count; ++k)
        if (p(k, 2) > 0)
          cv::circle(image, cv::Point2d(p(k, 0), p(k, 1)), 2,
                     p(k, 2) >= 0.6 ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 140, 255), cv::FILLED);
    const double scale = std::min(1.0, 256.0 / std::max(image.cols, image.rows));
    if (scale < 1) cv::resize(image, image, cv::Size(), scale, scale, cv::INTER_AREA);
    cv::putText(image, views[v] + " " + dataset_frame_name(frame), cv::Point(4, 14), cv::FONT_HERSHEY_SIMPLEX, 0.4,
                cv::Scalar(255, 255, 255), 1);
    if (sheet.empty()) sheet = cv::Mat(rows * image.rows, cols * image.cols, CV_8UC3, cv::Scalar(0, 0, 0));
    image.copyTo(sheet(cv::Rect((t % cols) * image.cols, (t / cols) * image.rows, image.cols, image.rows)));
  }
  return sheet;
}

nlohmann::json finite_or_null(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); }

std::string yaml_int_list(const std::vector<int>& v) {
  std::ostringstream s;
  s << "[";
  for (size_t i = 0; i < v.size(); ++i) s << (i ? ", " : "") << v[i];
  s << "]";
  return s.str();
}


// ------------------------------------------------------------------ the stages of synthesize_dataset

using SynthProgressFn = std::function<void(const SynthProgress&)>;

// Character: generated, written into the dataset, used from memory.
DefaultCharacter make_dataset_character(const SynthConfig& cfg, const fs::path& out) {
  const DefaultCharacterConfig char_cfg = load_default_character_config(cfg.character);
  DefaultCharacter dc = make_default_character(char_cfg);
  write_default_character(dc, char_cfg, (out / "character").string());
  WEFT_CHECK(dc.character.has_cloth(), cfg.character, ": the character has no garment (garment.type none); the studio "
             "simulates and renders a garment");
  return dc;
}

// The ground-truth motion: the clips' frames one after another; clip k starts at dataset
// frame segments[k].
struct PosedMotion {
  int frames = 0;
  std::vector<int> segments;
  Motion gt;
  std::vector<PosedCharacter> posed;  // per frame
  int clips() const { return static_cast<int>(segments.size()); }
  int segment_end(int k) const { return k + 1 < clips() ? segments[k + 1] : frames; }
};

PosedMotion pose_motion(const SynthConfig& cfg, const Character& ch, const SynthProgressFn& progress) {
  PosedMotion pm;
  const int frames = pm.frames = cfg.frames();
  std::vector<PosedCharacter>& posed = pm.posed;
  Motion& gt = pm.gt;
  posed.reserve(frames);
  for (size_t k = 0; k < cfg.motions.size(); ++k) {
    const SynthMotionConfig& m = cfg.motions[k];
    const Motion motion = load_dataset_motion(cfg, k, ch, progress);
    if (k == 0) gt.dofs.resize(frames, motion.dofs.cols());
    const int first = static_cast<int>(posed.size());
    pm.segments.push_back(first);
    Eigen::MatrixXd clip(m.frames, motion.dofs.cols());
    for (int i = 0; i < m.frames; ++i) clip.row(i) = motion.dofs.row(i * m.stride);
    if (m.in_place_s >= 0)
      take_away_horizontal_path(ch.skeleton, clip, m.in_place_s * m.fps,
                                cfg.file + ": " + cfg.motion_key(k) + ".in_place_s");
    gt.dofs.middleRows(first, m.frames) = clip;
    for (int i = 0; i < m.frames; ++i) {
      const int f = first + i;
      gt.frame_ids.push_back(f);
      const Eigen::VectorXd dofs = gt.dofs.row(f).transpose();
      WEFT_CHECK(dofs.allFinite(), cfg.file, ": ", cfg.motion_key(k), " has a non-finite dof at dataset frame ", f);
      posed.push_back(pose_character(ch, dofs));
    }
  }
  return pm;
}

// The ground-truth cloth per frame, and metrics.json's record of each frame.
struct ClothTrack {
  std::vector<Vertices> cloth;
  nlohmann::json metric_frames = nlohmann::json::array();
};

// Frame f's report of a simulation step r with metrics m, and its metrics.json record.
nlohmann::json step_record(int f, const physics::StepResult& r, const physics::FrameMetrics& m,
                           const SynthSimulationConfig& s, SynthFrameReport& rep) {
  rep.frame = f;
  rep.status = physics::to_string(r.status);
  rep.newton_iterations = r.newton_iterations;
  rep.penetration_max = m.penetration_max;
  rep.oob_force_max_rel = m.oob_force_max_rel;
  // Failed: ended more than 10× Newton's tolerance from equilibrium (a step stopped by the
  // iteration cap or the line search close to it is kept), non-finite, or too deep.
  const bool near_converged =
      r.status == physics::StepStatus::converged ||
      (r.status != physics::StepStatus::non_finite && r.last.residual <= 10 * s.tolerance);
  rep.failed = !near_converged || m.penetration_max > s.max_penetration || !r.x.allFinite();
  physics::FrameRecord rec;
  rec.frame = f;
  rec.status = r.status;
  rec.newton_iterations = r.newton_iterations;
  rec.gradient_norm = r.gradient_norm;
  rec.energy = r.energy;
  rec.metrics = m;
  nlohmann::json entry = physics::frame_record_json(rec, /*with_timing=*/false);
  entry["failed"] = rep.failed;
  entry["substeps"] = r.substeps;  // of the attempt kept (adaptive, then halved on retries)
  entry["residual"] = finite_or_null(r.last.residual);
  return entry;
}

// Simulates clip k's garment: settled on the clip's first pose, then stepped over its
// frames; `done` of `total` counts the simulation's progress.
void simulate_clip(const SynthConfig& cfg, const Character& ch, const PosedMotion& pm, int k,
                   const std::vector<int>& anchors, const SynthProgressFn& progress, int total, int& done,
                   ClothTrack& track, SynthSummary& summary) {
  const SynthSimulationConfig& s = cfg.simulation;
  const double mpu = ch.metres_per_unit;
  const std::vector<PosedCharacter>& posed = pm.posed;
  auto body_metres = [&](int f) -> Eigen::MatrixX3d { return posed[f].body * mpu; };
  auto pin_targets = [&](int f) { return garment_pin_targets(ch, posed[f].cloth); };
  const int first = pm.segments[k], end = pm.segment_end(k);
  const std::unique_ptr<physics::ClothSimulator> simulator =
      make_garment_simulator(ch, s, cfg.fps(), body_metres(first), pin_targets(first));
  physics::ClothSimulator& sim = *simulator;
  const double h = sim.settings().time_step;
  physics::Positions x2 = to_positions(posed[first].cloth, mpu), x1 = x2;
  Eigen::MatrixX3d body_prev = body_metres(first), body_now;
  // Settling: the garment falls into its rest drape on the clip's first pose.
  for (int i = 0; i < s.settle_frames; ++i) {
    physics::StepResult r = sim.step(x2, x1);
    x2 = std::move(x1);
    x1 = std::move(r.x);
    if (progress) progress({"simulation", ++done, total});
  }
  track.cloth[first] = to_vertices(x1, mpu);
  SynthFrameReport& settled = summary.reports[first];
  settled.frame = first;
  settled.status = s.settle_frames > 0 ? "settled" : "skinned";
  {
    physics::FrameMetrics m;
    physics::measure_penetration(sim, x1, m);
    settled.penetration_max = m.penetration_max;
    settled.failed = m.penetration_max > s.max_penetration;
    track.metric_frames.push_back({{"frame", first}, {"status", settled.status},
                                   {"penetration_max", m.penetration_max},
                                   {"min_signed_distance", finite_or_null(m.min_signed_distance)}});
  }
  for (int f = first + 1; f < end; ++f) {
    body_now = body_metres(f);
    sim.set_pins(anchors, pin_targets(f));
    physics::StepResult r = sim.step(x2, x1, &body_prev, &body_now);
    const physics::FrameMetrics m = physics::frame_metrics(sim, x2, x1, r.x, h);
    track.metric_frames.push_back(step_record(f, r, m, s, summary.reports[f]));
    track.cloth[f] = to_vertices(r.x, mpu);
    x2 = std::move(x1);
    x1 = std::move(r.x);
    body_prev = body_now;
    if (progress) progress({"simulation", ++done, total});
  }
}

// Ground-truth cloth: simulated over the motion (or skinned); a report per frame.
ClothTrack ground_truth_cloth(const SynthConfig& cfg, const Character& ch, const PosedMotion& pm,
                              const SynthProgressFn& progress, SynthSummary& summary) {
  const int frames = pm.frames;
  ClothTrack track;
  track.cloth.resize(frames);
  summary.reports.resize(frames);
  if (!cfg.simulation.enabled) {
    for (int f = 0; f < frames; ++f) {
      track.cloth[f] = pm.posed[f].cloth;
      summary.reports[f].frame = f;
    }
    return track;
  }
  const std::vector<int> anchors = garment_pin_vertices(ch);
  const int total = pm.clips() * cfg.simulation.settle_frames + frames - pm.clips();
  int done = 0;
  // Each clip is a simulation of its own, started like the first: the next clip's body
  // starts somewhere else, and one step across the boundary would tear the garment.
  for (int k = 0; k < pm.clips(); ++k) simulate_clip(cfg, ch, pm, k, anchors, progress, total, done, track, summary);
  return track;
}

// The cameras: per view its name and a camera per frame, and each frame's exposure.
struct CameraSetup {
  std::vector<std::string> views;
  std::vector<std::vector<Camera>> cameras;  // [view][frame]
  std::vector<double> exposure;
  int num_views() const { return static_cast<int>(views.size()); }
};

// The wild camera's path over every frame, and the frames' exposure. Each clip is a take of
// its own: the orbit starts again and follows that clip's subject (smoothing across a clip
// boundary would drag the camera after a jump).
std::vector<Camera> wild_cameras(const SynthConfig& cfg, double mpu, const PosedMotion& pm,
                                 std::vector<double>& exposure) {
  WildCameraConfig wild = cfg.cameras.wild;
  wild.metres_per_unit = mpu;
  std::vector<Camera> path;
  for (int k = 0; k < pm.clips(); ++k) {
    const int first = pm.segments[k], n = pm.segment_end(k) - first;
    std::vector<Eigen::Vector3d> subject_track(n);  // the body's vertex centroid, character units
    for (int i = 0; i < n; ++i) subject_track[i] = pm.posed[first + i].body.colwise().mean().transpose();
    const uint64_t seed = k == 0 ? cfg.seed : mix_seed(cfg.seed, kWildTakeStream, static_cast<uint64_t>(k));
    const std::vector<Camera> take = wild_camera_path(wild, n, cfg.fps(), seed, subject_track);
    const std::vector<double> light = wild_exposure(wild, n, cfg.fps(), seed);
    path.insert(path.end(), take.begin(), take.end());
    std::copy(light.begin(), light.end(), exposure.begin() + first);
  }
  for (int f = 0; f < pm.frames; ++f) path[f].name = "wild_" + dataset_frame_name(f);
  return path;
}

// The studio rig or the wild camera, written to cameras.yaml.
CameraSetup make_cameras(const SynthConfig& cfg, double mpu, const PosedMotion& pm, const fs::path& out) {
  const int frames = pm.frames;
  CameraSetup cs;
  cs.exposure.assign(frames, 1.0);
  if (cfg.cameras.kind == CameraRigKind::studio) {
    StudioRigConfig rig = cfg.cameras.studio;
    rig.metres_per_unit = mpu;
    const std::vector<Camera> cams = studio_rig(rig);
    for (const Camera& c : cams) {
      cs.views.push_back(c.name);
      cs.cameras.emplace_back(frames, c);
    }
    write_cameras_yaml((out / "cameras.yaml").string(), cams);
  } else {
    const std::vector<Camera> path = wild_cameras(cfg, mpu, pm, cs.exposure);
    cs.views.push_back("wild");
    cs.cameras.push_back(path);
    write_cameras_yaml((out / "cameras.yaml").string(), path);
  }
  return cs;
}

// What the renders take besides the meshes: the clutter background, per clip the lights
// and (photos) each view's background, and the body's texture.
struct RenderLooks {
  cv::Mat clutter;
  std::vector<int> clip_of;                       // per frame
  std::vector<Lighting> clip_lighting;            // per clip
  std::vector<std::vector<cv::Mat>> clip_photos;  // [clip][view]
  cv::Mat body_texture;
};

RenderLooks render_looks(const SynthConfig& cfg, const Character& ch, const PosedMotion& pm, const CameraSetup& cs) {
  const std::vector<std::vector<Camera>>& cameras = cs.cameras;
  RenderLooks looks;
  looks.clutter = cfg.render.background == BackgroundKind::clutter
                      ? cluttered_background(cameras[0][0].width, cameras[0][0].height, cfg.seed)
                      : cv::Mat();
  looks.clip_of.resize(pm.frames);
  looks.clip_photos.resize(pm.clips());
  for (int k = 0; k < pm.clips(); ++k) {
    std::fill(looks.clip_of.begin() + pm.segments[k], looks.clip_of.begin() + pm.segment_end(k), k);
    looks.clip_lighting.push_back(draw_lighting(cfg.render.lighting, cfg.seed, k));
    if (cfg.render.background == BackgroundKind::image)
      for (int v = 0; v < cs.num_views(); ++v)
        looks.clip_photos[k].push_back(draw_photo_background(cfg.render.photos, cameras[v][pm.segments[k]].width,
                                                             cameras[v][pm.segments[k]].height, cfg.seed, k, v));
  }
  if (!cfg.render.body_texture.empty()) {
    looks.body_texture = cv::imread(cfg.render.body_texture, cv::IMREAD_COLOR);
    WEFT_CHECK(!looks.body_texture.empty(), cfg.render.body_texture, ": cannot read the body texture (", cfg.file,
               ": render.body_texture)");
    WEFT_CHECK(ch.body.mesh.has_uv(), cfg.file, ": render.body_texture needs texture coordinates in the body mesh ",
               ch.body.path, ", which has none");
  }
  return looks;
}

// Frame f seen by view v: the body (skin, textured or painted) and the garment.
RenderResult render_view(const SynthConfig& cfg, const Character& ch, const Vertices& body_vertices,
                         const Vertices& cloth_vertices, const Camera& cam, const RenderLooks& looks,
                         double exposure, int f, int v) {
  const TriangleMesh& cloth_mesh = ch.cloth->mesh;
  RenderMesh body, garment;
  body.mesh = &ch.body.mesh;
  body.vertices = &body_vertices;
  body.part = 1;
  body.color = cv::Scalar(150, 175, 215);  // BGR: skin
  if (!looks.body_texture.empty()) {
    body.source = ColorSource::texture;
    body.texture = looks.body_texture;
  } else if (ch.body.mesh.has_colors()) {
    body.source = ColorSource::vertex;  // a painted character (appearance.h)
  }
  garment.mesh = &cloth_mesh;
  garment.vertices = &cloth_vertices;
  garment.part = 2;
  garment.color = cv::Scalar(60, 60, 190);  // BGR: a red skirt
  if (cloth_mesh.has_colors()) garment.source = ColorSource::vertex;
  RenderOptions o;
  o.supersample = cfg.render.supersample;
  o.lighting = looks.clip_lighting[looks.clip_of[f]];
  o.lighting.exposure = exposure;
  if (cfg.render.background == BackgroundKind::clutter) {
    o.background.kind = BackgroundKind::image;
    o.background.image = looks.clutter;
  } else if (cfg.render.background == BackgroundKind::image) {
    o.background.kind = BackgroundKind::image;
    o.background.image = looks.clip_photos[looks.clip_of[f]][v];
  }
  return render(cam, {body, garment}, o);
}

// Rendering, keypoints, files: (frame, view) pairs in parallel, each writing its own files.
// The wall time goes to the summary's rendering and writing seconds.
void render_dataset(const SynthConfig& cfg, const Character& ch, const PosedMotion& pm, const ClothTrack& track,
                    const CameraSetup& cs, const fs::path& out, const SynthProgressFn& progress,
                    SynthSummary& summary) {
  const int frames = pm.frames, num_views = cs.num_views();
  const std::vector<std::string>& views = cs.views;
  double render_seconds = 0, write_seconds = 0;
  std::mutex time_mutex;
  int rendered = 0;  // under time_mutex
  const RenderLooks looks = render_looks(cfg, ch, pm, cs);
  const auto t_render = Clock::now();
  tbb::parallel_for(0, frames * num_views, [&](int job) {
    const int f = job / num_views, v = job % num_views;
    const Camera& cam = cs.cameras[v][f];
    const auto a = Clock::now();
    const RenderResult r = render_view(cfg, ch, pm.posed[f].body, track.cloth[f], cam, looks, cs.exposure[f], f, v);
    const cv::Mat dt = distance_transform(r.mask);
    KeypointNoiseConfig noise = cfg.keypoints;
    noise.metres_per_unit = ch.metres_per_unit;
    const Body25 kp = synthesize_keypoints(cam, pm.posed[f].body25, r.depth, noise,
                                           mix_seed(cfg.seed, static_cast<uint64_t>(v), static_cast<uint64_t>(f)));
    const auto b = Clock::now();
    write_png_atomically(frame_file(out / "images", views[v], f, ".png"), r.rgb);
    write_png_atomically(frame_file(out / "masks", views[v], f, ".png"), r.mask);
    write_png_atomically(frame_file(out / "parts", views[v], f, ".png"), r.parts);
    write_png_atomically(frame_file(out / "dt", views[v], f, ".png"), quantize_dt(dt, cfg.render.dt_scale));
    OpenPoseFrame op;
    op.people.push_back(kp);
    write_openpose_json(frame_file(out / "keypoints", views[v], f, "_keypoints.json"), op);
    const auto c = Clock::now();
    // One lock for the times and the progress: the callback is never entered from two
    // threads at once (a caller's progress bar or map need not be thread-safe).
    std::lock_guard<std::mutex> lock(time_mutex);
    render_seconds += std::chrono::duration<double>(b - a).count();
    write_seconds += std::chrono::duration<double>(c - b).count();
    if (progress) progress({"rendering", ++rendered, frames * num_views});
  });
  const double render_wall = seconds_since(t_render);
  // Split the wall time of the parallel loop by the CPU-time shares of its two halves.
  const double busy = render_seconds + write_seconds;
  summary.seconds_rendering = busy > 0 ? render_wall * render_seconds / busy : 0;
  summary.seconds_writing = busy > 0 ? render_wall * write_seconds / busy : 0;
}

// Ground-truth meshes.
void write_ground_truth_meshes(const Character& ch, const PosedMotion& pm, const ClothTrack& track,
                               const fs::path& out) {
  for (int f = 0; f < pm.frames; ++f) {
    write_ply((out / "gt" / ("body_" + dataset_frame_name(f) + ".ply")).string(),
              with_vertices(ch.body.mesh, pm.posed[f].body));
    write_ply((out / "gt" / ("cloth_" + dataset_frame_name(f) + ".ply")).string(),
              with_vertices(ch.cloth->mesh, track.cloth[f]));
  }
}

// Splits: in each clip one held-out stretch (val, then test) placed at `split_place` of
// the clip (1: its end; 0.5: its middle), the rest train, so every split sees every
// motion; failed frames left out.
void split_frames(const SynthConfig& cfg, const PosedMotion& pm, SynthSummary& summary) {
  for (int k = 0; k < pm.clips(); ++k) {
    const ClipSplit split =
        split_clip(pm.segments[k], pm.segment_end(k), cfg.val_fraction, cfg.test_fraction, cfg.split_place);
    const auto keep = [&](const std::vector<int>& from, std::vector<int>& to) {
      for (int f : from)
        if (!summary.reports[f].failed) to.push_back(f);
    };
    keep(split.train, summary.train), keep(split.val, summary.val), keep(split.test, summary.test);
  }
}

// metrics.json: deterministic (no wall times; those go to timing.json).
void write_metrics_json(const SynthConfig& cfg, const Character& ch, const PosedMotion& pm, const ClothTrack& track,
                        const std::vector<int>& failed, const fs::path& out) {
  nlohmann::json doc = {{"frames", track.metric_frames},
                        {"summary",
                         {{"simulated", cfg.simulation.enabled},
                          {"cloth_vertices", ch.cloth->mesh.num_vertices()},
                          {"frames", pm.frames},
                          {"failed_frames", failed},
                          {"time_step", 1.0 / cfg.fps()},
                          {"substeps", cfg.simulation.substeps},
                          {"settle_frames", cfg.simulation.settle_frames}}}};
  if (pm.clips() > 1) doc["summary"]["segments"] = pm.segments;  // one clip: the file as before
  write_text_atomically((out / "metrics.json").string(), doc.dump(2) + "\n");
}

// dataset.yaml
void write_dataset_yaml(const SynthConfig& cfg, double mpu, const PosedMotion& pm, const CameraSetup& cs,
                        const SynthSummary& summary, const std::vector<int>& failed, const fs::path& out) {
  std::ostringstream y;
  y << "# Written by `weft synth` from " << cfg.file << " (layout: docs/DATASET.md).\n"
    << "format: weft-synth/1\n"
    << "name: " << cfg.name << "\n"
    << "seed: " << cfg.seed << "\n"
    << "fps: " << cfg.fps() << "\n"
    << "metres_per_unit: " << mpu << "\n"
    << "frames: " << pm.frames << "\n";
  if (pm.clips() > 1) y << "segments: " << yaml_int_list(pm.segments) << "\n";  // one clip: no key, the file as before
  y << "views: [";
  for (int v = 0; v < cs.num_views(); ++v) y << (v ? ", " : "") << cs.views[v];
  y << "]\n"
    << "image_width: " << cs.cameras[0][0].width << "\n"
    << "image_height: " << cs.cameras[0][0].height << "\n"
    << "camera_per_frame: " << (cfg.cameras.kind == CameraRigKind::wild ? "true" : "false") << "\n"
    << "character: character/character.yaml\n"
    << "dt_scale: " << cfg.render.dt_scale << "\n"
    << "splits:\n"
    << "  train: " << yaml_int_list(summary.train) << "\n"
    << "  val: " << yaml_int_list(summary.val) << "\n"
    << "  test: " << yaml_int_list(summary.test) << "\n"
    << "failed_frames: " << yaml_int_list(failed) << "\n"
    << simulation_config_yaml(cfg.simulation);
  write_text_atomically((out / "dataset.yaml").string(), y.str());
}

// timing.json: the wall times of the stages.
void write_timing_json(const SynthSummary& summary, const fs::path& out) {
  nlohmann::json t = {{"seconds_character", summary.seconds_character},
                      {"seconds_motion", summary.seconds_motion},
                      {"seconds_simulation", summary.seconds_simulation},
                      {"seconds_rendering", summary.seconds_rendering},
                      {"seconds_writing", summary.seconds_writing},
                      {"seconds_total", summary.seconds_total},
                      {"views_per_second", summary.views_per_second()}};
  write_text_atomically((out / "timing.json").string(), t.dump(2) + "\n");
}
}  // namespace

void parse_keypoint_noise(const StrictYaml& y, const YAML::Node& n, KeypointNoiseConfig& k, const std::string& key) {
  const std::string dot = key + ".";
  // The model first: it sets the other keys' defaults and which keys apply.
  if (n.IsMap() && n["model"]) {
    const std::string m = y.get<std::string>(n["model"], dot + "model", "gaussian or openpose");
    if (m == "openpose") k = KeypointNoiseConfig::openpose();
    else if (m == "gaussian") k = KeypointNoiseConfig();
    else y.fail_at(n["model"], dot + "model", "expected gaussian or openpose, found '" + m + "'");
  }
  y.numbers(n, dot,
                    {{"noise_px", &k.noise_px, 0, 1000},
                     {"dropout", &k.dropout, 0, 1},
                     {"occluded_dropout", &k.occluded_dropout, 0, 1},
                     {"visible_confidence", &k.visible_confidence, 0, 1},
                     {"occluded_confidence", &k.occluded_confidence, 0, 1},
                     {"confidence_jitter", &k.confidence_jitter, 0, 1},
                     {"depth_tolerance_m", &k.depth_tolerance_m, 0, 10},
                     {"scale_error_multiple", &k.scale_error_multiple, 0, 100},
                     {"swap_probability", &k.swap_probability, 0, 1},
                     {"swap_probability_side", &k.swap_probability_side, 0, 1},
                     {"swap_confidence_scale", &k.swap_confidence_scale, 0, 1},
                     {"confidence_falloff", &k.confidence_falloff, 1e-3, 1000}},
                    {}, {"model"});
  // A key of the other model would be silently ignored: say so instead.
  const bool openpose = k.model == KeypointErrorModel::openpose;
  for (const char* name : {"scale_error_multiple", "swap_probability", "swap_probability_side", "swap_confidence_scale",
                          "confidence_falloff"})
    if (!openpose && n[name])
      y.fail_at(n[name], dot + name, "applies to model: openpose only (the default model is gaussian)");
  if (openpose && n["noise_px"])
    y.fail_at(n["noise_px"], dot + "noise_px",
              "applies to model: gaussian only (openpose sizes the error by the person: scale_error_multiple)");
  validate_keypoint_noise(k, y.file + ": " + key);
}

ClipSplit split_clip(int first, int end, double val_fraction, double test_fraction, double place) {
  WEFT_CHECK(first <= end && val_fraction >= 0 && test_fraction >= 0 && val_fraction + test_fraction <= 1 &&
                 place >= 0 && place <= 1,
             "split_clip: bad arguments");
  const int n = end - first;
  const int n_test = static_cast<int>(std::floor(test_fraction * n));
  const int n_val = static_cast<int>(std::floor(val_fraction * n));
  const int held_out = first + static_cast<int>(std::lround(place * (n - n_val - n_test)));
  ClipSplit s;
  for (int f = first; f < end; ++f) {
    if (f >= held_out + n_val && f < held_out + n_val + n_test) s.test.push_back(f);
    else if (f >= held_out && f < held_out + n_val) s.val.push_back(f);
    else s.train.push_back(f);
  }
  return s;
}

int SynthConfig::frames() const {
  int n = 0;
  for (const SynthMotionConfig& m : motions) n += m.frames;
  return n;
}

std::string SynthConfig::motion_key(size_t clip) const {
  return motion_list ? "motions[" + std::to_string(clip) + "]" : "motion";
}

SynthConfig parse_synth_config(const std::string& text, const std::string& name) {
  StrictYaml y;
  y.file = name;
  y.dir = fs::path(name).parent_path();
  const YAML::Node root = y.parse(text);
  if (!root.IsMap()) y.fail_at(root, "(document)", "expected a mapping of config keys");
  y.check_keys(root, "", {"name", "seed", "character", "motion", "motions", "simulation", "cameras", "render",
                          "keypoints", "splits"});
  SynthConfig c;
  c.file = name;
  c.name = root["name"] ? y.get<std::string>(root["name"], "name", "a string") : fs::path(name).stem().string();
  if (root["seed"]) c.seed = y.get<uint64_t>(root["seed"], "seed", "a non-negative integer");
  if (!root["character"]) y.fail_at(root, "character", "missing: a default-character config (configs/characters/*.yaml)");
  c.character = y.path(root["character"], "character");
  parse_motions(y, root, c);
  if (root["simulation"]) parse_simulation_config(y, root["simulation"], c.simulation);
  if (root["cameras"]) parse_camera_setup(y, root["cameras"], c.cameras);
  if (root["render"]) parse_render(y, root["render"], c.render);
  if (root["keypoints"]) parse_keypoint_noise(y, root["keypoints"], c.keypoints);
  if (root["splits"]) parse_splits(y, root["splits"], c);
  return c;
}

SynthConfig load_synth_config(const std::string& path) { return parse_synth_config(read_file_bytes(path), path); }

SynthSummary synthesize_dataset(const SynthConfig& cfg, const std::string& out_dir,
                                const std::function<void(const SynthProgress&)>& progress) {
  const auto t_start = Clock::now();
  SynthSummary summary;
  const fs::path out(out_dir);
  make_dir(out);

  auto t0 = Clock::now();
  const DefaultCharacter dc = make_dataset_character(cfg, out);
  const Character& ch = dc.character;
  const double mpu = ch.metres_per_unit;
  summary.seconds_character = seconds_since(t0);

  t0 = Clock::now();
  const PosedMotion motion = pose_motion(cfg, ch, progress);
  make_dir(out / "gt");
  write_motion((out / "gt" / "pose.motion").string(), motion.gt);
  summary.seconds_motion = seconds_since(t0);

  t0 = Clock::now();
  const ClothTrack cloth = ground_truth_cloth(cfg, ch, motion, progress, summary);
  summary.seconds_simulation = seconds_since(t0);
  for (const auto& r : summary.reports) summary.failed_frames += r.failed;

  const CameraSetup cameras = make_cameras(cfg, mpu, motion, out);
  for (const char* kind : {"images", "masks", "parts", "dt", "keypoints"})
    for (const auto& v : cameras.views) make_dir(out / kind / v);
  render_dataset(cfg, ch, motion, cloth, cameras, out, progress, summary);
  write_png_atomically((out / "preview.png").string(), preview_sheet(out, cameras.views, motion.frames));
  write_ground_truth_meshes(ch, motion, cloth, out);

  std::vector<int> failed;
  for (int f = 0; f < motion.frames; ++f)
    if (summary.reports[f].failed) failed.push_back(f);
  split_frames(cfg, motion, summary);
  write_metrics_json(cfg, ch, motion, cloth, failed, out);

  summary.frames = motion.frames;
  summary.segments = motion.segments;
  summary.views = cameras.num_views();
  summary.images = motion.frames * cameras.num_views();
  summary.cloth_vertices = ch.cloth->mesh.num_vertices();
  summary.body_vertices = ch.body.mesh.num_vertices();
  write_dataset_yaml(cfg, mpu, motion, cameras, summary, failed, out);

  summary.seconds_total = seconds_since(t_start);
  write_timing_json(summary, out);
  return summary;
}

}  // namespace weft::capture
