#include "capture/dataset/synthetic_dataset.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>
#include <set>

#include <tbb/global_control.h>

#include "capture/io/portable_random.h"
#include "capture/render/renderer.h"
#include "files/strict_yaml.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace fs = std::filesystem;

namespace {

constexpr double kConfidentKeypoint = 0.1;  // keypoints that may place a crop
const double kImageNetMean[3] = {0.485, 0.456, 0.406};  // RGB
const double kImageNetStd[3] = {0.229, 0.224, 0.225};

std::string frame_id(int frame) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04d", frame);
  return buf;
}

std::string join(const std::string& dir, const std::string& a, const std::string& b,
                 const std::string& file) {
  return (fs::path(dir) / a / b / file).string();
}

// ------------------------------------------------------------------------ dataset.yaml

YAML::Node required(const StrictYaml& y, const YAML::Node& root, const char* key) {
  const YAML::Node n = root[key];
  if (!n) weft::fail(y.file, ": missing key '", key, "'");
  return n;
}

int positive_int(const StrictYaml& y, const YAML::Node& node, const std::string& key) {
  const int v = y.get<int>(node, key, "an integer");
  if (v < 1) y.fail_at(node, key, "expected an integer ≥ 1, found " + node.Scalar());
  return v;
}

// A list of frame ids in [0, frames), each once.
std::vector<int> frame_list(const StrictYaml& y, const YAML::Node& node, const std::string& key,
                            int frames) {
  if (!node.IsSequence()) y.fail_at(node, key, "expected a list of frame ids");
  std::vector<int> out;
  std::set<int> seen;
  for (const YAML::Node& item : node) {
    const int f = y.get<int>(item, key, "a frame id (integer)");
    if (f < 0 || f >= frames)
      y.fail_at(item, key,
                "frame " + std::to_string(f) + " out of range (frames: " + std::to_string(frames) +
                    ", ids 0.." + std::to_string(frames - 1) + ")");
    if (!seen.insert(f).second) y.fail_at(item, key, "frame " + std::to_string(f) + " listed twice");
    out.push_back(f);
  }
  return out;
}

// `segments`: the first frame of each clip, 0 first, strictly increasing, below `frames`.
std::vector<int> segment_list(const StrictYaml& y, const YAML::Node& node, int frames) {
  if (!node.IsSequence() || node.size() == 0)
    y.fail_at(node, "segments", "expected a list of the clips' first frames, starting with 0 ([0, 300, 600])");
  std::vector<int> out;
  for (const YAML::Node& item : node) {
    const int f = y.get<int>(item, "segments", "a frame id (integer)");
    if (out.empty() && f != 0)
      y.fail_at(item, "segments", "the first clip starts at frame 0, found " + std::to_string(f));
    if (!out.empty() && f <= out.back())
      y.fail_at(item, "segments",
                "frame " + std::to_string(f) + " after " + std::to_string(out.back()) +
                    ": expected increasing first frames (a clip has at least one frame)");
    if (f >= frames)
      y.fail_at(item, "segments",
                "frame " + std::to_string(f) + " out of range (frames: " + std::to_string(frames) + ")");
    out.push_back(f);
  }
  return out;
}

// ------------------------------------------------------------------------ per-sample files

void require_file(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) fail(path, ": file not found");
}

cv::Mat read_png(const std::string& path, int flags, int type, const char* expected,
                 const DatasetInfo& info) {
  require_file(path);
  cv::Mat m;
  try {
    m = cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    fail(path, ": cannot decode image: ", e.err);
  }
  if (m.empty()) fail(path, ": cannot read image (not a PNG, or unreadable)");
  if (m.type() != type) fail(path, ": expected ", expected, ", found ", cv::typeToString(m.type()));
  if (m.cols != info.image_width || m.rows != info.image_height)
    fail(path, ": image is ", m.cols, "x", m.rows, ", expected ", info.image_width, "x",
         info.image_height, " (dataset.yaml image_width, image_height)");
  return m;
}


// ------------------------------------------------------------------------ cropping

