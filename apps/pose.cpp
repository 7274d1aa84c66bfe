// `weft pose`: poses a character through a Skeletool motion and writes one OBJ per frame
// (body, and cloth when the character has one), plus overlay PNGs with cameras.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "apps/commands.h"
#include "apps/progress_bar.h"
#include "capture/io/camera.h"
#include "capture/character/character.h"
#include "capture/motion/pose_sequence.h"
#include "capture/character/skeletool_io.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::apps {

namespace {

struct PoseArgs {
  std::string character, motion, out, frames, cameras, image_size;
  bool linear_blend = false;
};

// "A:B" (half-open, either side may be empty) → [first, last); last -1 = to the end.
void parse_frames(const std::string& s, int& first, int& last) {
  const size_t colon = s.find(':');
  long long a = 0, b = -1;
  const std::string lhs = s.substr(0, colon), rhs = colon == std::string::npos ? "" : s.substr(colon + 1);
  if (colon == std::string::npos || (!lhs.empty() && !parse_int(lhs, a)) ||
      (!rhs.empty() && !parse_int(rhs, b)) || a < 0 || (!rhs.empty() && b <= a))
    fail("--frames '", s, "': expected A:B with 0 <= A < B (frames A to B-1; A or B may be omitted)");
  first = static_cast<int>(a);
  last = rhs.empty() ? -1 : static_cast<int>(b);
}

void parse_size(const std::string& s, int& w, int& h) {
  const size_t x = s.find('x');
  long long a = 0, b = 0;
  if (x == std::string::npos || !parse_int(s.substr(0, x), a) || !parse_int(s.substr(x + 1), b) ||
      a <= 0 || b <= 0 || a > 16384 || b > 16384)
    fail("--image-size '", s, "': expected WxH in pixels, e.g. 640x480");
  w = static_cast<int>(a);
  h = static_cast<int>(b);
}

void run_pose(const PoseArgs& a) {
  const capture::Character ch = capture::load_character(a.character);
  const capture::Motion motion = capture::read_motion(a.motion, ch.skeleton.num_dofs());
  capture::PoseSequenceOptions o;
  o.out_dir = a.out;
  if (!a.frames.empty()) parse_frames(a.frames, o.first_frame, o.last_frame);
  if (!a.image_size.empty() && a.cameras.empty()) fail("--image-size needs --cameras");
  if (!a.cameras.empty()) {
    const std::string ext = std::filesystem::path(a.cameras).extension().string();
    o.cameras = ext == ".calibration" ? capture::read_skeletool_calibration(a.cameras)
                                      : capture::read_cameras_yaml(a.cameras);
    if (!a.image_size.empty()) {
      int w = 0, h = 0;
      parse_size(a.image_size, w, h);
      for (auto& c : o.cameras) c = capture::resize_camera(c, w, h);
    }
  }
  o.method = a.linear_blend ? capture::SkinningMethod::linear_blend : capture::SkinningMethod::dual_quaternion;
  ProgressBar bar("posing");
  o.progress = [&bar](int done, int total) { bar.update(done, total); };
  spdlog::info("character '{}': {} vertices{}, {} joints, {} dofs; motion {} frames",
               ch.name, ch.body.mesh.num_vertices(), ch.has_cloth() ? " + cloth" : "",
               ch.skeleton.num_joints(), ch.skeleton.num_dofs(), motion.num_frames());
  const capture::PoseSequenceSummary s = capture::pose_sequence(ch, motion, o);
  spdlog::info("{} frames: {} meshes and {} overlay images written to {} (posing {:.1f} ms/frame, writing {:.1f} ms/frame)",
               s.frames, s.meshes_written, s.images_written, a.out, 1e3 * s.seconds_posing / s.frames,
               1e3 * s.seconds_writing / s.frames);
}

}  // namespace

void add_pose_command(CLI::App& app) {
  auto args = std::make_shared<PoseArgs>();
  auto* cmd = app.add_subcommand(
      "pose",
      "Pose a character through a Skeletool motion: one OBJ per frame (body_0000.obj, and\n"
      "cloth_0000.obj when the character has a garment), dual quaternion skinning from the\n"
      "bind pose; with --cameras also overlay_<camera>_0000.png per frame and camera.\n"
      "Coordinates stay in the character's units (ddc: millimetres).");
  cmd->add_option("--character", args->character,
                  "Character file: a character.yaml (docs/CHARACTER.md) or a Skeletool .character")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--motion", args->motion,
                  "Skeletool .motion file: a header, then per frame an index and one value per dof")
      ->required()->check(CLI::ExistingFile);
  cmd->add_option("--out", args->out, "Output folder (created if missing); files are written atomically")
      ->required();
  cmd->add_option("--frames", args->frames,
                  "Frames A:B of the motion (0-based rows, A included, B excluded; '10:' = from 10 to the "
                  "end); default: all");
  cmd->add_option("--cameras", args->cameras,
                  "Cameras for overlay images: OpenCV FileStorage YAML (a 'cameras' list with name, K, dist, "
                  "R, t, image_width, image_height) or a Skeletool .calibration")
      ->check(CLI::ExistingFile);
  cmd->add_option("--image-size", args->image_size,
                  "Overlay image size WxH in pixels (e.g. 640x480); the intrinsics are scaled from each "
                  "camera's calibrated size. Default: the calibrated size");
  cmd->add_flag("--linear-blend", args->linear_blend, "Use linear blend skinning instead of dual quaternions");
  cmd->callback([args] { run_pose(*args); });
}

}  // namespace weft::apps
