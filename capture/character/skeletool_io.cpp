#include "capture/character/skeletool_io.h"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <unordered_map>

#include "graph/atomic_file.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

// Reads "key: N" (key given without the colon) on the next non-empty line.
long long read_count_line(TextReader& in, std::string_view key, long long max_count) {
  if (!in.next_nonempty_line()) in.fail_eof(std::string(key) + ": <count>");
  const auto& t = in.tokens();
  if (t.size() != 2 || t[0] != std::string(key) + ":")
    in.fail("expected '", key, ": <count>', found '", in.line(), "'");
  const long long n = in.to_int(t[1], std::string(key) + " count");
  if (n < 0 || n > max_count) in.fail(key, " count ", n, " out of range (0..", max_count, ")");
  return n;
}

void expect_header(TextReader& in, std::string_view expected_start, std::string_view what) {
  if (!in.next_nonempty_line()) in.fail_eof(std::string(what) + " header");
  auto lower = [](std::string_view s) {
    std::string out(s);
    for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
  };
  // Case-insensitive: ddc.character starts "skeletool character file v1.0".
  if (lower(in.line()).find(lower(expected_start)) == std::string::npos)
    in.fail("expected a header line starting '", expected_start, "' (", what, "), found '", in.line(), "'");
}

Eigen::Vector3d read_vec3(const TextReader& in, size_t first, std::string_view what) {
  return {in.to_double(in.token(first, what), what), in.to_double(in.token(first + 1, what), what),
          in.to_double(in.token(first + 2, what), what)};
}

}  // namespace