// The side×side square at (left, top) of `src`; zeros where it lies beyond the image.
cv::Mat cut_square(const cv::Mat& src, const CropWindow& crop) {
  cv::Mat out(crop.side, crop.side, src.type(), cv::Scalar::all(0));
  const cv::Rect want(crop.left, crop.top, crop.side, crop.side);
  const cv::Rect inside = want & cv::Rect(0, 0, src.cols, src.rows);
  if (inside.area() > 0)
    src(inside).copyTo(out(cv::Rect(inside.x - crop.left, inside.y - crop.top, inside.width, inside.height)));
  return out;
}

cv::Mat resize_square(const cv::Mat& src, int input_size) {
  cv::Mat out;
  const int interpolation = input_size < src.cols ? cv::INTER_AREA : cv::INTER_LINEAR;
  cv::resize(src, out, cv::Size(input_size, input_size), 0, 0, interpolation);
  return out;
}

// ------------------------------------------------------------------------ shuffling

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Epoch `epoch`'s permutation of 0..n−1: Fisher–Yates on mt19937_64 (fully specified by
// the standard, unlike std::shuffle and the std distributions), seeded by (seed, epoch).
std::vector<int> epoch_order(int n, uint64_t seed, int64_t epoch) {
  std::mt19937_64 engine(splitmix64(seed ^ splitmix64(static_cast<uint64_t>(epoch))));
  std::vector<int> order(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) order[size_t(i)] = i;
  for (int i = n - 1; i > 0; --i) {
    // Unbiased draw in [0, i] by rejection.
    const uint64_t range = uint64_t(i) + 1, limit = UINT64_MAX - UINT64_MAX % range;
    uint64_t r;
    do r = engine();
    while (r >= limit);
    std::swap(order[size_t(i)], order[size_t(r % range)]);
  }
  return order;
}

}  // namespace

Body25 read_dataset_keypoints(const std::string& path) {
  require_file(path);
  OpenPoseFrame frame;
  try {
    frame = read_openpose_json(path);
  } catch (const weft::Error& e) {
    fail(path, ": ", e.what());
  }
  if (frame.people.empty()) return Body25::Zero();  // nobody detected
  if (frame.people.size() > 1)
    fail(path, ": expected one person, found ", frame.people.size());
  return frame.people[0];
}

cv::Mat read_dataset_mask(const DatasetInfo& info, int frame, const std::string& view) {
  return read_png(dataset_mask_path(info, frame, view), cv::IMREAD_UNCHANGED, CV_8UC1,
                  "an 8-bit one-channel mask", info) != 0;  // 0/255
}

// ------------------------------------------------------------------------ DatasetInfo

std::string dataset_image_path(const DatasetInfo& info, int frame, const std::string& view) {
  return join(info.dir, "images", view, frame_id(frame) + ".png");
}
std::string dataset_mask_path(const DatasetInfo& info, int frame, const std::string& view) {
  return join(info.dir, "masks", view, frame_id(frame) + ".png");
}
std::string dataset_keypoints_path(const DatasetInfo& info, int frame, const std::string& view) {
  return join(info.dir, "keypoints", view, frame_id(frame) + "_keypoints.json");
}
std::string dataset_frame_name(int frame) {
  char buf[16];
  std::snprintf(buf, sizeof(buf), "%04d", frame);
  return buf;
}

std::string dataset_camera_name(const DatasetInfo& info, int frame, const std::string& view) {
  return info.camera_per_frame ? view + "_" + frame_id(frame) : view;
}

