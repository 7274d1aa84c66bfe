#include "capture/motion/bvh.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string_view>

#include "graph/atomic_file.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
// Deeper nesting than this is a corrupt file, not a skeleton; it also bounds recursion.
constexpr int kMaxDepth = 256;

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i])))
      return false;
  return true;
}

bool parse_channel(std::string_view token, BvhChannel& c) {
  static const std::pair<const char*, BvhChannel> names[] = {
      {"Xposition", BvhChannel::x_position}, {"Yposition", BvhChannel::y_position},
      {"Zposition", BvhChannel::z_position}, {"Xrotation", BvhChannel::x_rotation},
      {"Yrotation", BvhChannel::y_rotation}, {"Zrotation", BvhChannel::z_rotation}};
  for (const auto& [n, ch] : names)
    if (iequals(token, n)) {
      c = ch;
      return true;
    }
  return false;
}

bool is_rotation(BvhChannel c) {
  return c == BvhChannel::x_rotation || c == BvhChannel::y_rotation || c == BvhChannel::z_rotation;
}

// Tokens across lines, for the free-form HIERARCHY section (braces may share a line
// with a keyword in some exporters' files).
class TokenStream {
 public:
  explicit TokenStream(TextReader& in) : in_(in) {}
  // The next token, or an end-of-file error naming what was expected.
  std::string_view next(std::string_view expected) {
    while (index_ >= in_.tokens().size()) {
      if (!in_.next_line()) in_.fail_eof(expected);
      index_ = 0;
    }
    return in_.tokens()[index_++];
  }
  // True when the current line has no tokens left (frame lines start on a fresh line).
  bool line_done() const { return index_ >= in_.tokens().size(); }
  TextReader& reader() { return in_; }

 private:
  TextReader& in_;
  size_t index_ = 0;
};

class Parser {
 public:
  explicit Parser(TextReader& in) : in_(in), ts_(in) {}

  BvhMotion parse() {
    m_.source = in_.path();
    const std::string_view first = ts_.next("'HIERARCHY'");
    if (first != "HIERARCHY") in_.fail("expected 'HIERARCHY', found '", first, "'");
    for (;;) {
      const std::string_view t = ts_.next("'ROOT' or 'MOTION'");
      if (t == "ROOT") {
        joint(std::string(ts_.next("a root joint name")), -1, 0);
      } else if (t == "MOTION") {
        if (m_.joints.empty()) in_.fail("'MOTION' before any 'ROOT' joint");
        break;
      } else {
        in_.fail("unknown keyword '", t, "' (expected ROOT or MOTION)");
      }
    }
    if (channels_ == 0) in_.fail("the hierarchy has no channels");
    motion();
    return std::move(m_);
  }

 private:
  double number(std::string_view what) { return in_.to_double(ts_.next(what), what); }

  void expect(std::string_view token, std::string_view context) {
    const std::string_view t = ts_.next(std::string("'") + std::string(token) + "'");
    if (t != token) in_.fail("expected '", token, "' ", context, ", found '", t, "'");
  }

  int add_joint(std::string name, int parent) {
    for (const BvhJoint& j : m_.joints)
      if (j.name == name) in_.fail("duplicate joint name '", name, "'");
    BvhJoint j;
    j.name = std::move(name);
    j.parent = parent;
    j.first_channel = channels_;
    m_.joints.push_back(std::move(j));
    return static_cast<int>(m_.joints.size()) - 1;
  }

  // After "ROOT name" / "JOINT name": the block in braces.
  void joint(std::string name, int parent, int depth) {
    if (depth > kMaxDepth) in_.fail("joints nested deeper than ", kMaxDepth, " levels");
    const int self = add_joint(std::move(name), parent);
    expect("{", "after joint '" + m_.joints[self].name + "'");
    bool have_offset = false, have_channels = false;
    for (;;) {
      const std::string_view t = ts_.next("'}' closing joint '" + m_.joints[self].name + "'");
      if (t == "OFFSET") {
        if (have_offset) in_.fail("second OFFSET in joint '", m_.joints[self].name, "'");
        m_.joints[self].offset = offset();
        have_offset = true;
      } else if (t == "CHANNELS") {
        if (have_channels) in_.fail("second CHANNELS in joint '", m_.joints[self].name, "'");
        if (m_.joints.size() != static_cast<size_t>(self) + 1)
          in_.fail("CHANNELS of joint '", m_.joints[self].name, "' after its child joints");
        channels(m_.joints[self]);
        have_channels = true;
      } else if (t == "JOINT") {
        if (!have_offset) in_.fail("joint '", m_.joints[self].name, "' has no OFFSET before its children");
        joint(std::string(ts_.next("a joint name")), self, depth + 1);
      } else if (t == "End") {
        const std::string_view site = ts_.next("'Site'");
        if (site != "Site") in_.fail("expected 'End Site', found 'End ", site, "'");
        end_site(self);
      } else if (t == "}") {
        if (!have_offset) in_.fail("joint '", m_.joints[self].name, "' has no OFFSET");
        return;
      } else {
        in_.fail("unknown keyword '", t, "' in joint '", m_.joints[self].name,
                 "' (expected OFFSET, CHANNELS, JOINT, End Site or '}')");
      }
    }
  }