Skeleton parse_skeleton(std::string text, const std::string& name) {
  TextReader in(std::move(text), name);
  expect_header(in, "Skeletool Skeleton", "Skeletool skeleton");
  Skeleton s;
  std::unordered_map<std::string, int> joint_by_name;
  const long long n_joints = read_count_line(in, "joints", 1000000);
  for (long long j = 0; j < n_joints; ++j) {
    if (!in.next_nonempty_line()) in.fail_eof("joint line " + std::to_string(j + 1) + " of " + std::to_string(n_joints));
    in.expect_tokens(10, "name type parent ox oy oz ax ay az scale");
    const auto& t = in.tokens();
    Joint joint;
    joint.name = t[0];
    if (joint_by_name.count(joint.name)) in.fail("duplicate joint name '", joint.name, "'");
    if (t[1] == "revolute") joint.type = JointType::revolute;
    else if (t[1] == "prismatic") joint.type = JointType::prismatic;
    else in.fail("unknown joint type '", t[1], "' (expected revolute or prismatic)");
    if (t[2] == "none") {
      joint.parent = -1;
    } else {
      const auto it = joint_by_name.find(std::string(t[2]));
      if (it == joint_by_name.end())
        in.fail("unknown parent joint '", t[2], "' of joint '", joint.name,
                "' (parents must be defined before their children)");
      joint.parent = it->second;
    }
    joint.offset = read_vec3(in, 3, "joint offset");
    const Eigen::Vector3d axis = read_vec3(in, 6, "joint axis");
    if (!(axis.norm() > 1e-12)) in.fail("joint '", joint.name, "' has a zero axis");
    joint.axis = axis.normalized();
    joint.scale = in.to_double(t[9], "joint scale");
    joint_by_name[joint.name] = static_cast<int>(s.joints.size());
    s.joints.push_back(std::move(joint));
  }
  auto find_joint = [&](std::string_view jname, std::string_view context) {
    const auto it = joint_by_name.find(std::string(jname));
    if (it == joint_by_name.end()) in.fail("unknown joint '", jname, "' in ", context);
    return it->second;
  };

  // markers (optional) then dofs.
  if (!in.next_nonempty_line()) in.fail_eof("'markers: <count>' or 'dofs: <count>'");
  auto section_count = [&](std::string_view key) {
    const auto& t = in.tokens();
    if (t.size() != 2 || t[0] != std::string(key) + ":") return -1LL;
    const long long n = in.to_int(t[1], std::string(key) + " count");
    if (n < 0 || n > 1000000) in.fail(key, " count ", n, " out of range");
    return n;
  };
  long long n_markers = section_count("markers");
  if (n_markers >= 0) {
    for (long long m = 0; m < n_markers; ++m) {
      if (!in.next_nonempty_line()) in.fail_eof("marker line " + std::to_string(m + 1) + " of " + std::to_string(n_markers));
      in.expect_tokens(10, "name joint type ox oy oz size r g b");
      const auto& t = in.tokens();
      Marker marker;
      marker.name = t[0];
      marker.joint = find_joint(t[1], "marker '" + marker.name + "'");
      marker.offset = read_vec3(in, 3, "marker offset");
      marker.size = in.to_double(t[6], "marker size");
      marker.color = read_vec3(in, 7, "marker colour");
      s.markers.push_back(std::move(marker));
    }
    if (!in.next_nonempty_line()) in.fail_eof("'dofs: <count>'");
  }
  // "scaling joints: N": ddc has none; their line format is not documented, so a file
  // with some is refused rather than misread.
  if (in.tokens().size() == 3 && in.tokens()[0] == "scaling" && in.tokens()[1] == "joints:") {
    const long long n = in.to_int(in.tokens()[2], "scaling joint count");
    if (n != 0) in.fail("scaling joints are not supported (found ", n, ", expected 0)");
    if (!in.next_nonempty_line()) in.fail_eof("'dofs: <count>'");
  }
  const long long n_dofs = section_count("dofs");
  if (n_dofs < 0) in.fail("expected 'dofs: <count>', found '", in.line(), "'");
  for (long long d = 0; d < n_dofs; ++d) {
    if (!in.next_nonempty_line()) in.fail_eof("dof block " + std::to_string(d + 1) + " of " + std::to_string(n_dofs));
    in.expect_tokens(2, "dof name and joint count");
    Dof dof;
    dof.name = in.tokens()[0];
    const long long count = in.to_int(in.tokens()[1], "dof joint count");
    if (count < 0 || count > n_joints) in.fail("dof '", dof.name, "' drives ", count, " joints; the skeleton has ", n_joints);
    if (!in.next_nonempty_line()) in.fail_eof("'nolimits' or 'limits lo hi'");
    if (in.tokens()[0] == "nolimits") {
      in.expect_tokens(1, "nolimits");
    } else if (in.tokens()[0] == "limits") {
      in.expect_tokens(3, "limits lo hi");
      dof.limited = true;
      dof.lower = in.to_double(in.tokens()[1], "lower limit");
      dof.upper = in.to_double(in.tokens()[2], "upper limit");
      if (dof.lower > dof.upper) in.fail("dof '", dof.name, "' lower limit exceeds upper limit");
    } else {
      in.fail("expected 'nolimits' or 'limits lo hi' for dof '", dof.name, "', found '", in.line(), "'");
    }
    for (long long k = 0; k < count; ++k) {
      if (!in.next_nonempty_line()) in.fail_eof("joint line of dof '" + dof.name + "'");
      in.expect_tokens(2, "joint weight");
      DofInfluence inf;
      inf.joint = find_joint(in.tokens()[0], "dof '" + dof.name + "'");
      inf.weight = in.to_double(in.tokens()[1], "dof weight");
      dof.joints.push_back(inf);
    }
    s.dofs.push_back(std::move(dof));
  }
  validate_skeleton(s, display_name(name));
  return s;
}

Skeleton read_skeleton(const std::string& path) { return parse_skeleton(read_file_bytes(path), path); }

