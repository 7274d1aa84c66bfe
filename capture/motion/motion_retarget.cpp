#include "capture/motion/motion_retarget.h"


#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "capture/character/character.h"
#include "files/strict_yaml.h"
#include "files/text_reader.h"
#include "graph/error.h"

namespace weft::capture {

namespace {

// '*' matches any run of characters (dof name patterns in fixed_dofs).
bool glob_match(std::string_view pattern, std::string_view name) {
  if (pattern.empty()) return name.empty();
  if (pattern[0] == '*') {
    for (size_t i = 0; i <= name.size(); ++i)
      if (glob_match(pattern.substr(1), name.substr(i))) return true;
    return false;
  }
  return !name.empty() && pattern[0] == name[0] && glob_match(pattern.substr(1), name.substr(1));
}

Eigen::Matrix3d parse_axes(const StrictYaml& y, const YAML::Node& node) {
  const std::vector<std::string> axes = y.strings(node, "source_axes");
  if (axes.size() != 3) y.fail_at(node, "source_axes", "expected 3 entries like [-x, y, -z]");
  Eigen::Matrix3d R = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i) {
    std::string a = axes[i];
    double sign = 1;
    if (!a.empty() && (a[0] == '-' || a[0] == '+')) {
      sign = a[0] == '-' ? -1 : 1;
      a = a.substr(1);
    }
    const int k = a == "x" ? 0 : a == "y" ? 1 : a == "z" ? 2 : -1;
    if (k < 0) y.fail_at(node, "source_axes", "entry '" + axes[i] + "' is not one of x, y, z, -x, -y, -z");
    R(i, k) = sign;
  }
  if (!(R.transpose() * R).isIdentity(1e-12))
    y.fail_at(node, "source_axes", "each source axis must appear exactly once");
  if (R.determinant() < 0)
    y.fail_at(node, "source_axes", "a reflection (determinant -1) would mirror the motion; use a rotation");
  return R;
}

// ----------------------------------------------------------------- the solver

struct Targets {
  std::vector<Eigen::Vector3d> directions;  // per bone, unit, character axes
  Eigen::Vector3d root;                     // character units
  std::vector<Eigen::Matrix3d> rotations;   // per orientation target, the joint's global rotation
};

// A joint whose global rotation is a target (RetargetMapping::orientations).
struct OrientationTarget {
  int source = -1, target = -1;  // BVH joint, character joint
  double weight = 1;
};

Eigen::Vector3d vee_of_skew_part(const Eigen::Matrix3d& M) {
  return 0.5 * Eigen::Vector3d(M(2, 1) - M(1, 2), M(0, 2) - M(2, 0), M(1, 0) - M(0, 1));
}

class Solver {
 public:
  Solver(const Skeleton& s, const std::vector<RetargetBone>& bones, const std::vector<OrientationTarget>& orientations,
         const std::vector<int>& root_joints, double root_weight, double length_scale, const RetargetMapping& m)
      : s_(s), bones_(bones), orientations_(orientations), root_joints_(root_joints), root_weight_(root_weight),
        length_scale_(length_scale), smooth_(m.smoothness), rest_(m.rest_weight), tol_(m.tolerance) {
    const int J = s.num_joints();
    ancestor_.assign(static_cast<size_t>(J) * J, 0);
    for (int k = 0; k < J; ++k)
      for (int j = k; j >= 0; j = s.joints[j].parent) ancestor_[static_cast<size_t>(j) * J + k] = 1;
  }

  bool is_ancestor(int j, int k) const { return ancestor_[static_cast<size_t>(j) * s_.num_joints() + k]; }

  // Dofs the residuals can see: those driving a revolute joint that is a strict ancestor
  // of a residual joint, and root translations (dofs driving only prismatic joints with
  // no revolute joint above them). Scale-like prismatic dofs further down stay fixed.
  std::vector<int> observable_dofs(const std::vector<std::string>& fixed_patterns) const {
    std::vector<int> endpoints;
    for (const RetargetBone& b : bones_) endpoints.insert(endpoints.end(), {b.target_from, b.target_to});
    endpoints.insert(endpoints.end(), root_joints_.begin(), root_joints_.end());
    std::vector<int> out;
    for (int d = 0; d < s_.num_dofs(); ++d) {
      const Dof& dof = s_.dofs[d];
      if (std::any_of(fixed_patterns.begin(), fixed_patterns.end(),
                      [&](const std::string& p) { return glob_match(p, dof.name); }))
        continue;
      bool use = false;
      for (const DofInfluence& inf : dof.joints) {
        if (inf.weight == 0) continue;
        const Joint& j = s_.joints[inf.joint];
        if (j.type == JointType::revolute) {
          for (int e : endpoints) use = use || (e != inf.joint && is_ancestor(inf.joint, e));
          for (const OrientationTarget& o : orientations_) use = use || is_ancestor(inf.joint, o.target);
        } else {
          bool revolute_above = false;
          for (int p = j.parent; p >= 0; p = s_.joints[p].parent)
            revolute_above = revolute_above || s_.joints[p].type == JointType::revolute;
          for (int e : endpoints) use = use || (!revolute_above && is_ancestor(inf.joint, e));
        }
      }
      if (use) out.push_back(d);
    }
    return out;
  }

