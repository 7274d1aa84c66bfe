#pragma once
// `weft detect`: the person's BODY_25 keypoints and mask in every frame of a video or an
// image folder, predicted by the model folder's person detector (capture/detection/
// person_detection.h: a coarse pass on the whole frame, then the crop), written as
// OpenPose would and as mask images, so a user can look at them and hand them to `weft
// infer --keypoints/--masks` or to any other tool:
//   OUT/keypoints/<name>_keypoints.json   OpenPose BODY_25, one person (or none), frame pixels
//   OUT/masks/<name>.png                  8-bit, 255 person
//   OUT/detect.json                       written last: format weft-detect/1, model, weights,
//                                         input, frames, timing
// <name> is the frame's name (capture/inference/frame_source.h): what `weft infer` looks
// for. Every file is written atomically.
#include <opencv2/core.hpp>

#include <functional>
#include <string>

#include "capture/io/openpose.h"

namespace weft::capture {

struct DetectOptions {
  std::string model;    // a model folder whose network has a detector (network.detector)
  std::string weights;  // optional: these weights instead of the folder's
  std::string input;    // a video file or an image folder
  std::string out;
  int max_frames = -1;  // −1: all
  int batch_size = 8;   // frames per pass of the detector
  // Also OUT/overlays/<name>.png: the frame with the detection drawn over it
  // (capture/render/detection_drawing.h).
  bool overlays = false;
};

struct DetectSummary {
  int frames = 0, found = 0;  // frames, and those where the coarse pass saw a person
  double seconds = 0;         // detection alone (reading and writing excluded)
  double total_seconds = 0;
  double fps() const { return seconds > 0 ? frames / seconds : 0; }
};

// Errors name the file or the model: a model without a detector says what to retrain.
DetectSummary detect_sequence(const DetectOptions& options,
                              const std::function<void(int done, int total)>& progress = {});

}  // namespace weft::capture