DatasetInfo read_dataset_info(const std::string& dir) {
  const std::string file = (fs::path(dir) / "dataset.yaml").string();
  const StrictYaml y{file, fs::path(dir)};
  const YAML::Node root = y.parse(read_file_bytes(file));
  // `simulation` (the garment's simulation settings) is read by capture/garment/garment_config.h.
  y.check_keys(root, "", {"format", "name", "seed", "fps", "metres_per_unit", "frames", "views",
                          "image_width", "image_height", "camera_per_frame", "character",
                          "dt_scale", "splits", "failed_frames", "segments", "simulation"});
  DatasetInfo info;
  info.dir = dir;

  info.format = y.get<std::string>(required(y, root, "format"), "format", "a string");
  if (info.format != "weft-synth/1")
    y.fail_at(root["format"], "format", "expected 'weft-synth/1', found '" + info.format + "'");
  info.name = root["name"] ? y.get<std::string>(root["name"], "name", "a string")
                           : fs::path(dir).lexically_normal().filename().string();
  if (root["seed"]) info.seed = y.get<uint64_t>(root["seed"], "seed", "a non-negative integer");
  info.fps = y.positive(required(y, root, "fps"), "fps");
  info.metres_per_unit = y.positive(required(y, root, "metres_per_unit"), "metres_per_unit");
  info.frames = positive_int(y, required(y, root, "frames"), "frames");
  if (root["segments"]) info.segments = segment_list(y, root["segments"], info.frames);

  const YAML::Node views = required(y, root, "views");
  info.views = y.strings(views, "views");
  if (info.views.empty()) y.fail_at(views, "views", "expected at least one view");
  std::set<std::string> seen_views;
  for (const std::string& v : info.views) {
    if (v.empty() || v == "." || v == ".." || v.find_first_of("/\\") != std::string::npos)
      y.fail_at(views, "views", "'" + v + "' is not a folder name");
    if (!seen_views.insert(v).second) y.fail_at(views, "views", "view '" + v + "' listed twice");
  }

  info.image_width = positive_int(y, required(y, root, "image_width"), "image_width");
  info.image_height = positive_int(y, required(y, root, "image_height"), "image_height");
  if (root["camera_per_frame"])
    info.camera_per_frame = y.get<bool>(root["camera_per_frame"], "camera_per_frame", "true or false");
  info.character = y.path(required(y, root, "character"), "character");
  info.dt_scale = y.positive(required(y, root, "dt_scale"), "dt_scale");

  const YAML::Node splits = required(y, root, "splits");
  if (!splits.IsMap() || splits.size() == 0)
    y.fail_at(splits, "splits", "expected a mapping of split names to frame lists (train: [0, 1])");
  std::map<int, std::string> split_of;  // frame → its split
  for (const auto& kv : splits) {
    const std::string name = y.get<std::string>(kv.first, "splits", "a split name");
    const std::string key = "splits." + name;
    std::vector<int> frames = frame_list(y, kv.second, key, info.frames);
    size_t i = 0;
    for (const YAML::Node& item : kv.second) {
      const int f = frames[i++];
      const auto [it, fresh] = split_of.emplace(f, name);
      if (!fresh)
        y.fail_at(item, key,
                  "frame " + std::to_string(f) + " is also in split '" + it->second +
                      "' (a frame belongs to one split)");
    }
    info.splits[name] = std::move(frames);
  }
  if (root["failed_frames"]) {
    const YAML::Node failed = root["failed_frames"];
    info.failed_frames = frame_list(y, failed, "failed_frames", info.frames);
    size_t i = 0;
    for (const YAML::Node& item : failed) {
      const int f = info.failed_frames[i++];
      if (split_of.count(f))
        y.fail_at(item, "failed_frames",
                  "frame " + std::to_string(f) + " failed but is in split '" + split_of[f] +
                      "' (failed frames belong to no split)");
    }
  }
  require_file((fs::path(dir) / "cameras.yaml").string());
  return info;
}

bool same_segment(const DatasetInfo& info, int a, int b) {
  for (const int f : {a, b})
    if (f < 0 || f >= info.frames)
      fail("same_segment: frame ", f, " is not a frame of ", info.dir, " (ids 0..", info.frames - 1, ")");
  // The clip of a frame: how many clips start at or before it.
  auto clip = [&](int f) { return std::upper_bound(info.segments.begin(), info.segments.end(), f); };
  return clip(a) == clip(b);
}

// ------------------------------------------------------------------------ SyntheticDataset

