#pragma once
// A single-camera sequence as `weft infer` and `weft adapt` read it: per frame the image,
// its camera, the person's mask and the OpenPose detections. Each comes from a given
// folder when there is one; else from the model's person detector when it has one
// (capture/detection/person_detection.h: from the pixels alone); else the mask from
// green-screen keying and no detections.
#include <opencv2/core.hpp>

#include <deque>
#include <map>
#include <string>

#include "capture/detection/person_detection.h"
#include "capture/inference/capture_config.h"
#include "capture/inference/frame_source.h"
#include "capture/io/camera.h"
#include "capture/io/openpose.h"

namespace weft::capture {

// The sequence's camera: one for every frame, or one per frame named <name>_<id:04d>.
class CaptureCameras {
 public:
  // wanted "": the file's only camera, or its only family of per-frame cameras. Errors
  // name the file and the cameras it has.
  CaptureCameras(const std::string& file, const std::string& wanted);
  const std::string& name() const { return name_; }
  bool per_frame() const { return per_frame_; }
  const Camera& at(int id) const;  // an error naming the file when it has none for frame `id`

 private:
  std::string listing() const;
  std::string file_, name_;
  bool per_frame_ = false;
  std::map<std::string, Camera> by_name_;
};

struct SequenceInputOptions {
  std::string input;        // a video or an image folder (frame_source.h)
  std::string camera;       // OpenCV FileStorage YAML
  std::string camera_name;  // see CaptureCameras
  std::string masks;        // "" : green-screen keying
  std::string keypoints;    // "" : no detections
  KeyingConfig keying;
  // The model's person detector (null: none): masks and detections where no folder gives them.
  PersonDetector* detector = nullptr;
  // A folder is missing for the masks or the detections: the model's detector would fill it.
  bool wants_detector() const { return masks.empty() || keypoints.empty(); }
};

// Where a frame's mask and detections came from (capture.json's masks_from, keypoints_from).
enum class InputSource { folder, detector, keying, none };
const char* input_source_name(InputSource s);  // "folder", "detector", "keying", "none"

struct SequenceFrame {
  InputFrame frame;
  Camera camera;
  cv::Mat mask;                        // CV_8UC1 0/255, the frame's size
  Body25 detections = Body25::Zero();  // full-image pixels; zeros without a detection
  bool has_detections = false;         // the keypoint folder has a file for this frame
};

class SequenceInput {
 public:
  explicit SequenceInput(SequenceInputOptions options);
  // The next frame; false at the end. Errors name the file: an image of another size than
  // its camera's, a missing mask, an unreadable mask or keypoint file. part_seconds (when
  // given) gains the time spent reading ("read") and segmenting ("segment").
  bool next(SequenceFrame& frame, std::map<std::string, double>* part_seconds = nullptr);
  FrameSource& source() { return source_; }
  const CaptureCameras& cameras() const { return cameras_; }
  std::string describe() const;  // one line for the log
  InputSource masks_from() const;
  InputSource keypoints_from() const;

 private:
  SequenceInputOptions options_;
  CaptureCameras cameras_;
  FrameSource source_;
  // With the detector: frames read ahead and detected in batches of kDetectBatch (one
  // frame at a time costs about four times as much per frame), served in order.
  static constexpr int kDetectBatch = 8;
  std::deque<std::pair<InputFrame, PersonDetection>> ahead_;
  FrameFiles masks_, keypoints_;
};

}  // namespace weft::capture