  void end_site(int parent) {
    const int self = add_joint(m_.joints[parent].name + "_end", parent);
    m_.joints[self].end_site = true;
    expect("{", "after 'End Site'");
    const std::string_view t = ts_.next("'OFFSET'");
    if (t != "OFFSET") in_.fail("expected 'OFFSET' in End Site, found '", t, "'");
    m_.joints[self].offset = offset();
    expect("}", "closing End Site");
  }

  Eigen::Vector3d offset() {
    Eigen::Vector3d o;
    for (int k = 0; k < 3; ++k) o[k] = number("an OFFSET coordinate");
    return o;
  }

  void channels(BvhJoint& j) {
    const long long n = in_.to_int(ts_.next("a channel count"), "the channel count");
    if (n < 0 || n > 6) in_.fail("channel count ", n, " out of range (0..6)");
    for (long long k = 0; k < n; ++k) {
      const std::string_view t = ts_.next("a channel name");
      BvhChannel c;
      if (!parse_channel(t, c))
        in_.fail("unknown channel '", t, "' (expected ", n, " of Xposition Yposition Zposition ",
                 "Xrotation Yrotation Zrotation)");
      if (std::find(j.channels.begin(), j.channels.end(), c) != j.channels.end())
        in_.fail("channel '", t, "' listed twice for joint '", j.name, "'");
      j.channels.push_back(c);
    }
    channels_ += static_cast<int>(n);
  }

  void motion() {
    // "Frames: N" and "Frame Time: t"; tolerate "Frames:N" too.
    std::string_view t = ts_.next("'Frames:'");
    long long frames = 0;
    if (t == "Frames:") frames = in_.to_int(ts_.next("the frame count"), "the frame count");
    else if (t.starts_with("Frames:")) frames = in_.to_int(t.substr(7), "the frame count");
    else in_.fail("expected 'Frames: <count>', found '", t, "'");
    if (frames < 0 || frames > 100000000) in_.fail("frame count ", frames, " out of range");
    t = ts_.next("'Frame Time:'");
    if (t != "Frame") in_.fail("expected 'Frame Time: <seconds>', found '", t, "'");
    t = ts_.next("'Time:'");
    if (t != "Time:") in_.fail("expected 'Frame Time: <seconds>', found 'Frame ", t, "'");
    m_.frame_time_s = number("the frame time");
    if (!(m_.frame_time_s > 0)) in_.fail("frame time must be > 0 s, found ", m_.frame_time_s);
    if (!ts_.line_done()) in_.fail("unexpected text after the frame time");

    // Grown as lines arrive (not sized from the header): a corrupt frame count must not
    // drive a huge allocation.
    std::vector<double> values;
    for (long long f = 0; f < frames; ++f) {
      if (!in_.next_nonempty_line())
        in_.fail_eof("frame " + std::to_string(f + 1) + " of " + std::to_string(frames));
      const auto& tok = in_.tokens();
      if (static_cast<int>(tok.size()) != channels_)
        in_.fail("frame ", f + 1, ": expected ", channels_, " channel values, found ", tok.size());
      for (int c = 0; c < channels_; ++c) values.push_back(in_.to_double(tok[c], "a channel value"));
    }
    m_.frames = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        values.data(), frames, channels_);
    // Lines after the declared frames are ignored, as other readers do: exporters write
    // them (assimp's Boxing_Toes.bvh has one frame line more than its 'Frames: 3069').
    while (in_.next_nonempty_line()) ++m_.extra_frame_lines;
  }

  TextReader& in_;
  TokenStream ts_;
  BvhMotion m_;
  int channels_ = 0;
};

void check_frame(const BvhMotion& m, int frame) {
  if (frame < 0 || frame >= m.num_frames())
    fail(display_name(m.source), ": frame ", frame, " out of range (", m.num_frames(), " frames)");
}

