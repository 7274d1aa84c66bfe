#pragma once
// Biovision hierarchy (.bvh) motion capture: a reader and writer of our own, and forward
// kinematics of the BVH skeleton (global joint transforms per frame or at any time).
//
// BVH semantics: each joint has an OFFSET from its parent and a list of CHANNELS; its
// local transform is T(offset + position channels) · R_c1 · R_c2 · R_c3, the rotations
// applied in the order the channels are listed (degrees in the file, radians here), and
// the global transform is G_parent · local. "End Site" blocks become joints without
// channels named "<parent>_end", so that bone directions to them can be mapped.
// Units are the file's (CMU: about 0.0564 m per unit); axes are the file's (CMU: y up,
// the subject faces +z, its left is +x).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace weft::capture {

enum class BvhChannel { x_position, y_position, z_position, x_rotation, y_rotation, z_rotation };

struct BvhJoint {
  std::string name;
  int parent = -1;                    // index into BvhMotion::joints, smaller than this one's
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // from the parent (file units)
  std::vector<BvhChannel> channels;   // in file order; empty for end sites
  int first_channel = 0;              // column of channels[0] in BvhMotion::frames
  bool end_site = false;
};

struct BvhMotion {
  std::string source;                 // the file it was read from (for messages)
  std::vector<BvhJoint> joints;       // parents before children, end sites included
  double frame_time_s = 0;            // seconds between frames (> 0)
  Eigen::MatrixXd frames;             // frames × channels, as written (units, degrees)
  int extra_frame_lines = 0;          // lines after the declared frame count (ignored)

  int num_frames() const { return static_cast<int>(frames.rows()); }
  int num_channels() const { return static_cast<int>(frames.cols()); }
  // Joints with channels or not, end sites excluded (CMU: 31).
  int num_joints_without_end_sites() const;
  double duration_s() const { return num_frames() > 0 ? (num_frames() - 1) * frame_time_s : 0; }
  // Index by exact name, or -1.
  int joint_index(const std::string& name) const;
};

// Parses BVH text; errors are weft::Error "file:line: what" (truncated file, a frame line
// with the wrong number of values, unknown keywords or channels, non-finite numbers,
// unbalanced braces). Lines after the declared number of frames are counted, not read.
BvhMotion parse_bvh(std::string text, const std::string& name);
BvhMotion read_bvh(const std::string& path);
// Writes BVH text (tabs, %.10g values) that parse_bvh reads back; end sites as End Site.
// Joints are written depth first, and so are the frame columns: the reader's joint order
// may differ from motion.joints, names and poses are preserved.
std::string format_bvh(const BvhMotion& motion);
void write_bvh(const std::string& path, const BvhMotion& motion);

using BvhTransforms = std::vector<Eigen::Isometry3d>;

// Rotation of a joint's rotation channels (radians from the degrees in `values`, which
// holds the joint's channel values in file order).
Eigen::Matrix3d bvh_rotation(const std::vector<BvhChannel>& channels, const double* values);
// Global transforms of every joint (end sites included) for one frame.
BvhTransforms bvh_global_transforms(const BvhMotion& motion, int frame);
// Global transforms at the zero pose (all channels 0): the skeleton as OFFSETs define it.
BvhTransforms bvh_zero_pose(const BvhMotion& motion);
// Global transforms at time t (seconds from frame 0, clamped to the clip): local
// translations are interpolated linearly and local rotations by slerp between the two
// neighbouring frames, so resampling never goes through Euler-angle wrap-arounds.
BvhTransforms bvh_global_transforms_at(const BvhMotion& motion, double t);

// Output frame times for resampling a clip of `duration_s` to `fps`: 0, 1/fps, ... up to
// the last time not after the end of the clip.
std::vector<double> resample_times(double duration_s, double fps);

const char* bvh_channel_name(BvhChannel channel);

}  // namespace weft::capture