CropWindow choose_crop(const cv::Mat& mask, const Body25& keypoints, int input_size, double margin) {
  const int width = mask.cols, height = mask.rows;
  CropWindow crop;
  int xmin = 0, xmax = width - 1, ymin = 0, ymax = height - 1;  // inclusive pixel indices
  const cv::Rect box = cv::boundingRect(mask);
  if (box.area() > 0) {
    crop.source = CropSource::mask;
    xmin = box.x, xmax = box.x + box.width - 1, ymin = box.y, ymax = box.y + box.height - 1;
  } else {
    // Keypoints inside the image only: a stray detection far outside must not blow the
    // crop up to gigapixels.
    int count = 0, kx0 = width, kx1 = -1, ky0 = height, ky1 = -1;
    for (int j = 0; j < kBody25Count; ++j) {
      if (!(keypoints(j, 2) >= kConfidentKeypoint)) continue;
      const double px = std::floor(keypoints(j, 0) + 0.5), py = std::floor(keypoints(j, 1) + 0.5);
      if (px < 0 || px >= width || py < 0 || py >= height) continue;
      ++count;
      kx0 = std::min(kx0, int(px)), kx1 = std::max(kx1, int(px));
      ky0 = std::min(ky0, int(py)), ky1 = std::max(ky1, int(py));
    }
    if (count >= 2 && (kx1 > kx0 || ky1 > ky0)) {
      crop.source = CropSource::keypoints;
      xmin = kx0, xmax = kx1, ymin = ky0, ymax = ky1;
    } else {
      crop.source = CropSource::whole_image;
      margin = 0;
    }
  }
  const int w = xmax - xmin + 1, h = ymax - ymin + 1;
  // The 1e-9 keeps 100 · 1.3 = 130.00000000000003 from becoming 131.
  crop.side = std::max(1, int(std::ceil(std::max(w, h) * (1 + 2 * margin) - 1e-9)));
  crop.left = xmin - (crop.side - w) / 2;  // side ≥ w, h: the box stays inside
  crop.top = ymin - (crop.side - h) / 2;
  crop.scale = double(input_size) / crop.side;
  crop.x0 = crop.left - 0.5 + 0.5 / crop.scale;
  crop.y0 = crop.top - 0.5 + 0.5 / crop.scale;
  return crop;
}

void move_crop(CropWindow& c, const AugmentationDraw& draw, int input_size) {
  if (draw.shift_x == 0 && draw.shift_y == 0 && draw.scale == 1) return;
  const double cx = c.left + 0.5 * c.side + draw.shift_x * c.side, cy = c.top + 0.5 * c.side + draw.shift_y * c.side;
  c.side = std::max(1, static_cast<int>(std::lround(c.side * draw.scale)));
  c.left = static_cast<int>(std::lround(cx - 0.5 * c.side));
  c.top = static_cast<int>(std::lround(cy - 0.5 * c.side));
  c.scale = double(input_size) / c.side;
  c.x0 = c.left - 0.5 + 0.5 / c.scale;
  c.y0 = c.top - 0.5 + 0.5 / c.scale;
}

Camera crop_camera(const Camera& full, const CropWindow& crop, int input_size) {
  Camera c = full;
  // u' = scale (u − x0): rows 0 and 1 of K shift by x0, y0 times row 2, then scale.
  c.K.row(0) = crop.scale * (full.K.row(0) - crop.x0 * full.K.row(2));
  c.K.row(1) = crop.scale * (full.K.row(1) - crop.y0 * full.K.row(2));
  c.width = c.height = input_size;
  return c;
}