// A joint's channel values of one frame (frames is column-major: copy them out).
void joint_values(const BvhMotion& m, int frame, const BvhJoint& j, double values[6]) {
  if (j.channels.size() > 6 || j.first_channel < 0 ||
      j.first_channel + static_cast<int>(j.channels.size()) > m.num_channels())
    fail(display_name(m.source), ": joint '", j.name, "' has channels outside the frame matrix");
  for (size_t k = 0; k < j.channels.size(); ++k) values[k] = m.frames(frame, j.first_channel + k);
}

// Local translation of a joint: offset plus its position channels.
Eigen::Vector3d local_translation(const BvhJoint& j, const double* values) {
  Eigen::Vector3d t = j.offset;
  for (size_t k = 0; k < j.channels.size(); ++k) {
    switch (j.channels[k]) {
      case BvhChannel::x_position: t.x() += values[k]; break;
      case BvhChannel::y_position: t.y() += values[k]; break;
      case BvhChannel::z_position: t.z() += values[k]; break;
      default: break;
    }
  }
  return t;
}

void write_joint(const BvhMotion& m, const std::vector<std::vector<int>>& children, int j, int depth,
                 std::string& out) {
  const std::string pad(depth, '\t');
  const BvhJoint& joint = m.joints[j];
  char buf[128];
  if (joint.end_site) out += pad + "End Site\n";
  else out += pad + (joint.parent < 0 ? "ROOT " : "JOINT ") + joint.name + "\n";
  out += pad + "{\n";
  std::snprintf(buf, sizeof(buf), "\tOFFSET %.10g %.10g %.10g\n", joint.offset.x(), joint.offset.y(),
                joint.offset.z());
  out += pad + buf;
  if (!joint.end_site) {
    out += pad + "\tCHANNELS " + std::to_string(joint.channels.size());
    for (BvhChannel c : joint.channels) out += std::string(" ") + bvh_channel_name(c);
    out += "\n";
  }
  for (int c : children[j]) write_joint(m, children, c, depth + 1, out);
  out += pad + "}\n";
}

}  // namespace

const char* bvh_channel_name(BvhChannel c) {
  switch (c) {
    case BvhChannel::x_position: return "Xposition";
    case BvhChannel::y_position: return "Yposition";
    case BvhChannel::z_position: return "Zposition";
    case BvhChannel::x_rotation: return "Xrotation";
    case BvhChannel::y_rotation: return "Yrotation";
    case BvhChannel::z_rotation: return "Zrotation";
  }
  return "?";
}

int BvhMotion::num_joints_without_end_sites() const {
  return static_cast<int>(std::count_if(joints.begin(), joints.end(), [](const BvhJoint& j) { return !j.end_site; }));
}

int BvhMotion::joint_index(const std::string& name) const {
  for (size_t j = 0; j < joints.size(); ++j)
    if (joints[j].name == name) return static_cast<int>(j);
  return -1;
}

BvhMotion parse_bvh(std::string text, const std::string& name) {
  TextReader in(std::move(text), name);
  return Parser(in).parse();
}

BvhMotion read_bvh(const std::string& path) { return parse_bvh(read_file_bytes(path), path); }

std::string format_bvh(const BvhMotion& m) {
  std::vector<std::vector<int>> children(m.joints.size());
  for (size_t j = 0; j < m.joints.size(); ++j)
    if (m.joints[j].parent >= 0) children[m.joints[j].parent].push_back(static_cast<int>(j));
  std::string out = "HIERARCHY\n";
  for (size_t j = 0; j < m.joints.size(); ++j)
    if (m.joints[j].parent < 0) write_joint(m, children, static_cast<int>(j), 0, out);
  // A reader assigns channel columns in the order the hierarchy is written (depth first),
  // which need not be the order of m.joints: write each frame's values in that order.
  std::vector<int> columns;
  std::vector<int> stack;
  for (size_t j = m.joints.size(); j-- > 0;)
    if (m.joints[j].parent < 0) stack.push_back(static_cast<int>(j));
  while (!stack.empty()) {
    const int j = stack.back();
    stack.pop_back();
    for (size_t k = 0; k < m.joints[j].channels.size(); ++k) columns.push_back(m.joints[j].first_channel + static_cast<int>(k));
    for (auto c = children[j].rbegin(); c != children[j].rend(); ++c) stack.push_back(*c);
  }
  if (static_cast<int>(columns.size()) != m.num_channels())
    fail(display_name(m.source), ": ", columns.size(), " joint channels for ", m.num_channels(), " frame columns");
  char buf[64];
  out += "MOTION\nFrames: " + std::to_string(m.num_frames()) + "\n";
  std::snprintf(buf, sizeof(buf), "Frame Time: %.10g\n", m.frame_time_s);
  out += buf;
  for (int f = 0; f < m.num_frames(); ++f) {
    for (size_t c = 0; c < columns.size(); ++c) {
      std::snprintf(buf, sizeof(buf), c == 0 ? "%.10g" : " %.10g", m.frames(f, columns[c]));
      out += buf;
    }
    out += "\n";
  }
  return out;
}