  // Residuals r (and the Jacobian over `active` dofs) at full dofs q.
  void evaluate(const Eigen::VectorXd& q, const Targets& t, const std::vector<int>& active,
                Eigen::VectorXd& r, Eigen::MatrixXd* Jac) const {
    const Transforms G = forward_kinematics(s_, q);
    const int B = static_cast<int>(bones_.size()), O = static_cast<int>(orientations_.size());
    r.resize(3 * B + 3 + 3 * O);
    // Orientation residuals: the skew part of E = R_targetᵀ R (sin θ times the axis).
    std::vector<Eigen::Matrix3d> E(O);
    for (int o = 0; o < O; ++o) {
      E[o] = t.rotations[o].transpose() * G[orientations_[o].target].linear();
      r.segment<3>(3 * B + 3 + 3 * o) = std::sqrt(orientations_[o].weight) * vee_of_skew_part(E[o]);
    }
    std::vector<Eigen::Vector3d> dirs(B);
    std::vector<Eigen::Matrix3d> dnorm(B);  // (I − d dᵀ)/L: the normalisation's derivative
    for (int b = 0; b < B; ++b) {
      const Eigen::Vector3d v = G[bones_[b].target_to].translation() - G[bones_[b].target_from].translation();
      const double L = std::max(v.norm(), 1e-12);
      dirs[b] = v / L;
      dnorm[b] = (Eigen::Matrix3d::Identity() - dirs[b] * dirs[b].transpose()) / L;
      r.segment<3>(3 * b) = std::sqrt(bones_[b].weight) * (dirs[b] - t.directions[b]);
    }
    Eigen::Vector3d root = Eigen::Vector3d::Zero();
    for (int j : root_joints_) root += G[j].translation();
    root /= static_cast<double>(root_joints_.size());
    const double rw = std::sqrt(root_weight_) / length_scale_;
    r.segment<3>(3 * B) = rw * (root - t.root);
    if (!Jac) return;
    Eigen::MatrixXd& Jm = *Jac;
    Jm.setZero(r.size(), static_cast<Eigen::Index>(active.size()));
    for (size_t c = 0; c < active.size(); ++c) {
      for (const DofInfluence& inf : s_.dofs[active[c]].joints) {
        const Joint& joint = s_.joints[inf.joint];
        const Eigen::Vector3d axis = G[inf.joint].linear() * joint.axis;
        const Eigen::Vector3d origin = G[inf.joint].translation();
        // Velocity of joint k's origin per unit of the dof.
        auto dx = [&](int k) -> Eigen::Vector3d {
          if (!is_ancestor(inf.joint, k)) return Eigen::Vector3d::Zero();
          if (joint.type == JointType::prismatic) return inf.weight * axis;
          return inf.weight * axis.cross(G[k].translation() - origin);
        };
        for (int b = 0; b < B; ++b) {
          const Eigen::Vector3d dv = dx(bones_[b].target_to) - dx(bones_[b].target_from);
          if (dv.squaredNorm() == 0) continue;
          Jm.block<3, 1>(3 * b, c) += std::sqrt(bones_[b].weight) * (dnorm[b] * dv);
        }
        Eigen::Vector3d droot = Eigen::Vector3d::Zero();
        for (int j : root_joints_) droot += dx(j);
        Jm.block<3, 1>(3 * B, c) += rw * droot / static_cast<double>(root_joints_.size());
        // A revolute dof turns every joint below it about its world axis a: dE = [Rᵀ_target a]× E.
        if (joint.type == JointType::revolute)
          for (int o = 0; o < O; ++o) {
            if (!is_ancestor(inf.joint, orientations_[o].target)) continue;
            const Eigen::Vector3d b = t.rotations[o].transpose() * (inf.weight * axis);
            Eigen::Matrix3d bx;
            bx << 0, -b.z(), b.y(), b.z(), 0, -b.x(), -b.y(), b.x(), 0;
            Jm.block<3, 1>(3 * B + 3 + 3 * o, c) += std::sqrt(orientations_[o].weight) * vee_of_skew_part(bx * E[o]);
          }
      }
    }
  }

  // Levenberg–Marquardt over the `active` dofs of q (others untouched), from q itself.
  // `previous` and `rest` are full dof vectors for the regularisers.
  void solve(Eigen::VectorXd& q, const Targets& t, const std::vector<int>& active, const Eigen::VectorXd& previous,
             const Eigen::VectorXd& rest, int iterations) const {
    const int n = static_cast<int>(active.size());
    auto regulariser = [&](const Eigen::VectorXd& x, Eigen::VectorXd* grad) {
      double c = 0;
      if (grad) grad->setZero(n);
      for (int i = 0; i < n; ++i) {
        const double dp = x(active[i]) - previous(active[i]), dr = x(active[i]) - rest(active[i]);
        c += 0.5 * (smooth_ * dp * dp + rest_ * dr * dr);
        if (grad) (*grad)(i) = smooth_ * dp + rest_ * dr;
      }
      return c;
    };
    Eigen::VectorXd r, r_new, g;
    Eigen::MatrixXd Jm;
    evaluate(q, t, active, r, &Jm);
    double cost = 0.5 * r.squaredNorm() + regulariser(q, &g);
    double mu = 1e-4;
    for (int it = 0; it < iterations; ++it) {
      Eigen::MatrixXd H = Jm.transpose() * Jm;
      H.diagonal().array() += smooth_ + rest_;
      const Eigen::VectorXd grad = Jm.transpose() * r + g;
      bool accepted = false;
      double new_cost = cost;
      Eigen::VectorXd q_new;
      for (int attempt = 0; attempt < 12 && !accepted; ++attempt) {
        Eigen::MatrixXd A = H;
        A.diagonal().array() += mu;
        const Eigen::VectorXd step = A.ldlt().solve(-grad);
        q_new = q;
        for (int i = 0; i < n; ++i) q_new(active[i]) += step(i);
        q_new = clamp_to_limits(s_, q_new);
        evaluate(q_new, t, active, r_new, nullptr);
        new_cost = 0.5 * r_new.squaredNorm() + regulariser(q_new, nullptr);
        if (std::isfinite(new_cost) && new_cost < cost) accepted = true;
        else mu *= 8;
      }
      if (!accepted) break;
      const double decrease = cost - new_cost;
      q = q_new;
      mu = std::max(mu / 4, 1e-9);
      evaluate(q, t, active, r, &Jm);
      cost = 0.5 * r.squaredNorm() + regulariser(q, &g);
      if (decrease <= tol_ * std::max(cost, 1e-12)) break;
    }
  }