SyntheticDataset::SyntheticDataset(const std::string& dir, DatasetOptions options)
    : info_(read_dataset_info(dir)), options_(std::move(options)) {
  const std::string where = (fs::path(dir) / "dataset.yaml").string();
  if (options_.input_size < 1) fail("SyntheticDataset: input_size must be ≥ 1, got ", options_.input_size);
  if (!(options_.margin >= 0) || !std::isfinite(options_.margin))
    fail("SyntheticDataset: margin must be a finite number ≥ 0, got ", options_.margin);
  const auto split = info_.splits.find(options_.split);
  if (split == info_.splits.end()) {
    std::string names;
    for (const auto& kv : info_.splits) names += (names.empty() ? "" : ", ") + kv.first;
    fail(where, ": no split '", options_.split, "' (splits: ", names, ")");
  }
  frames_ = split->second;
  if (options_.augmentation.background_probability > 0 && !options_.augmentation.backgrounds.empty())
    photos_ = load_background_photos(options_.augmentation.backgrounds, options_.augmentation.background_photos);

  const std::string cameras_path = (fs::path(dir) / "cameras.yaml").string();
  std::vector<Camera> cameras;
  try {
    cameras = read_cameras_yaml(cameras_path);
  } catch (const weft::Error& e) {
    fail(cameras_path, ": ", e.what());
  }
  for (Camera& c : cameras) {
    const std::string name = c.name;
    if (!cameras_.emplace(name, std::move(c)).second)
      fail(cameras_path, ": camera '", name, "' appears twice");
  }
  auto check = [&](const std::string& name) {
    const auto it = cameras_.find(name);
    if (it == cameras_.end()) fail(cameras_path, ": no camera '", name, "'");
    if (it->second.width != info_.image_width || it->second.height != info_.image_height)
      fail(cameras_path, ": camera '", name, "' is ", it->second.width, "x", it->second.height,
           ", dataset.yaml says ", info_.image_width, "x", info_.image_height);
  };
  for (const std::string& view : info_.views) {
    if (!info_.camera_per_frame) check(view);
    else
      for (int f : frames_) check(dataset_camera_name(info_, f, view));
  }
}

const Camera& SyntheticDataset::camera(int frame, const std::string& view) const {
  const auto it = cameras_.find(dataset_camera_name(info_, frame, view));
  if (it == cameras_.end())
    fail(info_.dir, "/cameras.yaml: no camera '", dataset_camera_name(info_, frame, view), "'");
  return it->second;
}

Sample SyntheticDataset::load(int index) const {
  if (index < 0 || index >= size())
    fail("SyntheticDataset::load: index ", index, " out of range (split '", options_.split,
         "' has ", size(), " samples)");
  const int views = static_cast<int>(info_.views.size());
  return load_at(index, frames_[size_t(index / views)], info_.views[size_t(index % views)]);
}

Sample SyntheticDataset::load(int index, uint64_t augmentation_seed) const {
  if (!options_.augmentation.enabled()) return load(index);
  if (index < 0 || index >= size())
    fail("SyntheticDataset::load: index ", index, " out of range (split '", options_.split,
         "' has ", size(), " samples)");
  const int views = static_cast<int>(info_.views.size());
  const AugmentationDraw draw =
      draw_augmentation(options_.augmentation, static_cast<int>(photos_.size()), augmentation_seed);
  return load_at(index, frames_[size_t(index / views)], info_.views[size_t(index % views)], &draw);
}

Sample SyntheticDataset::load(int frame, const std::string& view) const {
  const auto f = std::find(frames_.begin(), frames_.end(), frame);
  if (f == frames_.end())
    fail("SyntheticDataset::load: frame ", frame, " is not in split '", options_.split, "' of ",
         info_.dir);
  const auto v = std::find(info_.views.begin(), info_.views.end(), view);
  if (v == info_.views.end())
    fail("SyntheticDataset::load: no view '", view, "' in ", info_.dir);
  const int index = int(f - frames_.begin()) * int(info_.views.size()) + int(v - info_.views.begin());
  return load_at(index, frame, view);
}

Sample SyntheticDataset::load_at(int index, int frame, const std::string& view, const AugmentationDraw* draw) const {
  const cv::Mat bgr = read_png(dataset_image_path(info_, frame, view), cv::IMREAD_COLOR, CV_8UC3,
                               "an 8-bit BGR image", info_);
  const cv::Mat mask = read_dataset_mask(info_, frame, view);
  const Body25 keypoints = read_dataset_keypoints(dataset_keypoints_path(info_, frame, view));
  const cv::Mat* photo = draw && draw->background >= 0 ? &photos_[size_t(draw->background)] : nullptr;
  Sample s = prepare_sample(bgr, mask, keypoints, camera(frame, view), options_, draw, photo);
  s.index = index;
  s.frame = frame;
  s.view = view;
  return s;
}