void write_bvh(const std::string& path, const BvhMotion& m) {
  const std::string text = format_bvh(m);
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

Eigen::Matrix3d bvh_rotation(const std::vector<BvhChannel>& channels, const double* values) {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  for (size_t k = 0; k < channels.size(); ++k) {
    if (!is_rotation(channels[k])) continue;
    const Eigen::Vector3d axis = channels[k] == BvhChannel::x_rotation   ? Eigen::Vector3d::UnitX()
                                 : channels[k] == BvhChannel::y_rotation ? Eigen::Vector3d::UnitY()
                                                                         : Eigen::Vector3d::UnitZ();
    R = R * Eigen::AngleAxisd(values[k] * kDegToRad, axis).toRotationMatrix();
  }
  return R;
}

BvhTransforms bvh_global_transforms(const BvhMotion& m, int frame) {
  check_frame(m, frame);
  BvhTransforms G(m.joints.size());
  for (size_t j = 0; j < m.joints.size(); ++j) {
    const BvhJoint& joint = m.joints[j];
    double values[6];
    joint_values(m, frame, joint, values);
    Eigen::Isometry3d L = Eigen::Isometry3d::Identity();
    L.translation() = local_translation(joint, values);
    L.linear() = bvh_rotation(joint.channels, values);
    G[j] = joint.parent < 0 ? L : G[joint.parent] * L;
  }
  return G;
}

BvhTransforms bvh_zero_pose(const BvhMotion& m) {
  BvhTransforms G(m.joints.size());
  for (size_t j = 0; j < m.joints.size(); ++j) {
    Eigen::Isometry3d L = Eigen::Isometry3d::Identity();
    L.translation() = m.joints[j].offset;
    G[j] = m.joints[j].parent < 0 ? L : G[m.joints[j].parent] * L;
  }
  return G;
}

BvhTransforms bvh_global_transforms_at(const BvhMotion& m, double t) {
  if (m.num_frames() == 0) fail(display_name(m.source), ": no frames");
  if (!std::isfinite(t)) fail(display_name(m.source), ": non-finite time ", t);
  const double f = std::clamp(t / m.frame_time_s, 0.0, static_cast<double>(m.num_frames() - 1));
  const int i0 = std::min(static_cast<int>(std::floor(f)), m.num_frames() - 1);
  const int i1 = std::min(i0 + 1, m.num_frames() - 1);
  const double a = f - i0;
  BvhTransforms G(m.joints.size());
  for (size_t j = 0; j < m.joints.size(); ++j) {
    const BvhJoint& joint = m.joints[j];
    double v0[6], v1[6];
    joint_values(m, i0, joint, v0);
    joint_values(m, i1, joint, v1);
    const Eigen::Quaterniond q0(bvh_rotation(joint.channels, v0));
    const Eigen::Quaterniond q1(bvh_rotation(joint.channels, v1));
    Eigen::Isometry3d L = Eigen::Isometry3d::Identity();
    L.translation() = (1 - a) * local_translation(joint, v0) + a * local_translation(joint, v1);
    L.linear() = q0.slerp(a, q1).toRotationMatrix();
    G[j] = joint.parent < 0 ? L : G[joint.parent] * L;
  }
  return G;
}

std::vector<double> resample_times(double duration_s, double fps) {
  if (!(fps > 0) || !std::isfinite(fps)) fail("resample: frame rate must be > 0, got ", fps);
  if (!(duration_s >= 0)) fail("resample: negative duration ", duration_s);
  // A small tolerance keeps the last frame when the duration is a whole number of periods
  // up to rounding (2751 × 0.0083333 s).
  const long long n = static_cast<long long>(std::floor(duration_s * fps + 1e-6)) + 1;
  std::vector<double> t(n);
  for (long long k = 0; k < n; ++k) t[k] = static_cast<double>(k) / fps;
  return t;
}

}  // namespace weft::capture
