#pragma once
// The reader of the datasets `weft synth` writes (docs/DATASET.md): dataset.yaml, the
// cameras, and per frame and view an image, a foreground mask and OpenPose keypoints.
// A SyntheticDataset opens one split and turns (frame, view) into a Sample the networks
// read: a square crop around the person, resized to input_size², with a camera for the
// crop; make_batch stacks samples into tensors and DatasetPrefetcher loads shuffled
// batches ahead of a training loop on TBB threads.
//
// Conventions
// - Pixels are OpenCV's (capture/render/renderer.h): pixel (x, y) has its centre at (u, v) = (x, y).
// - The crop is an integer square of the full image, [left, left + side) × [top, top + side)
//   (it may reach beyond the image: padded with black pixels and background), resized to
//   S = input_size with cv::resize (INTER_AREA when shrinking, INTER_LINEAR when growing).
//   A full-image position (u, v) lands at crop position
//     u' = scale (u − x0),  v' = scale (v − y0),  scale = S / side,
//     x0 = left − ½ + ½ / scale,  y0 = top − ½ + ½ / scale,
//   the geometry of cv::resize (pixel edges map onto pixel edges). The crop camera is the
//   full camera with K replaced by diag(scale, scale, 1) · [1 0 −x0; 0 1 −y0; 0 0 1] · K, so
//   it projects world points straight into the crop (lens distortion unchanged).
// - image: cv::Mat CV_32FC3, HWC, channels in RGB order, values (c/255 − mean) / std with
//   ImageNet's mean (0.485, 0.456, 0.406) and std (0.229, 0.224, 0.225) (torchvision), or
//   c/255 with normalize = false. make_batch transposes to CHW.
// - mask: CV_8UC1, 1 foreground (body and cloth), 0 background: the resized 0/255 mask
//   thresholded at 50 % coverage.
// - dt: CV_32FC1, distance in crop pixels to the nearest foreground pixel, 0 on it:
//   capture::distance_transform of the cropped full-resolution mask (zero padded), resized
//   like the image and multiplied by scale. Recomputed rather than read from dt/*.png,
//   because the stored distances end at the image border while a crop may extend past
//   it; inside the image the two agree up to the PNG's 1/dt_scale quantisation. A sample
//   without foreground gets the crop's diagonal (S·√2) everywhere.
// - keypoints: BODY_25 rows (x, y, confidence) in crop pixels, confidence as read; a
//   keypoint with confidence 0 (undetected) stays (0, 0, 0).
#include <opencv2/core.hpp>

#include <Eigen/Core>
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <exception>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include "capture/dataset/augmentation.h"
#include "capture/io/camera.h"
#include "capture/io/openpose.h"
#include "graph/tensor.h"

