#pragma once
// The synthetic studio's cameras: a calibrated multi-view rig on rings around the subject,
// and single moving "in the wild" cameras with hand-held shake and an exposure schedule
// for lighting changes.
//
// World conventions: Y up, the floor at y = 0 (the default character stands on it around
// x = z = 0, facing +z; ddc faces −z). Azimuth is measured about +y from +z towards +x, so
// azimuth 0 is in front of the default character and 180 in front of ddc.
// Configs are in metres; `metres_per_unit` converts them to the character's units (1 for
// the default character, 0.001 for ddc in millimetres), so cameras come out in the units
// of the meshes they will render.
// Cameras follow OpenCV: x right, y down, z along the optical axis; the principal point
// is the image centre ((width − 1)/2, (height − 1)/2) in the renderer's pixel convention.
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "capture/io/camera.h"

namespace weft::capture {

// A pinhole camera at `centre` looking at `target` with the world's +y up in the image,
// square pixels, a vertical field of view in degrees and radial distortion k1. Units of
// centre and target are the world's. Throws weft::Error when centre = target, the view is
// along ±y (no image "up"), or the sizes or field of view are out of range.
Camera look_at_camera(const std::string& name, const Eigen::Vector3d& centre, const Eigen::Vector3d& target,
                      int width, int height, double vertical_fov_deg, double k1 = 0);

struct StudioRigConfig {
  int views = 8;                 // 1..72 cameras
  int width = 512, height = 512;  // pixels
  double vertical_fov_deg = 50;  // fits a 1.66 m subject at 3 m from 0.9–1.7 m heights
  double radius_m = 3.0;         // horizontal distance of every camera from the target's axis
  double height_m = 1.3;         // camera height above the floor (the middle height with rings)
  Eigen::Vector3d target_m = Eigen::Vector3d(0, 0.9, 0);  // look-at point (metres)
  double first_azimuth_deg = 0;  // azimuth of cam00 (0: in front of the default character)
  // Rings of cameras at different heights; 0 = automatic: one ring per 9 views (1 ring for
  // up to 9 views, 2 rings of 9 for 18). Views are split as evenly as the count allows,
  // ring r at height_m + (r − (rings − 1)/2) · ring_spacing_m, and ring r's azimuths are
  // turned by r/rings of its angular step so the rings interleave (18 views: two rings of
  // 9 at 0.9 m and 1.7 m, every 20° one camera).
  int rings = 0;
  double ring_spacing_m = 0.8;
  double k1 = 0;                 // radial distortion of every camera
  double metres_per_unit = 1.0;  // character units: 1 (metres), 0.001 (millimetres)
};

// Cameras "cam00", "cam01", … ring by ring, evenly spaced in azimuth, each looking at the
// target (which projects to the principal point) and validated. Throws weft::Error naming
// the field for an invalid config.
std::vector<Camera> studio_rig(const StudioRigConfig& config);

// The number of rings studio_rig uses for `config` (resolves rings = 0).
int studio_rig_rings(const StudioRigConfig& config);

// One hand-held camera moving around the subject. Over the sequence the camera orbits
// from start_azimuth_deg by arc_deg and dollies from radius_start_m to radius_end_m,
// eased in and out (smoothstep of the sequence fraction); on top, a low-frequency shake
// of its position and viewing direction, each axis a sum of three sinusoids with seeded
// frequencies in [0.4, 1] · shake_frequency_hz and seeded phases, bounded by the
// amplitudes. Exposure varies smoothly the same way between exposure_min and exposure_max.
// Given the subject's track, the operator follows the subject: the orbit's centre and the
// aim point move with the subject over the ground (x and z; not its height), the track
// smoothed over follow_smoothing_s seconds (smooth_track), relative to frame 0 (so frame 0
// is where the config puts it).
struct WildCameraConfig {
  int width = 512, height = 512;  // pixels
  double vertical_fov_deg = 50;
  double radius_start_m = 3.2, radius_end_m = 2.8;
  double height_m = 1.4;
  Eigen::Vector3d target_m = Eigen::Vector3d(0, 0.9, 0);
  double start_azimuth_deg = -20, arc_deg = 40;
  double shake_position_m = 0.015;   // bound of the positional shake per axis
  double shake_rotation_deg = 0.4;   // bound of the rotational shake per axis (yaw, pitch, roll)
  double shake_frequency_hz = 1.0;   // highest shake frequency
  double k1 = 0;
  double exposure_min = 0.6, exposure_max = 1.3;  // Lighting::exposure range
  double exposure_frequency_hz = 0.2;             // highest frequency of the lighting changes
  bool follow_subject = true;       // use the subject track when one is given
  double follow_smoothing_s = 0.5;  // σ of the track's smoothing, seconds (0: follow exactly)
  double metres_per_unit = 1.0;
};

// `frames` cameras named "wild0000", "wild0001", …, frame i at time i / fps seconds.
// subject_track: empty (the camera aims at target_m throughout) or one position per frame
// in character units, e.g. the root joint's (see follow_subject). Deterministic for a seed
// on every platform (capture/io/portable_random.h). Throws weft::Error naming the field for an
// invalid config, frames < 1, fps ≤ 0 or a track of the wrong length or non-finite.
std::vector<Camera> wild_camera_path(const WildCameraConfig& config, int frames, double fps, uint64_t seed,
                                     const std::vector<Eigen::Vector3d>& subject_track = {});

// The track smoothed over time: at each frame the value of a straight line fitted to the
// frames around it by least squares with Gaussian weights of sigma_frames (the Gaussian
// mean in the interior; a steady motion is reproduced up to the ends, without lag).
// sigma_frames = 0 returns the track.
std::vector<Eigen::Vector3d> smooth_track(const std::vector<Eigen::Vector3d>& track, double sigma_frames);

// Per-frame Lighting::exposure in [exposure_min, exposure_max], smooth in time; the same
// seed gives the same schedule (independent of the camera path's shake).
std::vector<double> wild_exposure(const WildCameraConfig& config, int frames, double fps, uint64_t seed);

}  // namespace weft::capture