  const std::vector<RetargetBone>& bones() const { return bones_; }

 private:
  const Skeleton& s_;
  std::vector<RetargetBone> bones_;
  std::vector<OrientationTarget> orientations_;
  std::vector<int> root_joints_;
  double root_weight_, length_scale_, smooth_, rest_, tol_;
  std::vector<char> ancestor_;  // J×J: ancestor_[j*J+k] = j is k or above it
};

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / std::numbers::pi;
}

// A bone's target direction from source positions (character axes): the source's
// direction, its elevation above the horizontal shifted by the bone's offset.
Eigen::Vector3d target_direction(const std::vector<Eigen::Vector3d>& p, const RetargetBone& b, int up) {
  Eigen::Vector3d u = p[b.source_to] - p[b.source_from];
  u /= std::max(u.norm(), 1e-300);
  if (b.elevation_offset == 0) return u;
  Eigen::Vector3d h = u;
  h(up) = 0;
  if (h.norm() < 1e-9) return u;  // vertical: no heading to keep
  const double elevation = std::asin(std::clamp(u(up), -1.0, 1.0)) + b.elevation_offset;
  Eigen::Vector3d out = std::cos(elevation) * h.normalized();
  out(up) += std::sin(elevation);
  return out;
}

// Source positions of the joints we use (metres, character axes) at time t.
std::vector<Eigen::Vector3d> source_positions(const BvhMotion& motion, const RetargetMapping& m, double t) {
  const BvhTransforms G = bvh_global_transforms_at(motion, t);
  std::vector<Eigen::Vector3d> p(G.size());
  for (size_t j = 0; j < G.size(); ++j) p[j] = m.source_to_target * G[j].translation() * m.source_metres_per_unit;
  return p;
}

int source_joint(const BvhMotion& motion, const RetargetMapping& m, const std::string& name) {
  const int j = motion.joint_index(name);
  if (j < 0)
    fail(display_name(m.file), ": source joint '", name, "' is not in ", display_name(motion.source),
         " (its joints: ", motion.joints.size(), ", e.g. '", motion.joints.front().name, "')");
  return j;
}

// The mapping resolved against one BVH file and one skeleton.
struct Resolved {
  std::vector<RetargetBone> bones;
  std::vector<OrientationTarget> orientations;
  std::vector<int> source_mapped, target_mapped;  // parallel
  std::vector<int> source_root, target_root;
};

Resolved resolve(const BvhMotion& motion, const RetargetMapping& m, const Skeleton& s) {
  Resolved r;
  const std::string file = display_name(m.file);
  if (m.joints.empty()) fail(file, ": no joints mapped");
  std::vector<int> target_of(motion.joints.size(), -1);
  for (const auto& [src, dst] : m.joints) {
    const int a = source_joint(motion, m, src);
    const int b = s.joint_index(dst);
    if (b < 0) fail(file, ": character joint '", dst, "' (mapped from '", src, "') is not in the skeleton");
    if (target_of[a] >= 0) fail(file, ": source joint '", src, "' mapped twice");
    target_of[a] = b;
    r.source_mapped.push_back(a);
    r.target_mapped.push_back(b);
  }
  auto weight_of = [&](const std::string& name) {
    for (const auto& [n, w] : m.bone_weights)
      if (n == name) return w;
    return 1.0;
  };
  for (const auto& [n, w] : m.bone_weights)
    if (target_of[source_joint(motion, m, n)] < 0) fail(file, ": bone_weights: '", n, "' is not a mapped joint");
  for (const std::string& n : m.rest_elevation)
    if (target_of[source_joint(motion, m, n)] < 0) fail(file, ": rest_elevation: '", n, "' is not a mapped joint");
  for (int a : r.source_mapped) {
    int p = motion.joints[a].parent;
    while (p >= 0 && target_of[p] < 0) p = motion.joints[p].parent;
    if (p < 0) continue;  // the topmost mapped joint starts no bone
    const std::string& name = motion.joints[a].name;
    r.bones.push_back({motion.joints[p].name + "->" + name, p, a, target_of[p], target_of[a], weight_of(name)});
  }
  for (const RetargetBoneSpec& e : m.extra_bones) {
    const int a = source_joint(motion, m, e.source_from), b = source_joint(motion, m, e.source_to);
    if (target_of[a] < 0 || target_of[b] < 0)
      fail(file, ": extra bone '", e.source_from, "->", e.source_to, "' joins joints that are not mapped");
    r.bones.push_back({e.source_from + "->" + e.source_to, a, b, target_of[a], target_of[b], e.weight});
  }
  for (const auto& [n, w] : m.orientations) {
    const int a = source_joint(motion, m, n);
    if (target_of[a] < 0) fail(file, ": orientations: '", n, "' is not a mapped joint");
    r.orientations.push_back({a, target_of[a], w});
  }
  if (r.bones.empty()) fail(file, ": the mapping defines no bones (map at least two joints)");
  if (m.root_joints.empty()) fail(file, ": root.joints is empty");
  for (const std::string& n : m.root_joints) {
    const int a = source_joint(motion, m, n);
    if (target_of[a] < 0) fail(file, ": root joint '", n, "' is not mapped");
    r.source_root.push_back(a);
    r.target_root.push_back(target_of[a]);
  }
  return r;
}

