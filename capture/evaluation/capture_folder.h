#pragma once
// The capture folder `weft infer` writes (docs/EVALUATION.md), read for evaluation:
//
//   DIR/capture.json   format "weft-capture/1"; model, character (character.yaml), metres_per_unit,
//                      input, camera, view, fps,
//                      collisions_resolved, frames [{id, source, pivot [x,y,z], translation_from}],
//                      optional: masks_from, keypoints_from ("folder", "detector", "keying",
//                      "none") and detections (a folder of the detector's keypoints/ and masks/,
//                      relative to DIR; "" none); timing (not read)
//   DIR/meshes/body_<id:04d>.ply, DIR/meshes/cloth_<id:04d>.ply   world coordinates, character
//                      units, the template's topology (the .obj copies beside them are not read)
//   DIR/pose.motion    Skeletool .motion, one row per entry of frames[] in that order: the
//                      character's full dofs (root chain included), so the posed skeleton
//                      is in world coordinates
//
// frames[i].id is the frame of the sequence (the dataset's frame id) the prediction is of;
// pivot is the predicted world position (character units) of the root chain's last joint
// (capture/model/capture_networks.h, PoseParametrisation::pivot_joint).
// Every reader throws one weft::Error naming the file and what was expected.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "capture/character/character.h"

namespace weft::capture {

struct CapturedFrame {
  int id = 0;                   // the sequence's (dataset's) frame id
  std::string source;           // the input image or video frame it was read from
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  // predicted pivot joint position (character units)
  std::string translation_from; // how the global translation was found (e.g. "keypoints")
};

struct CaptureFolder {
  std::string dir;
  std::string format;           // "weft-capture/1"
  std::string model;            // the model folder
  std::string character;        // character.yaml (resolved against dir when relative)
  double metres_per_unit = 1.0;
  std::string input, camera, view;
  double fps = 30;
  bool collisions_resolved = false;
  std::string masks_from, keypoints_from;  // "" in captures written before they were recorded
  std::string detections;                  // the detector's keypoints/ and masks/ ("" : none)
  std::vector<CapturedFrame> frames;  // in capture order; ids distinct
};

// Reads and checks DIR/capture.json: a missing folder or file, invalid JSON, a wrong
// format string, a missing key or one of the wrong type, repeated or negative frame ids,
// a non-finite pivot.
CaptureFolder read_capture_folder(const std::string& dir);

// One predicted frame's meshes (character units, the template's topology).
struct CapturedMeshes {
  Vertices body, cloth;  // cloth empty when the character has none
};
// Reads DIR/meshes/body_<id>.ply (and cloth_<id>.ply when the character has a garment);
// a missing file or a vertex count other than the template's is an error naming the file.
CapturedMeshes read_captured_meshes(const CaptureFolder& capture, int id, const Character& character);

// DIR/pose.motion: one row of the character's dofs per frames[] entry (an error otherwise).
Eigen::MatrixXd read_captured_dofs(const CaptureFolder& capture, const Character& character);

}  // namespace weft::capture
