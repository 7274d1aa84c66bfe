#pragma once
// The settings of `weft infer` (configs/infer/default.yaml; docs/CAPTURE.md). Every key is
// optional; an unknown key or a value out of range is a weft::Error naming the file,
// line and key.
#include <string>
#include <vector>

#include "capture/model/pose_refinement.h"

namespace weft::capture {

// Green-screen keying (OpenCV's HSV: hue 0..180, saturation and value 0..255): a pixel is
// background when its hue lies in [hue_min, hue_max] with at least min_saturation and
// min_value; the person is the rest, cleaned by an opening and a closing.
struct KeyingConfig {
  double hue_min = 35, hue_max = 85;
  double min_saturation = 80, min_value = 40;
  int open_px = 1, close_px = 3;  // radii of the elliptic structuring elements (0: off)
  bool largest_component = true;  // keep only the largest connected foreground region
};

struct CaptureConfig {
  std::string file;       // where it was read from ("" for the defaults)
  int batch_size = 8;     // frames per network pass
  KeyingConfig keying;
  // The paper's temporal Gaussian filter on the network outputs: a window of
  // 2·radius + 1 frames (5), weights exp(−k²/2σ²) renormalised where the window passes
  // the sequence's ends. sigma_frames = 0 switches it off.
  double filter_sigma_frames = 1.0;
  int filter_radius_frames = 2;
  PoseRefinementConfig refine;  // before the filter
  std::vector<std::string> mesh_formats = {"ply", "obj"};  // per frame, body and cloth
  bool overlays = true;   // overlays/<id>.png: the meshes drawn over the input
  bool video = true;      // overlay.mp4 (or overlay.avi when no MP4 encoder is available)
  double overlay_alpha = 0.6;  // opacity of the drawn meshes
};

CaptureConfig load_capture_config(const std::string& path);
CaptureConfig parse_capture_config(const std::string& yaml_text, const std::string& name);

}  // namespace weft::capture
