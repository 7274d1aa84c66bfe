#pragma once
// `weft infer`: a trained model (capture/model/model_folder.h) captures a single-camera
// sequence, frame by frame, as the paper tests (../shared/DESIGN.md, "Testing"):
//  1. frames from a video or an image folder (frame_source.h);
//  2. the person's mask and detections: given folders (--masks, --keypoints), else the
//     model's person detector when it has one (from the pixels alone:
//     capture/detection/person_detection.h), else green-screen keying (green_screen.h) and
//     no detections; the networks' crop follows the mask as in training;
//  3. PoseNet and PADefNet on each crop (batched), then the temporal Gaussian filter over
//     5 frames on their outputs (temporal_filter.h);
//  4. the global translation: DeepCap's least squares on the keypoint rays when an OpenPose
//     folder gives the frame's detections (two or more mapped keypoints), else from the
//     silhouette: the depth at which the predicted body's projected height matches the
//     mask's, and the position that centres its projection on the mask's box;
//  5. the deformation layer: posed and deformed body and cloth in world coordinates, and
//     with resolve_collisions the cloth pushed out of the body;
//  6. written to OUT (docs/CAPTURE.md): meshes/body_<id>.ply|obj and cloth_<id>.ply|obj
//     (the template's topology, character units), pose.motion (the character's dofs, the
//     root chain solved so the skeleton stands where the capture put it: root_placement.h),
//     pose.bvh, overlays/<id>.png, overlay.mp4, detections/ (what the person detector
//     gave: keypoints/<name>_keypoints.json and masks/<name>.png, as `weft detect` writes
//     them), and capture.json, written last, which lists the frames (id, source, pivot, how
//     the translation was found), the inputs and where each came from, and the time per
//     part. Every file is written atomically.
#include <functional>
#include <map>
#include <string>

#include "capture/model/pose_refinement.h"

namespace weft::capture {

// OUT's folder of the detector's keypoints and masks (capture.json "detections").
inline constexpr const char* kDetectionsFolder = "detections";

struct CaptureOptions {
  std::string model;        // a model folder (the --out of `weft train`)
  std::string weights;      // optional: these weights instead of the folder's (a checkpoint of
                            // it, e.g. RUN/checkpoints/step_0000500.safetensors: a learning curve)
  std::string input;        // a video file or a folder of images
  std::string camera;       // OpenCV FileStorage YAML (capture/io/camera.h)
  std::string camera_name;  // the camera in that file ("" : its only camera, or its only
                            // per-frame family <name>_<frame:04d>)
  std::string masks;        // optional: <name>.png per frame (255 person)
  std::string keypoints;    // optional: OpenPose BODY_25 JSON per frame
  std::string config;       // optional: configs/infer/*.yaml ("" : the defaults)
  std::string out;
  double fps = 0;           // frame rate for pose.bvh and the video (0: the video's, else 30)
  int max_frames = -1;      // stop after this many frames (−1: all)
  // The paper's optional final collision resolution: cloth vertices pushed out of the body
  // (capture/garment/garment_collision_resolution.h) with the garment material of the
  // model folder (model.yaml's simulation section, from its training dataset).
  bool resolve_collisions = false;
};

struct CaptureSummary {
  int frames = 0;
  int translations_from_keypoints = 0, translations_from_silhouette = 0;
  double seconds = 0;
  std::map<std::string, double> part_seconds;  // read, segment, crop, networks, filter, deform, collisions, place, write
  // With resolve_collisions: the deepest cloth vertex inside the body over all frames,
  // before and after the pass (character units).
  double penetration_before = 0, penetration_after = 0;
  double metres_per_unit = 1;  // the character's
  PoseRefinementSummary refinement;  // with refine.iterations > 0
  double fps() const { return seconds > 0 ? frames / seconds : 0; }
};

// progress(done, total) after each frame of each pass ("networks" then "meshes").
CaptureSummary capture_sequence(const CaptureOptions& options,
                                const std::function<void(const std::string& pass, int done, int total)>& progress = {});

}  // namespace weft::capture
