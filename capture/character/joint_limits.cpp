#include "capture/character/joint_limits.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "capture/character/body_skeleton_fit.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

constexpr double kRad = std::numbers::pi / 180;

DofLimit limit(const std::string& dof, double lo_deg, double hi_deg) { return {dof, true, lo_deg * kRad, hi_deg * kRad}; }

}  // namespace

// Signs in the bind-pose frame (y up, facing +z, left at +x):
// - legs (pointing −y): +rx swings the leg back (extension), +rz toward +x (abduction
//   of the left leg, adduction of the right), ry twists about the vertical;
// - trunk and neck (pointing +y): +rx bends forward, +rz leans to the right (toward −x),
//   +ry twists to the left;
// - ankles: +rx points the toes down (plantar flexion);
// - clavicles (pointing ±x): +rz raises the left one and lowers the right one.
// Ranges: the normal active ranges of motion of adults (AAOS: hip flexion 120°,
// extension 30°, abduction 45°, adduction 30°, rotation 45° each way; thoracolumbar
// flexion 80°, extension 25°, lateral bend 35°, rotation 45°; cervical flexion and
// extension 45°, lateral bend 45°, rotation 80°; ankle plantar flexion 50°,
// dorsiflexion 20°, inversion 35°, eversion 15°; wrist flexion 80°, extension 70°), a
// little wider, and split between the two joints that share the trunk and the neck:
// retargeting motion capture onto a different skeleton needs some slack (docs/MOTIONS.md),
// and what the limits must rule out is a pelvis turned by 90° or more with the hips and
// spine turned back. The wrists' axes are not the forearm's in the A-pose, so their box
// is loose (±90°): it only rules out hands turned inside out.
const std::vector<DofLimit>& default_body_dof_limits() {
  static const std::vector<DofLimit> limits = [] {
    std::vector<DofLimit> l = {
        limit("spine_rx", -30, 60),  limit("spine_ry", -30, 30), limit("spine_rz", -30, 30),
        limit("chest_rx", -25, 45),  limit("chest_ry", -35, 35), limit("chest_rz", -25, 25),
        limit("neck_rx", -40, 45),   limit("neck_ry", -50, 50),  limit("neck_rz", -35, 35),
        limit("head_rx", -40, 40),   limit("head_ry", -50, 50),  limit("head_rz", -30, 30),
    };
    for (const std::string side : {"l_", "r_"}) {
      const double s = side == "l_" ? 1 : -1;  // mirror the sideways axis (rz) for the right
      auto mirrored = [&](const std::string& dof, double lo, double hi) {
        return s > 0 ? limit(dof, lo, hi) : limit(dof, -hi, -lo);
      };
      l.push_back(limit(side + "hip_rx", -130, 40));
      l.push_back(limit(side + "hip_ry", -50, 50));
      l.push_back(mirrored(side + "hip_rz", -35, 55));
      l.push_back(limit(side + "ankle_rx", -35, 60));
      l.push_back(limit(side + "ankle_ry", -35, 35));
      l.push_back(limit(side + "ankle_rz", -35, 35));
      l.push_back(limit(side + "clavicle_rx", -30, 30));
      l.push_back(limit(side + "clavicle_ry", -30, 30));
      l.push_back(mirrored(side + "clavicle_rz", -15, 45));
      l.push_back(limit(side + "wrist_rx", -90, 90));
      l.push_back(limit(side + "wrist_ry", -90, 90));
      l.push_back(limit(side + "wrist_rz", -90, 90));
    }
    return l;
  }();
  return limits;
}

void apply_dof_limits(Skeleton& s, const std::vector<DofLimit>& limits, const std::string& what) {
  for (const DofLimit& l : limits) {
    const int d = s.dof_index(l.dof);
    if (d < 0) fail(what, ": joint limits for '", l.dof, "', which the skeleton does not have");
    s.dofs[d].limited = l.limited;
    s.dofs[d].lower = l.limited ? l.lower : 0;
    s.dofs[d].upper = l.limited ? l.upper : 0;
  }
}

std::vector<DofLimit> parse_body_joint_limits(const StrictYaml& y, const YAML::Node& section, const std::string& key) {
  const std::vector<std::string> dofs = body_skeleton_dof_names();
  std::vector<const char*> joints;
  for (const std::string& j : kBodyJointNames)
    if (j != kBodyJointNames.front()) joints.push_back(j.c_str());  // the root stays free
  y.check_keys(section, key, joints);
  std::vector<DofLimit> out;
  for (const auto& kv : section) {
    const std::string joint = kv.first.as<std::string>();
    const std::string where = key + "." + joint;
    std::vector<std::string> axes;
    for (const std::string& d : dofs)
      if (d.starts_with(joint + "_") && d.find('_', joint.size() + 1) == std::string::npos)
        axes.push_back(d.substr(joint.size() + 1));
    std::vector<const char*> names;
    for (const std::string& a : axes) names.push_back(a.c_str());
    y.check_keys(kv.second, where, names);
    for (const auto& ax : kv.second) {
      const std::string axis = ax.first.as<std::string>(), k = where + "." + axis;
      const YAML::Node v = ax.second;
      if (v.IsScalar() && v.Scalar() == "free") {
        out.push_back({joint + "_" + axis, false, 0, 0});
        continue;
      }
      if (!v.IsSequence() || v.size() != 2) y.fail_at(v, k, "expected [min, max] in degrees, or free");
      const double lo = y.number(v[0], k + "[0]", -360, 360), hi = y.number(v[1], k + "[1]", -360, 360);
      std::ostringstream range;
      range << "[" << lo << ", " << hi << "]";
      if (lo > hi) y.fail_at(v, k, "min > max in " + range.str());
      if (lo > 0 || hi < 0) y.fail_at(v, k, "the range " + range.str() + " must contain 0 (the bind pose)");
      out.push_back(limit(joint + "_" + axis, lo, hi));
    }
  }
  return out;
}

}  // namespace weft::capture