// ----------------------------------------------------------------- retargeting stages

// The output times (source seconds): the clip window at the output rate.
struct OutputTimes {
  std::vector<double> times;
  double fps = 0;
};

OutputTimes output_times(const BvhMotion& motion, const RetargetOptions& o) {
  const double end = o.end_s < 0 ? motion.duration_s() : std::min(o.end_s, motion.duration_s());
  if (o.start_s < 0 || o.start_s > end) fail("retarget: clip window [", o.start_s, ", ", end, "] s is empty");
  OutputTimes out;
  out.fps = o.fps > 0 ? o.fps : 1.0 / motion.frame_time_s;
  out.times = resample_times(end - o.start_s, out.fps);
  for (double& t : out.times) t += o.start_s;
  return out;
}

// Bone lengths of the source's zero pose and the character's rest pose; a bone of zero
// length in either is an error.
struct BoneLengths {
  double source_m = 0, target_m = 0;  // metres, summed over the joint-to-joint bones
  double target_units = 0;            // character units, summed over all bones
};

BoneLengths bone_lengths(const Resolved& res, const RetargetMapping& m, const Skeleton& s,
                         const Transforms& rest, const BvhTransforms& zero, double metres_per_unit) {
  const std::string file = display_name(m.file);
  BoneLengths out;
  for (const RetargetBone& b : res.bones) {
    const double ls = (zero[b.source_to].translation() - zero[b.source_from].translation()).norm();
    const double lt = (rest[b.target_to].translation() - rest[b.target_from].translation()).norm();
    if (!(ls > 1e-9)) fail(file, ": bone '", b.name, "' has zero length in the source skeleton");
    if (!(lt > 1e-9))
      fail(file, ": bone '", b.name, "' has zero length in the character (",
           s.joints[b.target_from].name, " and ", s.joints[b.target_to].name, " coincide)");
    const bool extra = std::any_of(m.extra_bones.begin(), m.extra_bones.end(), [&](const RetargetBoneSpec& e) {
      return e.source_from + "->" + e.source_to == b.name;
    });
    if (!extra) {
      out.source_m += ls * m.source_metres_per_unit;
      out.target_m += lt * metres_per_unit;
    }
    out.target_units += lt;
  }
  return out;
}

// The bones with their elevation offsets: a bone ending at a rest_elevation joint keeps the
// character's rest elevation where the source has its zero-pose elevation.
std::vector<RetargetBone> with_rest_elevation(std::vector<RetargetBone> bones, const BvhMotion& motion,
                                              const RetargetMapping& m, const Transforms& rest,
                                              const BvhTransforms& zero) {
  const int up = m.up_axis;
  for (RetargetBone& b : bones) {
    const std::string& end = motion.joints[b.source_to].name;
    if (std::find(m.rest_elevation.begin(), m.rest_elevation.end(), end) == m.rest_elevation.end()) continue;
    const Eigen::Vector3d ds = (m.source_to_target * (zero[b.source_to].translation() - zero[b.source_from].translation())).normalized();
    const Eigen::Vector3d dc = (rest[b.target_to].translation() - rest[b.target_from].translation()).normalized();
    b.elevation_offset = std::asin(std::clamp(dc(up), -1.0, 1.0)) - std::asin(std::clamp(ds(up), -1.0, 1.0));
  }
  return bones;
}

// The heights of the mapped joints: the source's in the first output frame (metres), the
// character's at rest (units).
void measure_heights(const Resolved& res, const std::vector<Eigen::Vector3d>& first, const Transforms& rest,
                     int up, RetargetResult& out) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int a : res.source_mapped) lo = std::min(lo, first[a](up)), hi = std::max(hi, first[a](up));
  out.source_height_m = hi - lo;
  lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int b : res.target_mapped) lo = std::min(lo, rest[b].translation()(up)), hi = std::max(hi, rest[b].translation()(up));
  out.target_height = hi - lo;
}

// The source's floor (metres): the mapping's, or else the median over the output frames of
// the lowest mapped joint.
double source_floor(const Resolved& res, const RetargetMapping& m,
                    const std::vector<std::vector<Eigen::Vector3d>>& src) {
  if (!std::isnan(m.source_floor)) return m.source_floor * m.source_metres_per_unit;
  const int F = static_cast<int>(src.size());
  std::vector<double> lows(F);
  for (int f = 0; f < F; ++f) {
    double low = std::numeric_limits<double>::infinity();
    for (int a : res.source_mapped) low = std::min(low, src[f][a](m.up_axis));
    lows[f] = low;
  }
  std::nth_element(lows.begin(), lows.begin() + F / 2, lows.end());
  return lows[F / 2];
}