Sample prepare_sample(const cv::Mat& bgr_in, const cv::Mat& mask, const Body25& keypoints, const Camera& camera,
                      const DatasetOptions& options, const AugmentationDraw* draw, const cv::Mat* photo) {
  const cv::Mat bgr = photo && draw ? replace_background(bgr_in, mask, *photo, *draw) : bgr_in;
  WEFT_CHECK(bgr.type() == CV_8UC3 && mask.type() == CV_8UC1 && bgr.size() == mask.size(),
             "prepare_sample: expected an 8-bit BGR image and an 8-bit mask of one size");
  WEFT_CHECK(bgr.cols == camera.width && bgr.rows == camera.height, "prepare_sample: a ", bgr.cols, "x", bgr.rows,
             " image for camera '", camera.name, "' of ", camera.width, "x", camera.height);
  const int S = options.input_size;
  Sample s;
  s.camera = camera;
  s.crop = choose_crop(mask, keypoints, S, options.margin);
  if (draw) move_crop(s.crop, *draw, S);  // the camera follows below
  s.crop_camera = crop_camera(s.camera, s.crop, S);

  // Image: to float before resizing, so only one rounding happens (the PNG's).
  cv::Mat image;
  cut_square(bgr, s.crop).convertTo(image, CV_32FC3, 1.0 / 255.0);
  image = resize_square(image, S);
  cv::cvtColor(image, image, cv::COLOR_BGR2RGB);
  if (draw) jitter_colours(image, *draw);
  if (options.normalize) {
    for (int y = 0; y < S; ++y) {
      float* p = image.ptr<float>(y);
      for (int x = 0; x < S; ++x)
        for (int c = 0; c < 3; ++c, ++p) *p = float((*p - kImageNetMean[c]) / kImageNetStd[c]);
    }
  }
  s.image = image;

  const cv::Mat square_mask = cut_square(mask, s.crop);
  cv::threshold(resize_square(square_mask, S), s.mask, 127, 1, cv::THRESH_BINARY);
  s.dt = resize_square(distance_transform(square_mask), S) * s.crop.scale;

  for (int j = 0; j < kBody25Count; ++j) {
    if (!(keypoints(j, 2) > 0)) continue;  // undetected: stays 0, 0, 0
    const Eigen::Vector2d p = s.crop.to_crop(keypoints.row(j).head<2>().transpose());
    s.keypoints.row(j) << p.x(), p.y(), keypoints(j, 2);
  }
  return s;
}

// ------------------------------------------------------------------------ batches

Batch make_batch(const std::vector<Sample>& samples) {
  if (samples.empty()) fail("make_batch: no samples");
  const int S = samples[0].image.rows;
  const int64_t B = static_cast<int64_t>(samples.size()), plane = int64_t(S) * S;
  Batch batch;
  batch.images = Tensor::empty({B, 3, S, S});
  batch.keypoints = Tensor::empty({B, kBody25Count, 3});
  batch.masks = Tensor::empty({B, 1, S, S});
  batch.dt = Tensor::empty({B, 1, S, S});
  float* images = batch.images.data<float>();
  float* keypoints = batch.keypoints.data<float>();
  float* masks = batch.masks.data<float>();
  float* dt = batch.dt.data<float>();
  for (int64_t b = 0; b < B; ++b) {
    const Sample& s = samples[size_t(b)];
    const cv::Size size(S, S);
    if (s.image.size() != size || s.image.type() != CV_32FC3 || s.mask.size() != size ||
        s.mask.type() != CV_8UC1 || s.dt.size() != size || s.dt.type() != CV_32FC1)
      fail("make_batch: sample ", b, " (frame ", s.frame, ", view ", s.view,
           ") does not match the first sample's ", S, "x", S, " image, mask and dt");
    for (int y = 0; y < S; ++y) {
      const float* rgb = s.image.ptr<float>(y);
      const uint8_t* m = s.mask.ptr<uint8_t>(y);
      const float* d = s.dt.ptr<float>(y);
      for (int x = 0; x < S; ++x) {
        const int64_t at = int64_t(y) * S + x;
        for (int c = 0; c < 3; ++c) images[(b * 3 + c) * plane + at] = rgb[3 * x + c];
        masks[b * plane + at] = m[x];
        dt[b * plane + at] = d[x];
      }
    }
    for (int j = 0; j < kBody25Count; ++j)
      for (int k = 0; k < 3; ++k) keypoints[(b * kBody25Count + j) * 3 + k] = float(s.keypoints(j, k));
    batch.indices.push_back(s.index);
    batch.frames.push_back(s.frame);
    batch.views.push_back(s.view);
    batch.cameras.push_back(s.crop_camera);
  }
  batch.whole_size = int(B);
  return batch;
}