void write_skeleton(const std::string& path, const Skeleton& s) {
  validate_skeleton(s, path);
  write_file_atomically(path, [&](std::ostream& out) {
    const char* eol = "\r\n";
    out << std::setprecision(17) << "Skeletool Skeleton Definition V1.0" << eol;
    out << "joints: " << s.num_joints() << eol;
    for (const Joint& j : s.joints) {
      out << "  " << j.name << ' ' << (j.type == JointType::revolute ? "revolute" : "prismatic") << ' '
          << (j.parent < 0 ? std::string("none") : s.joints[j.parent].name) << ' ' << j.offset.x() << ' '
          << j.offset.y() << ' ' << j.offset.z() << ' ' << j.axis.x() << ' ' << j.axis.y() << ' '
          << j.axis.z() << ' ' << j.scale << eol;
    }
    out << "markers: " << s.num_markers() << eol;
    for (const Marker& m : s.markers)
      out << "  " << m.name << ' ' << s.joints[m.joint].name << " point " << m.offset.x() << ' '
          << m.offset.y() << ' ' << m.offset.z() << ' ' << m.size << ' ' << m.color.x() << ' '
          << m.color.y() << ' ' << m.color.z() << eol;
    out << "dofs: " << s.num_dofs() << eol;
    for (const Dof& d : s.dofs) {
      out << "  " << d.name << ' ' << d.joints.size() << eol;
      if (d.limited) out << "      limits " << d.lower << ' ' << d.upper << eol;
      else out << "      nolimits" << eol;
      for (const DofInfluence& inf : d.joints)
        out << "      " << s.joints[inf.joint].name << ' ' << inf.weight << eol;
    }
  });
}

// ---------------------------------------------------------------- .skin

int skin_bone_joint(const Skeleton& s, const std::string& bone) {
  int found = -1;
  for (int j = 0; j < s.num_joints(); ++j) {
    const std::string& n = s.joints[j].name;
    const size_t us = n.find('_');
    if (n.compare(0, us == std::string::npos ? n.size() : us, bone) == 0 &&
        (us == std::string::npos ? n.size() : us) == bone.size())
      found = j;
  }
  return found;
}

SkinningWeights parse_skin(std::string text, const std::string& name, const Skeleton& s, int num_vertices) {
  // Without a known vertex count, an index can be at most the number of lines: a corrupt
  // index must not drive a huge allocation.
  const long long line_count = std::count(text.begin(), text.end(), '\n') + 1;
  TextReader in(std::move(text), name);
  expect_header(in, "Skeletool", "Skeletool skinning file");
  if (!in.next_nonempty_line() ) in.fail_eof("'bones:'");
  if (in.tokens().size() != 1 || in.tokens()[0] != "bones:") in.fail("expected 'bones:', found '", in.line(), "'");
  if (!in.next_nonempty_line()) in.fail_eof("the list of bone names");
  std::vector<int> bone_joint;
  for (std::string_view b : in.tokens()) {
    const int j = skin_bone_joint(s, std::string(b));
    if (j < 0) in.fail("bone '", b, "' matches no joint of the skeleton (by the name before its first '_')");
    bone_joint.push_back(j);
  }
  if (!in.next_nonempty_line()) in.fail_eof("'vertex weights:'");
  if (in.line().find("vertex weights:") == std::string_view::npos)
    in.fail("expected 'vertex weights:', found '", in.line(), "'");
  SkinningWeights w;
  w.num_joints = s.num_joints();
  std::vector<int> seen_line;
  while (in.next_nonempty_line()) {
    const auto& t = in.tokens();
    if (t.size() % 2 != 1 || t.size() < 3)
      in.fail("expected 'vertex (bone weight)+', found ", t.size(), " fields");
    const long long v = in.to_int(t[0], "vertex index");
    const long long limit = num_vertices >= 0 ? num_vertices : line_count;
    if (v < 0 || v >= limit) in.fail("vertex index ", v, " out of range (", limit, " vertices)");
    if (v >= static_cast<long long>(w.vertices.size())) {
      w.vertices.resize(v + 1);
      seen_line.resize(v + 1, 0);
    }
    if (seen_line[v]) in.fail("vertex ", v, " already listed on line ", seen_line[v]);
    seen_line[v] = in.line_number();
    auto& infl = w.vertices[v];
    for (size_t k = 1; k < t.size(); k += 2) {
      const long long b = in.to_int(t[k], "bone index");
      if (b < 0 || b >= static_cast<long long>(bone_joint.size()))
        in.fail("bone index ", b, " out of range (", bone_joint.size(), " bones)");
      const double weight = in.to_double(t[k + 1], "bone weight");
      if (weight < 0) in.fail("negative bone weight ", weight);
      if (weight == 0) continue;
      const int joint = bone_joint[b];
      bool merged = false;
      for (auto& existing : infl)
        if (existing.joint == joint) {
          existing.weight += weight;
          merged = true;
        }
      if (!merged) infl.push_back({joint, weight});
    }
    if (infl.empty()) in.fail("vertex ", v, " has no positive weight");
  }
  if (num_vertices >= 0 && static_cast<int>(w.vertices.size()) != num_vertices)
    in.fail("weights for ", w.vertices.size(), " vertices, expected ", num_vertices);
  for (size_t v = 0; v < w.vertices.size(); ++v)
    if (!seen_line[v]) in.fail("vertex ", v, " has no weight line (expected one line per vertex)");
  if (w.vertices.empty()) in.fail("no vertex weight lines");
  normalize_weights(w, display_name(name));
  return w;
}