// The feet of both skeletons: the character's floor, and how far each skeleton's feet are
// above their standing heights.
class Feet {
 public:
  Feet(const Resolved& res, const RetargetMapping& m, const Skeleton& s, const Transforms& rest,
       const BvhTransforms& zero, double target_height)
      : s_(s), up_(m.up_axis) {
    for (const std::string& n : m.floor_markers) {
      const int k = s.marker_index(n);
      if (k < 0) fail(display_name(m.file), ": floor marker '", n, "' is not a marker of the skeleton");
      floor_markers_.push_back(k);
    }
    zero_pose_ = forward_kinematics(s, Eigen::VectorXd::Zero(s.num_dofs()));
    // The character's lowest foot point: mapped joints and floor markers (character units).
    target_floor_ = std::numeric_limits<double>::infinity();
    for (int b : res.target_mapped) target_floor_ = std::min(target_floor_, rest[b].translation()(up_));
    for (int mk : floor_markers_) target_floor_ = std::min(target_floor_, marker_height(rest, mk));
    // Feet for the floor: mapped joints near the bottom of each skeleton in its standing
    // pose (within 15% of its height: feet, not hands), and the floor markers. Each keeps its
    // own standing height, so a heel strike lowers the heel to its standing height, not to
    // the toes' height.
    for (int b : res.target_mapped)
      if (rest[b].translation()(up_) <= target_floor_ + 0.15 * target_height)
        target_feet_.emplace_back(b, rest[b].translation()(up_));
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int a : res.source_mapped) {
      const double h = (m.source_to_target * zero[a].translation())(up_);
      lo = std::min(lo, h), hi = std::max(hi, h);
    }
    for (int a : res.source_mapped) {
      const double h = (m.source_to_target * zero[a].translation())(up_);
      if (h <= lo + 0.15 * (hi - lo)) source_feet_.emplace_back(a, (h - lo) * m.source_metres_per_unit);
    }
    for (int mk : floor_markers_) marker_rest_.push_back(marker_height(rest, mk));
  }

  double target_floor() const { return target_floor_; }

  // How far the character's feet are above their standing heights (units).
  double target_clearance(const Transforms& G) const {
    double c = std::numeric_limits<double>::infinity();
    for (const auto& [b, h] : target_feet_) c = std::min(c, G[b].translation()(up_) - h);
    for (size_t i = 0; i < floor_markers_.size(); ++i) c = std::min(c, marker_height(G, floor_markers_[i]) - marker_rest_[i]);
    return c;
  }

  // How far the source's feet at positions p are above their standing heights over the
  // floor (metres).
  double source_clearance(const std::vector<Eigen::Vector3d>& p, double source_floor_m) const {
    double c = std::numeric_limits<double>::infinity();
    for (const auto& [a, h] : source_feet_) c = std::min(c, p[a](up_) - (source_floor_m + h));
    return c;
  }

 private:
  double marker_height(const Transforms& G, int mk) const {
    const Marker& marker = s_.markers[mk];
    return (G[marker.joint] * (zero_pose_[marker.joint].inverse(Eigen::Isometry) * marker.offset))(up_);
  }

  const Skeleton& s_;
  int up_;
  std::vector<int> floor_markers_;
  Transforms zero_pose_;
  double target_floor_;
  std::vector<std::pair<int, double>> target_feet_;  // joint, rest height (units)
  std::vector<std::pair<int, double>> source_feet_;  // joint, standing height (m)
  std::vector<double> marker_rest_;                  // per floor marker, rest height (units)
};

// Where the character's root goes for source positions p (character units): the source's
// root scaled by k; its height over the floor (root_on_floor) or absolute; across the floor
// relative to the first frame (root_relative) or absolute.
class RootTargets {
 public:
  RootTargets(const Resolved& res, const RetargetMapping& m, const Transforms& rest,
              const std::vector<Eigen::Vector3d>& first, double k, double metres_per_unit,
              double target_floor, double source_floor_m)
      : res_(res), m_(m), k_(k), metres_per_unit_(metres_per_unit), target_floor_(target_floor),
        source_floor_m_(source_floor_m) {
    target_root_rest_ = Eigen::Vector3d::Zero();
    for (int b : res.target_root) target_root_rest_ += rest[b].translation();
    target_root_rest_ /= static_cast<double>(res.target_root.size());
    source_root_0_ = source_root(first);
  }

  Eigen::Vector3d at(const std::vector<Eigen::Vector3d>& p) const {
    const Eigen::Vector3d ps = source_root(p);
    Eigen::Vector3d root;
    for (int i = 0; i < 3; ++i) {
      if (i == m_.up_axis) {
        root(i) = m_.root_on_floor ? target_floor_ + k_ * (ps(i) - source_floor_m_) / metres_per_unit_
                                   : k_ * ps(i) / metres_per_unit_;
      } else {
        root(i) = m_.root_relative ? target_root_rest_(i) + k_ * (ps(i) - source_root_0_(i)) / metres_per_unit_
                                   : k_ * ps(i) / metres_per_unit_;
      }
    }
    return root;
  }

 private:
  Eigen::Vector3d source_root(const std::vector<Eigen::Vector3d>& p) const {
    Eigen::Vector3d r = Eigen::Vector3d::Zero();
    for (int a : res_.source_root) r += p[a];
    return Eigen::Vector3d(r / static_cast<double>(res_.source_root.size()));
  }

  const Resolved& res_;
  const RetargetMapping& m_;
  double k_, metres_per_unit_, target_floor_, source_floor_m_;
  Eigen::Vector3d target_root_rest_, source_root_0_;
};