namespace weft::capture {

// dataset.yaml. Required keys: format (weft-synth/1), metres_per_unit, fps, frames, views,
// image_width, image_height, character, dt_scale, splits; optional: name (default: the
// folder's name), seed (0), camera_per_frame (false), failed_frames (none), segments (one
// clip).
struct DatasetInfo {
  std::string dir;            // the dataset folder
  std::string format;         // "weft-synth/1"
  std::string name;
  uint64_t seed = 0;          // the seed `weft synth` used
  double fps = 30.0;          // frames per second
  double metres_per_unit = 1.0;  // world / character units in metres (ddc: 0.001)
  int frames = 0;             // frame ids 0 .. frames − 1
  // First frame of each motion clip, ascending from 0 (a dataset made from several clips):
  // clip k is frames [segments[k], segments[k+1]), simulated on its own. Empty: one clip.
  std::vector<int> segments;
  std::vector<std::string> views;
  int image_width = 0, image_height = 0;  // pixels
  bool camera_per_frame = false;  // cameras named <view>_<frame:04d> ("in the wild")
  std::string character;      // path of character.yaml (resolved against dir; exists)
  double dt_scale = 16;       // dt PNG value = min(65535, round(dt_scale · distance px))
  std::map<std::string, std::vector<int>> splits;  // split name → frame ids, in file order
  std::vector<int> failed_frames;  // frames whose simulation failed: in no split
};

// Reads and checks DIR/dataset.yaml: unknown keys, wrong types, missing keys, a missing
// character or cameras.yaml, split frames out of range or repeated, a frame in two splits
// or in a split and failed_frames, segments not starting at 0, not increasing or out of
// range are weft::Errors naming the file, line, key and what was expected.
DatasetInfo read_dataset_info(const std::string& dir);

// True when frames a and b (in [0, info.frames), else a weft::Error) lie in the same clip:
// a simulation window over frames a..b needs it, the garment's motion does not go on
// across a clip boundary.
bool same_segment(const DatasetInfo& info, int a, int b);

// Paths of one frame and view's files (frame ids are written with 4 digits).
std::string dataset_image_path(const DatasetInfo& info, int frame, const std::string& view);
std::string dataset_mask_path(const DatasetInfo& info, int frame, const std::string& view);
std::string dataset_keypoints_path(const DatasetInfo& info, int frame, const std::string& view);
// Name of the camera of a frame and view in cameras.yaml: the view, or <view>_<frame:04d>.
// A frame's name in the layout's file names (docs/DATASET.md): "0007".
std::string dataset_frame_name(int frame);

std::string dataset_camera_name(const DatasetInfo& info, int frame, const std::string& view);
// One view's keypoints (Body25::Zero() when nobody is detected; more than one person is an
// error) and foreground mask (CV_8UC1 0/255 of the dataset's image size); errors name the file.
Body25 read_dataset_keypoints(const std::string& path);
cv::Mat read_dataset_mask(const DatasetInfo& info, int frame, const std::string& view);

struct DatasetOptions {
  std::string split = "train";
  int input_size = 256;   // S: crops are S×S pixels
  double margin = 0.15;   // crop side = max(box w, h) · (1 + 2 margin)
  bool normalize = true;  // ImageNet mean/std on RGB in [0, 1] (torchvision)
  // Applied by load(index, augmentation_seed) only (DatasetPrefetcher passes a seed per
  // sample and epoch when it is enabled); load(index) is never augmented.
  AugmentationOptions augmentation;
};

// Where a crop's square came from.
enum class CropSource {
  mask,         // bounding box of the foreground mask
  keypoints,    // the mask is empty: bounding box of keypoints with confidence ≥ 0.1
  whole_image,  // neither: the square around the whole image
};

// The square cut from the full image and the map into the crop's pixels.
struct CropWindow {
  int left = 0, top = 0;  // first column / row of the square in the full image (may be < 0)
  int side = 0;           // full-image pixels
  double scale = 1;       // crop pixels per full-image pixel: input_size / side
  double x0 = 0, y0 = 0;  // full-image position of the crop's pixel (0, 0) centre
  CropSource source = CropSource::mask;
  Eigen::Vector2d to_crop(const Eigen::Vector2d& uv) const {
    return {scale * (uv.x() - x0), scale * (uv.y() - y0)};
  }
};

// The square SyntheticDataset::load cuts around the person: the bounding box of `mask`
// (CV_8UC1, nonzero = person), or, when it is empty, of the keypoints with confidence ≥ 0.1
// inside the image, or else the whole image; its side max(box w, h) · (1 + 2 margin).
CropWindow choose_crop(const cv::Mat& mask, const Body25& keypoints, int input_size, double margin);
// The crop moved and scaled about its centre by an augmentation draw's shift and scale
// (augmentation.h); a draw without either leaves it as it is.
void move_crop(CropWindow& crop, const AugmentationDraw& draw, int input_size);

// The camera that projects world points into `crop` (same R, t, dist; K changed).
Camera crop_camera(const Camera& full, const CropWindow& crop, int input_size);

struct Sample {
  int index = 0;           // position in the dataset (frame-major: i_frame · views + i_view)
  int frame = 0;
  std::string view;
  Camera camera;           // the full image's camera
  CropWindow crop;
  Camera crop_camera;      // projects into the input_size² crop
  cv::Mat image;           // CV_32FC3 RGB, normalised (see the conventions above)
  cv::Mat mask;            // CV_8UC1, 0/1
  cv::Mat dt;              // CV_32FC1, crop pixels
  Body25 keypoints = Body25::Zero();  // crop pixels, confidence unchanged
};

// A sample from one full image (CV_8UC3 BGR of the camera's size), its foreground mask
// (CV_8UC1 0/255, same size) and its detections (full-image px; zeros when there are
// none), cut and resized exactly as SyntheticDataset::load does: what `weft infer` feeds
// the networks from a video frame. index, frame and view are left for the caller.
// With `draw` (augmentation.h) the crop is moved and scaled, the colours jittered and, with
// `photo`, the background replaced before cutting (options.augmentation is not read here).
Sample prepare_sample(const cv::Mat& bgr, const cv::Mat& mask, const Body25& keypoints, const Camera& camera,
                      const DatasetOptions& options, const AugmentationDraw* draw = nullptr,
                      const cv::Mat* photo = nullptr);

class SyntheticDataset {
 public:
  // Reads dataset.yaml and cameras.yaml and checks that every frame and view of the split
  // has a camera of the dataset's image size. Errors name the file and what is missing.
  explicit SyntheticDataset(const std::string& dir, DatasetOptions options = {});

  const DatasetInfo& info() const { return info_; }
  const DatasetOptions& options() const { return options_; }
  const std::vector<int>& frames() const { return frames_; }  // the split's frames
  int size() const { return static_cast<int>(frames_.size() * info_.views.size()); }

  // The sample at `index` in [0, size()): frame frames()[index / views], view index % views.
  // Thread-safe. A missing or unreadable image, mask or keypoint file, or one of the wrong
  // size or type, is a weft::Error naming its path.
  Sample load(int index) const;
  // The same augmented by options().augmentation with draws from `augmentation_seed`
  // (the sample as load(index) gives it when augmentation is off).
  Sample load(int index, uint64_t augmentation_seed) const;
  // A frame of the split and one of the views (anything else is an error).
  Sample load(int frame, const std::string& view) const;