Batch batch_rows(const Batch& batch, int first, int last) {
  if (first < 0 || last > batch.size() || first >= last)
    fail("batch_rows: rows [", first, ", ", last, ") of a batch of ", batch.size());
  Batch out;
  out.epoch = batch.epoch;
  out.whole_size = batch.whole_size;
  out.indices.assign(batch.indices.begin() + first, batch.indices.begin() + last);
  out.frames.assign(batch.frames.begin() + first, batch.frames.begin() + last);
  out.views.assign(batch.views.begin() + first, batch.views.begin() + last);
  out.cameras.assign(batch.cameras.begin() + first, batch.cameras.begin() + last);
  out.images = batch.images.slice_view(0, first, last).clone();
  out.keypoints = batch.keypoints.slice_view(0, first, last).clone();
  out.masks = batch.masks.slice_view(0, first, last).clone();
  out.dt = batch.dt.slice_view(0, first, last).clone();
  return out;
}

// ------------------------------------------------------------------------ DatasetPrefetcher

namespace {
PrefetchOptions checked(const PrefetchOptions& o) {
  if (o.batch_size < 1) fail("DatasetPrefetcher: batch_size must be ≥ 1, got ", o.batch_size);
  if (o.batches_ahead < 1) fail("DatasetPrefetcher: batches_ahead must be ≥ 1, got ", o.batches_ahead);
  if (o.loader_threads < 0) fail("DatasetPrefetcher: loader_threads must be ≥ 0, got ", o.loader_threads);
  if (o.first_batch < 0) fail("DatasetPrefetcher: first_batch must be ≥ 0, got ", o.first_batch);
  if (o.shards < 1 || o.shard < 0 || o.shard >= o.shards)
    fail("DatasetPrefetcher: shard ", o.shard, " of ", o.shards, " does not exist");
  if (o.batch_size < o.shards)
    fail("DatasetPrefetcher: a batch of ", o.batch_size, " cannot be cut into ", o.shards, " non-empty shards");
  return o;
}

// Loader slots plus one for the thread that waits in the destructor, capped by TBB's
// thread limit (cores, or a tbb::global_control): asking for more only earns a warning.
int loader_arena_size(int loader_threads) {
  const int limit = int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
  return std::max(1, std::min(loader_threads + 1, limit));
}
}  // namespace

DatasetPrefetcher::DatasetPrefetcher(const SyntheticDataset& dataset, PrefetchOptions options)
    : dataset_(dataset),
      options_(checked(options)),
      arena_(loader_arena_size(options_.loader_threads), 1) {
  const int64_t n = dataset_.size(), bs = options_.batch_size;
  if (n == 0) fail("DatasetPrefetcher: split '", dataset_.options().split, "' of ", dataset_.info().dir, " is empty");
  batches_per_epoch_ = options_.drop_last ? n / bs : (n + bs - 1) / bs;
  if (batches_per_epoch_ == 0)
    fail("DatasetPrefetcher: batch_size ", bs, " with drop_last exceeds the split's ", n, " samples");
  loaders_ = loader_arena_size(options_.loader_threads) - 1;
  next_batch_ = scheduled_ = options_.first_batch;
  while (scheduled_ < options_.first_batch + options_.batches_ahead) schedule(scheduled_);
}