// Of the solved dofs, the root's own: translations and the rotations above every mapped
// joint.
std::vector<int> root_dofs_of(const std::vector<int>& solved, const Skeleton& s, const Resolved& res,
                              const Solver& solver) {
  std::vector<int> root_dofs;
  for (int d : solved) {
    bool above_all = true;
    for (const DofInfluence& inf : s.dofs[d].joints)
      for (int e : res.target_mapped) above_all = above_all && solver.is_ancestor(inf.joint, e);
    if (above_all) root_dofs.push_back(d);
  }
  return root_dofs;
}

// Frame f's dofs q, its mean bone direction error (degrees) and its root error (units)
// against the targets t, into out.
void record_frame(int f, const Eigen::VectorXd& q, const Targets& t, const Resolved& res, const Skeleton& s,
                  RetargetResult& out) {
  const std::vector<RetargetBone>& bones = out.bones;
  out.motion.dofs.row(f) = q.transpose();
  out.motion.frame_ids[f] = f;
  const Transforms G = forward_kinematics(s, q);
  double sum = 0;
  for (size_t b = 0; b < bones.size(); ++b)
    sum += angle_deg(t.directions[b], G[bones[b].target_to].translation() - G[bones[b].target_from].translation());
  out.direction_error_deg(f) = sum / static_cast<double>(bones.size());
  Eigen::Vector3d root = Eigen::Vector3d::Zero();
  for (int b : res.target_root) root += G[b].translation();
  out.root_error(f) = (root / static_cast<double>(res.target_root.size()) - t.root).norm();
  for (size_t o = 0; o < res.orientations.size(); ++o)
    out.orientation_error_deg(f) +=
        Eigen::AngleAxisd(t.rotations[o].transpose() * G[res.orientations[o].target].linear()).angle() * 180 /
        std::numbers::pi / double(res.orientations.size());
}

}  // namespace

// ----------------------------------------------------------------- mapping files

RetargetMapping parse_retarget_mapping(const std::string& text, const std::string& name) {
  const StrictYaml y{display_name(name)};
  const YAML::Node root = y.parse(text);
  RetargetMapping m;
  m.file = name;
  try {
    y.check_keys(root, "", {"source_units_m", "source_axes", "up", "joints", "bone_weights", "extra_bones",
                            "rest_elevation", "floor_markers", "root", "source_floor", "fixed_dofs", "solver",
                            "orientations"});
    if (root["source_units_m"]) m.source_metres_per_unit = y.positive(root["source_units_m"], "source_units_m");
    if (root["source_axes"]) m.source_to_target = parse_axes(y, root["source_axes"]);
    if (root["up"]) {
      const std::string up = y.get<std::string>(root["up"], "up", "x, y or z");
      m.up_axis = up == "x" ? 0 : up == "y" ? 1 : up == "z" ? 2 : -1;
      if (m.up_axis < 0) y.fail_at(root["up"], "up", "expected x, y or z, found '" + up + "'");
    }
    const YAML::Node joints = root["joints"];
    if (!joints) y.fail_at(root, "joints", "missing key (source joint: character joint)");
    if (!joints.IsMap() || joints.size() == 0) y.fail_at(joints, "joints", "expected a mapping source: target");
    for (const auto& kv : joints)
      m.joints.emplace_back(y.get<std::string>(kv.first, "joints", "a joint name"),
                            y.get<std::string>(kv.second, "joints." + kv.first.Scalar(), "a joint name"));
    if (const YAML::Node w = root["bone_weights"]) {
      if (!w.IsMap()) y.fail_at(w, "bone_weights", "expected a mapping joint: weight");
      for (const auto& kv : w) {
        const std::string key = "bone_weights." + kv.first.Scalar();
        const double v = y.number(kv.second, key);
        if (v < 0) y.fail_at(kv.second, key, "weights must be >= 0");
        m.bone_weights.emplace_back(kv.first.Scalar(), v);
      }
    }
    if (const YAML::Node e = root["extra_bones"]) {
      if (!e.IsSequence()) y.fail_at(e, "extra_bones", "expected a list of [from, to] or [from, to, weight]");
      for (const auto& b : e) {
        if (!b.IsSequence() || (b.size() != 2 && b.size() != 3))
          y.fail_at(b, "extra_bones", "expected [from, to] or [from, to, weight]");
        RetargetBoneSpec spec{y.get<std::string>(b[0], "extra_bones", "a joint name"),
                              y.get<std::string>(b[1], "extra_bones", "a joint name"), 1.0};
        if (b.size() == 3) spec.weight = y.number(b[2], "extra_bones");
        if (spec.weight < 0) y.fail_at(b, "extra_bones", "weights must be >= 0");
        m.extra_bones.push_back(spec);
      }
    }
    if (const YAML::Node w = root["orientations"]) {
      if (!w.IsMap()) y.fail_at(w, "orientations", "expected a mapping source joint: weight");
      for (const auto& kv : w) {
        const std::string key = "orientations." + kv.first.Scalar();
        const double v = y.number(kv.second, key);
        if (!(v > 0)) y.fail_at(kv.second, key, "weights must be > 0");
        m.orientations.emplace_back(kv.first.Scalar(), v);
      }
    }
    if (root["rest_elevation"]) m.rest_elevation = y.strings(root["rest_elevation"], "rest_elevation");
    if (root["floor_markers"]) m.floor_markers = y.strings(root["floor_markers"], "floor_markers");
    const YAML::Node r = root["root"];
    if (!r) y.fail_at(root, "root", "missing key (root: {joints: [...]})");
    y.check_keys(r, "root", {"joints", "weight", "scale", "vertical", "horizontal"});
    if (!r["joints"]) y.fail_at(r, "root.joints", "missing key");
    m.root_joints = y.strings(r["joints"], "root.joints");
    if (m.root_joints.empty()) y.fail_at(r["joints"], "root.joints", "expected at least one joint");
    if (r["weight"]) m.root_weight = y.positive(r["weight"], "root.weight");
    if (r["scale"]) {
      const std::string s = y.get<std::string>(r["scale"], "root.scale", "'auto' or a number");
      if (s != "auto") m.root_scale = y.positive(r["scale"], "root.scale");
    }
    if (r["vertical"]) {
      const std::string v = y.get<std::string>(r["vertical"], "root.vertical", "floor or source");
      if (v != "floor" && v != "source") y.fail_at(r["vertical"], "root.vertical", "expected floor or source");
      m.root_on_floor = v == "floor";
    }
    if (r["horizontal"]) {
      const std::string h = y.get<std::string>(r["horizontal"], "root.horizontal", "relative or source");
      if (h != "relative" && h != "source")
        y.fail_at(r["horizontal"], "root.horizontal", "expected relative or source");
      m.root_relative = h == "relative";
    }
    if (root["source_floor"]) {
      const std::string s = y.get<std::string>(root["source_floor"], "source_floor", "'auto' or a number");
      if (s != "auto") m.source_floor = y.number(root["source_floor"], "source_floor");
    }
    if (root["fixed_dofs"]) m.fixed_dofs = y.strings(root["fixed_dofs"], "fixed_dofs");
    if (const YAML::Node s = root["solver"]) {
      y.check_keys(s, "solver", {"iterations", "smoothness", "rest_weight", "tolerance"});
      if (s["iterations"]) {
        const int it = y.get<int>(s["iterations"], "solver.iterations", "an integer");
        if (it < 1 || it > 10000) y.fail_at(s["iterations"], "solver.iterations", "expected 1..10000");
        m.iterations = it;
      }
      if (s["smoothness"]) m.smoothness = y.number(s["smoothness"], "solver.smoothness");
      if (s["rest_weight"]) m.rest_weight = y.number(s["rest_weight"], "solver.rest_weight");
      if (s["tolerance"]) m.tolerance = y.number(s["tolerance"], "solver.tolerance");
      if (m.smoothness < 0 || m.rest_weight < 0 || m.tolerance < 0)
        y.fail_at(s, "solver", "weights and tolerance must be >= 0");
    }
  } catch (const YAML::Exception& e) {  // conversions deep inside yaml-cpp
    fail(y.file, ":", e.mark.line + 1, ": ", e.msg);
  }
  return m;
}

