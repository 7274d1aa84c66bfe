#pragma once
// Posing a character through a motion and writing the results: the library side of
// `weft pose`. Meshes go out as OBJ per frame (body_0000.obj, cloth_0000.obj); with
// cameras, an overlay PNG per frame and camera (overlay_<camera>_0000.png) shows the
// projected mesh over a grey background. All writes are atomic.
#include <functional>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "capture/io/camera.h"
#include "capture/character/character.h"
#include "capture/character/skeletool_io.h"

namespace weft::capture {

struct PoseSequenceOptions {
  std::string out_dir;
  int first_frame = 0;   // motion rows [first_frame, last_frame)
  int last_frame = -1;   // -1: to the end
  std::vector<Camera> cameras;  // empty: no overlays
  SkinningMethod method = SkinningMethod::dual_quaternion;
  // Called after each frame with (frames done, frames total).
  std::function<void(int, int)> progress;
};

struct PoseSequenceSummary {
  int frames = 0;
  int meshes_written = 0;
  int images_written = 0;
  double seconds_posing = 0;   // forward kinematics + skinning
  double seconds_writing = 0;  // OBJ and PNG output (including rendering)
};

PoseSequenceSummary pose_sequence(const Character& character, const Motion& motion,
                                  const PoseSequenceOptions& options);

// Renders the meshes' projections into `camera` (its image size): filled triangles
// (back-to-front by depth, flat-shaded by the angle to the view ray) over grey, with
// triangles behind the camera skipped. `colors` gives one BGR colour per mesh.
cv::Mat render_overlay(const Camera& camera, const std::vector<const TriangleMesh*>& meshes,
                       const std::vector<const Vertices*>& posed, const std::vector<cv::Scalar>& colors);

// Scales a camera's intrinsics to another image size (same field of view).
Camera resize_camera(const Camera& camera, int width, int height);

}  // namespace weft::capture