SkinningWeights read_skin(const std::string& path, const Skeleton& s, int num_vertices) {
  return parse_skin(read_file_bytes(path), path, s, num_vertices);
}

// ---------------------------------------------------------------- .motion

Motion parse_motion(std::string text, const std::string& name, int num_dofs) {
  TextReader in(std::move(text), name);
  expect_header(in, "Skeletool Motion", "Skeletool motion file");
  Motion m;
  std::vector<double> values;
  int dofs = num_dofs;
  while (in.next_nonempty_line()) {
    const auto& t = in.tokens();
    if (dofs < 0) dofs = static_cast<int>(t.size()) - 1;
    if (static_cast<int>(t.size()) != dofs + 1)
      in.fail("expected a frame index and ", dofs, " dof values, found ", t.size(), " fields");
    m.frame_ids.push_back(in.to_int(t[0], "frame index"));
    for (size_t k = 1; k < t.size(); ++k) values.push_back(in.to_double(t[k], "dof value"));
  }
  if (m.frame_ids.empty()) in.fail("no frames in motion file");
  m.dofs = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
      values.data(), m.frame_ids.size(), dofs);
  return m;
}

Motion read_motion(const std::string& path, int num_dofs) {
  return parse_motion(read_file_bytes(path), path, num_dofs);
}

void write_motion(const std::string& path, const Motion& m) {
  if (static_cast<int>(m.frame_ids.size()) != m.num_frames())
    fail(path, ": ", m.frame_ids.size(), " frame ids for ", m.num_frames(), " frames");
  write_file_atomically(path, [&](std::ostream& out) {
    out << "Skeletool Motion File V1.0\r\n" << std::setprecision(17);
    for (int f = 0; f < m.num_frames(); ++f) {
      out << m.frame_ids[f];
      for (Eigen::Index d = 0; d < m.dofs.cols(); ++d) out << ' ' << m.dofs(f, d);
      out << "\r\n";
    }
  });
}

// ---------------------------------------------------------------- .character

SkeletoolCharacterFiles read_skeletool_character(const std::string& path) {
  TextReader in(path);
  expect_header(in, "Skeletool", "Skeletool character file");
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  SkeletoolCharacterFiles files;
  std::string pending;
  while (in.next_nonempty_line()) {
    for (std::string_view tok : in.tokens()) {
      if (pending.empty()) {
        if (tok != "skeleton" && tok != "mesh" && tok != "skin" && tok != "pose")
          in.fail("unknown keyword '", tok, "' (expected skeleton, mesh, skin or pose)");
        pending = tok;
        continue;
      }
      const std::string resolved = (dir / std::string(tok)).lexically_normal().string();
      if (pending == "skeleton") files.skeleton = resolved;
      else if (pending == "mesh") files.mesh = resolved;
      else if (pending == "skin") files.skin = resolved;
      else files.pose = resolved;
      pending.clear();
    }
  }
  if (!pending.empty()) in.fail_eof("a path after '" + pending + "'");
  if (files.skeleton.empty()) in.fail("no 'skeleton' entry");
  if (files.mesh.empty()) in.fail("no 'mesh' entry");
  return files;
}

}  // namespace weft::capture