RetargetMapping load_retarget_mapping(const std::string& path) {
  return parse_retarget_mapping(read_file_bytes(path), path);
}

// ----------------------------------------------------------------- retargeting

Eigen::VectorXd bone_direction_errors_deg(const BvhMotion& motion, const RetargetMapping& m,
                                          const std::vector<RetargetBone>& bones, const Skeleton& s,
                                          const Eigen::VectorXd& dofs, double t) {
  const std::vector<Eigen::Vector3d> p = source_positions(motion, m, t);
  const Transforms G = forward_kinematics(s, dofs);
  Eigen::VectorXd e(bones.size());
  for (size_t b = 0; b < bones.size(); ++b)
    e(b) = angle_deg(target_direction(p, bones[b], m.up_axis),
                     G[bones[b].target_to].translation() - G[bones[b].target_from].translation());
  return e;
}

RetargetResult retarget_motion(const BvhMotion& motion, const RetargetMapping& m, const Skeleton& s,
                               const Eigen::VectorXd& rest_dofs, double metres_per_unit,
                               const RetargetOptions& o) {
  if (motion.num_frames() == 0) fail(display_name(motion.source), ": no frames to retarget");
  if (rest_dofs.size() != s.num_dofs())
    fail("retarget: ", rest_dofs.size(), " rest dofs for a skeleton with ", s.num_dofs());
  if (!(metres_per_unit > 0)) fail("retarget: metres_per_unit must be > 0");
  const Resolved res = resolve(motion, m, s);
  const int up = m.up_axis;
  const OutputTimes times = output_times(motion, o);
  const int F = static_cast<int>(times.times.size());

  // Rest pose of the character and zero pose of the source: lengths, heights, scale.
  const Transforms rest = forward_kinematics(s, rest_dofs);
  const BvhTransforms zero = bvh_zero_pose(motion);
  const BoneLengths lengths = bone_lengths(res, m, s, rest, zero, metres_per_unit);
  RetargetResult out;
  out.fps = times.fps;
  out.root_scale = m.root_scale > 0 ? m.root_scale : lengths.target_m / lengths.source_m;
  const double k = out.root_scale;
  out.bones = with_rest_elevation(res.bones, motion, m, rest, zero);
  const std::vector<RetargetBone>& bones = out.bones;

  // Source joint positions per output frame (metres, character axes).
  std::vector<std::vector<Eigen::Vector3d>> src(F);
  for (int f = 0; f < F; ++f) src[f] = source_positions(motion, m, times.times[f]);
  measure_heights(res, src[0], rest, up, out);
  out.source_floor_m = source_floor(res, m, src);
  const Feet feet(res, m, s, rest, zero, out.target_height);
  out.target_floor = feet.target_floor();
  const RootTargets roots(res, m, rest, src[0], k, metres_per_unit, out.target_floor, out.source_floor_m);

  // Root residuals are divided by the mean bone length: comparable to direction residuals.
  const double mean_bone = lengths.target_units / static_cast<double>(res.bones.size());
  Solver solver(s, bones, res.orientations, res.target_root, m.root_weight, mean_bone, m);
  out.solved_dofs = solver.observable_dofs(m.fixed_dofs);
  // For the first frame, the root's own dofs first: the character may face anywhere
  // relative to the source.
  const std::vector<int> root_dofs = root_dofs_of(out.solved_dofs, s, res, solver);

  out.motion.dofs.resize(F, s.num_dofs());
  out.motion.frame_ids.resize(F);
  out.direction_error_deg.resize(F);
  out.root_error.resize(F);
  out.orientation_error_deg = Eigen::VectorXd::Zero(F);
  Eigen::VectorXd q = clamp_to_limits(s, rest_dofs);
  for (int f = 0; f < F; ++f) {
    Targets t;
    for (const RetargetBone& b : bones) t.directions.push_back(target_direction(src[f], b, up));
    t.root = roots.at(src[f]);
    if (!res.orientations.empty()) {
      // The source joint's turn from its zero pose, in character axes, applied to the
      // character joint's rest rotation.
      const BvhTransforms G = bvh_global_transforms_at(motion, times.times[f]);
      for (const OrientationTarget& ot : res.orientations)
        t.rotations.push_back(m.source_to_target * G[ot.source].linear() * zero[ot.source].linear().transpose() *
                              m.source_to_target.transpose() * rest[ot.target].linear());
    }
    const Eigen::VectorXd previous = q;
    if (f == 0) {
      if (!root_dofs.empty()) solver.solve(q, t, root_dofs, previous, rest_dofs, 10 * m.iterations);
      solver.solve(q, t, out.solved_dofs, q, rest_dofs, 10 * m.iterations);
    } else {
      solver.solve(q, t, out.solved_dofs, previous, rest_dofs, m.iterations);
    }
    if (m.root_on_floor) {
      // Feet: the character's lowest mapped joint goes where the source's is (scaled),
      // whatever the two skeletons' leg proportions; the hip-height target alone leaves
      // a character with relatively shorter legs floating. Only the root height moves.
      const double source_clearance = feet.source_clearance(src[f], out.source_floor_m);  // metres
      t.root(up) += k * source_clearance / metres_per_unit - feet.target_clearance(forward_kinematics(s, q));
      solver.solve(q, t, out.solved_dofs, previous, rest_dofs, m.iterations);
    }
    record_frame(f, q, t, res, s, out);
    if (o.progress) o.progress(f + 1, F);
  }
  out.mean_direction_error_deg = out.direction_error_deg.mean();
  out.max_direction_error_deg = out.direction_error_deg.maxCoeff();
  return out;
}