  const Camera& camera(int frame, const std::string& view) const;

 private:
  Sample load_at(int index, int frame, const std::string& view, const AugmentationDraw* draw = nullptr) const;

  DatasetInfo info_;
  DatasetOptions options_;
  std::vector<cv::Mat> photos_;  // options_.augmentation.backgrounds, loaded once
  std::vector<int> frames_;
  std::map<std::string, Camera> cameras_;
};

// Samples stacked as float32 tensors, S = input_size:
//   images [B, 3, S, S] (RGB planes), keypoints [B, 25, 3] (crop pixels, confidence),
//   masks [B, 1, S, S] (0/1), dt [B, 1, S, S] (crop pixels).
struct Batch {
  int64_t epoch = 0;            // set by DatasetPrefetcher
  std::vector<int> indices;     // dataset indices of the samples
  std::vector<int> frames;
  std::vector<std::string> views;
  std::vector<Camera> cameras;  // crop cameras
  Tensor images, keypoints, masks, dt;
  int whole_size = 0;           // samples of the whole batch when this is one shard of it (DatasetPrefetcher)
  int size() const { return static_cast<int>(indices.size()); }
};

// Throws weft::Error for an empty list or samples of different sizes.
Batch make_batch(const std::vector<Sample>& samples);
// Samples [first, last) of a batch (copies; whole_size is kept).
Batch batch_rows(const Batch& batch, int first, int last);

struct PrefetchOptions {
  int batch_size = 8;
  uint64_t seed = 0;       // the shuffle: epoch e's order is a function of (seed, e) only
  int batches_ahead = 2;   // batches loaded or loading ahead of the one next() returns (≥ 1)
  int loader_threads = 1;  // TBB threads loading in the background (0: next() loads; capped by
                           // TBB's thread limit, e.g. a tbb::global_control, minus the caller)
  bool drop_last = false;  // drop an epoch's last, smaller batch
  int64_t first_batch = 0; // the stream's batch the first next() returns (a resumed run)
  // Data parallelism (nn/data_parallel.h): load only shard `shard` of `shards` of every
  // batch, samples [⌊shard·n/shards⌋, ⌊(shard+1)·n/shards⌋) of its n; the batches and
  // their order are those of the unsharded stream.
  int shard = 0, shards = 1;
};

// Shuffled batches of a dataset, loaded ahead on TBB threads. Batch k of the stream is
// decided by (seed, k) alone: epoch e = k / batches_per_epoch() visits every sample once
// in a permutation of its own, and batch k holds its consecutive slice of it; so the
// sequence does not depend on thread count or timing. At most batches_ahead batches are
// in flight; next() waits only when the batch it needs is still loading, and loads it on
// the calling thread when no TBB thread has started it (so one thread in total works too).
// An error loading a sample (e.g. a missing image, named by path) is rethrown by the
// next() that would have returned its batch; the following call continues with the next
// batch. The destructor stops loading and waits for the running loads to finish.
class DatasetPrefetcher {
 public:
  DatasetPrefetcher(const SyntheticDataset& dataset, PrefetchOptions options = {});
  ~DatasetPrefetcher();
  DatasetPrefetcher(const DatasetPrefetcher&) = delete;
  DatasetPrefetcher& operator=(const DatasetPrefetcher&) = delete;

  Batch next();
  int batches_per_epoch() const { return static_cast<int>(batches_per_epoch_); }
  int64_t batches_returned() const { return next_batch_; }

 private:
  struct Slot {
    enum class State { pending, loading, ready } state = State::pending;
    int64_t epoch = 0;
    int whole_size = 0;  // the whole batch's samples (indices: this process's shard of them)
    std::vector<int> indices;
    Batch batch;
    std::exception_ptr error;
  };
  void schedule(int64_t batch);          // creates the slot (caller holds no lock)
  void load_first_pending();             // a TBB task: claims and loads one pending batch
  void load_slot(int64_t batch, const std::vector<int>& indices, int64_t epoch);

  const SyntheticDataset& dataset_;
  PrefetchOptions options_;
  int loaders_ = 0;  // background loaders: loader_threads capped by TBB's thread limit
  int64_t batches_per_epoch_ = 0;
  int64_t next_batch_ = 0;  // the batch the next call of next() returns
  int64_t scheduled_ = 0;   // batches [0, scheduled_) have had slots
  int64_t order_epoch_ = -1;
  std::vector<int> order_;  // the permutation of epoch order_epoch_

  std::mutex mutex_;
  std::condition_variable ready_;
  std::map<int64_t, Slot> slots_;
  std::atomic<bool> stopping_{false};
  tbb::task_arena arena_;
  tbb::task_group group_;
};

}  // namespace weft::capture