DatasetPrefetcher::~DatasetPrefetcher() {
  stopping_ = true;
  // Runs tasks nobody started (they return at once) and waits for loads in progress.
  arena_.execute([this] { group_.wait(); });
}

void DatasetPrefetcher::schedule(int64_t batch) {
  const int64_t epoch = batch / batches_per_epoch_, first = (batch % batches_per_epoch_) * options_.batch_size;
  if (epoch != order_epoch_) {
    order_ = epoch_order(dataset_.size(), options_.seed, epoch);
    order_epoch_ = epoch;
  }
  const int64_t last = std::min<int64_t>(first + options_.batch_size, int64_t(order_.size()));
  const int64_t n = last - first;
  if (n < options_.shards)
    fail("DatasetPrefetcher: batch ", batch, " of ", n, " samples cannot be cut into ", options_.shards,
         " non-empty shards");
  const int64_t shard_first = first + n * options_.shard / options_.shards,
                shard_last = first + n * (options_.shard + 1) / options_.shards;
  Slot slot;
  slot.epoch = epoch;
  slot.whole_size = int(n);
  slot.indices.assign(order_.begin() + shard_first, order_.begin() + shard_last);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    slots_.emplace(batch, std::move(slot));
  }
  scheduled_ = batch + 1;
  if (loaders_ > 0) arena_.enqueue(group_.defer([this] { load_first_pending(); }));
}

void DatasetPrefetcher::load_first_pending() {
  int64_t batch = -1, epoch = 0;
  std::vector<int> indices;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_) return;
    for (auto& [k, slot] : slots_)
      if (slot.state == Slot::State::pending) {
        slot.state = Slot::State::loading;
        batch = k, epoch = slot.epoch, indices = slot.indices;
        break;
      }
  }
  if (batch >= 0) load_slot(batch, indices, epoch);
}

void DatasetPrefetcher::load_slot(int64_t batch, const std::vector<int>& indices, int64_t epoch) {
  Batch loaded;
  std::exception_ptr error;
  try {
    std::vector<Sample> samples;
    samples.reserve(indices.size());
    for (int i : indices) {
      if (stopping_) break;
      // Each sample of each epoch its own augmentation draws (a function of the stream's
      // seed, the epoch and the sample: resume-exact).
      samples.push_back(dataset_.options().augmentation.enabled()
                            ? dataset_.load(i, mix_seed(options_.seed ^ 0x4155474du, static_cast<uint64_t>(epoch),
                                                        static_cast<uint64_t>(i)))
                            : dataset_.load(i));
    }
    if (!stopping_) {
      loaded = make_batch(samples);
      loaded.epoch = epoch;
    }
  } catch (...) {
    error = std::current_exception();
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    Slot& slot = slots_.at(batch);
    slot.batch = std::move(loaded);
    slot.error = error;
    slot.state = Slot::State::ready;
  }
  ready_.notify_all();
}

Batch DatasetPrefetcher::next() {
  const int64_t k = next_batch_;
  Slot taken;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    Slot& slot = slots_.at(k);
    if (slot.state == Slot::State::pending) {  // no loader has started it: load it here
      slot.state = Slot::State::loading;
      const std::vector<int> indices = slot.indices;
      const int64_t epoch = slot.epoch;
      lock.unlock();
      load_slot(k, indices, epoch);
      lock.lock();
    }
    ready_.wait(lock, [&] { return slot.state == Slot::State::ready; });
    taken = std::move(slot);
    slots_.erase(k);
  }
  ++next_batch_;
  while (scheduled_ < next_batch_ + options_.batches_ahead) schedule(scheduled_);
  if (taken.error) std::rethrow_exception(taken.error);
  taken.batch.whole_size = taken.whole_size;
  return std::move(taken.batch);
}

}  // namespace weft::capture