Skeleton skeleton_from_bvh(const BvhMotion& motion) {
  Skeleton s;
  std::vector<int> last(motion.joints.size(), -1);  // BVH joint → its chain's last joint
  for (size_t j = 0; j < motion.joints.size(); ++j) {
    const BvhJoint& bj = motion.joints[j];
    int parent = bj.parent < 0 ? -1 : last[bj.parent];
    const size_t n = std::max<size_t>(bj.channels.size(), 1);
    for (size_t k = 0; k < n; ++k) {
      Joint joint;
      joint.parent = parent;
      joint.offset = k == 0 ? bj.offset : Eigen::Vector3d::Zero();
      joint.axis = Eigen::Vector3d::UnitX();
      if (k < bj.channels.size()) {
        const BvhChannel c = bj.channels[k];
        const int axis = c == BvhChannel::x_position || c == BvhChannel::x_rotation   ? 0
                         : c == BvhChannel::y_position || c == BvhChannel::y_rotation ? 1
                                                                                      : 2;
        joint.axis = Eigen::Vector3d::Unit(axis);
        joint.type = c == BvhChannel::x_position || c == BvhChannel::y_position || c == BvhChannel::z_position
                         ? JointType::prismatic
                         : JointType::revolute;
        Dof dof;
        dof.name = bj.name + "_" + bvh_channel_name(c);
        dof.joints.push_back({static_cast<int>(s.joints.size()), 1.0});
        s.dofs.push_back(std::move(dof));
      }
      joint.name = k + 1 == n ? bj.name : bj.name + "_c" + std::to_string(k);
      parent = static_cast<int>(s.joints.size());
      s.joints.push_back(std::move(joint));
    }
    last[j] = parent;
  }
  validate_skeleton(s, display_name(motion.source));
  return s;
}

Eigen::VectorXd bvh_frame_dofs(const BvhMotion& motion, int frame) {
  if (frame < 0 || frame >= motion.num_frames())
    fail(display_name(motion.source), ": frame ", frame, " out of range (", motion.num_frames(), " frames)");
  Eigen::VectorXd d = motion.frames.row(frame).transpose();
  for (const BvhJoint& j : motion.joints)
    for (size_t k = 0; k < j.channels.size(); ++k) {
      const BvhChannel c = j.channels[k];
      if (c == BvhChannel::x_rotation || c == BvhChannel::y_rotation || c == BvhChannel::z_rotation)
        d(j.first_channel + k) *= std::numbers::pi / 180.0;
    }
  return d;
}

RetargetResult retarget_motion(const BvhMotion& motion, const RetargetMapping& mapping, const Character& ch,
                               const RetargetOptions& options) {
  return retarget_motion(motion, mapping, ch.skeleton, ch.rest_dofs, ch.metres_per_unit, options);
}

}  // namespace weft::capture
