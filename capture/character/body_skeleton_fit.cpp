#include "capture/character/body_skeleton_fit.h"

#include "capture/character/joint_limits.h"

#include <assimp/postprocess.h>
#include <Eigen/Eigenvalues>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Importer.hpp>
#include <cmath>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <numbers>

#include "graph/error.h"

namespace weft::capture {

using Eigen::Vector3d;

// ------------------------------------------------------------------ loading

namespace {

void collect_meshes(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent,
                    std::vector<std::pair<const aiMesh*, aiMatrix4x4>>& out) {
  const aiMatrix4x4 M = parent * node->mTransformation;
  for (unsigned i = 0; i < node->mNumMeshes; ++i) out.emplace_back(scene->mMeshes[node->mMeshes[i]], M);
  for (unsigned c = 0; c < node->mNumChildren; ++c) collect_meshes(scene, node->mChildren[c], M, out);
}

Vector3d to_eigen(const aiMatrix4x4& M, const aiVector3D& v) {
  const aiVector3D p = M * v;
  return {p.x, p.y, p.z};
}

}  // namespace

LoadedBody load_body_mesh(const std::string& path, double target_height) {
  if (!std::filesystem::exists(path)) fail(path, ": file not found");
  Assimp::Importer importer;
  const aiScene* scene = importer.ReadFile(path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices);
  if (!scene || !scene->mRootNode) fail(path, ": assimp cannot read it: ", importer.GetErrorString());
  std::vector<std::pair<const aiMesh*, aiMatrix4x4>> meshes;
  collect_meshes(scene, scene->mRootNode, aiMatrix4x4(), meshes);
  if (meshes.empty()) fail(path, ": no meshes in the scene");
  // The body is the largest mesh (ties: the first in node order).
  size_t body = 0;
  for (size_t i = 1; i < meshes.size(); ++i)
    if (meshes[i].first->mNumVertices > meshes[body].first->mNumVertices) body = i;
  const aiMesh* m = meshes[body].first;
  const aiMatrix4x4& M = meshes[body].second;

  LoadedBody out;
  out.file_vertices = static_cast<int>(m->mNumVertices);
  // Weld by exact position: assimp keeps one vertex per (position, uv) pair.
  std::map<std::array<double, 3>, int> index;
  std::vector<int> remap(m->mNumVertices);
  std::vector<Vector3d> points;
  for (unsigned v = 0; v < m->mNumVertices; ++v) {
    const Vector3d p = to_eigen(M, m->mVertices[v]);
    const auto [it, added] = index.try_emplace({p.x(), p.y(), p.z()}, static_cast<int>(points.size()));
    if (added) points.push_back(p);
    remap[v] = it->second;
  }
  std::vector<std::array<int, 3>> faces;
  std::vector<std::array<int, 3>> corner;  // original (uv-split) vertex per corner
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    const aiFace& face = m->mFaces[f];
    if (face.mNumIndices != 3) continue;  // points and lines left by Triangulate
    std::array<int, 3> t{remap[face.mIndices[0]], remap[face.mIndices[1]], remap[face.mIndices[2]]};
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    faces.push_back(t);
    corner.push_back({static_cast<int>(face.mIndices[0]), static_cast<int>(face.mIndices[1]),
                      static_cast<int>(face.mIndices[2])});
  }
  if (faces.empty()) fail(path, ": the body mesh has no triangles");

  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Vector3d& p : points) lo = std::min(lo, p.y()), hi = std::max(hi, p.y());
  out.file_height = hi - lo;
  if (!(out.file_height > 0)) fail(path, ": the body mesh has zero height");
  out.scale = target_height > 0 ? target_height / out.file_height : 1.0;
  const Vector3d shift(0, -lo, 0);  // feet on y = 0 before scaling
  auto place = [&](const Vector3d& p) -> Vector3d { return (p + shift) * out.scale; };

  TriangleMesh& mesh = out.mesh;
  mesh.V.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) mesh.V.row(static_cast<Eigen::Index>(i)) = place(points[i]).transpose();
  mesh.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t f = 0; f < faces.size(); ++f)
    mesh.F.row(static_cast<Eigen::Index>(f)) << faces[f][0], faces[f][1], faces[f][2];
  if (m->HasTextureCoords(0)) {
    mesh.uv.resize(m->mNumVertices, 2);
    for (unsigned v = 0; v < m->mNumVertices; ++v) mesh.uv.row(v) << m->mTextureCoords[0][v].x, m->mTextureCoords[0][v].y;
    mesh.uv_faces.resize(mesh.F.rows(), 3);
    for (size_t f = 0; f < corner.size(); ++f)
      mesh.uv_faces.row(static_cast<Eigen::Index>(f)) << corner[f][0], corner[f][1], corner[f][2];
  }
  validate_mesh(mesh, path);

  int extra = 0;
  for (size_t i = 0; i < meshes.size(); ++i)
    if (i != body) extra += static_cast<int>(meshes[i].first->mNumVertices);
  out.extra.resize(extra, 3);
  int row = 0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    if (i == body) continue;
    for (unsigned v = 0; v < meshes[i].first->mNumVertices; ++v)
      out.extra.row(row++) = place(to_eigen(meshes[i].second, meshes[i].first->mVertices[v])).transpose();
  }
  return out;
}

// ------------------------------------------------------------------ cross-sections

std::vector<Section> slice_mesh(const TriangleMesh& mesh, const Vector3d& n, double d) {
  const Vertices& V = mesh.V;
  const Faces& F = mesh.F;
  std::vector<char> above(V.rows());
  for (Eigen::Index i = 0; i < V.rows(); ++i) above[i] = V.row(i).dot(n) >= d;
  auto key = [](int a, int b) { return a < b ? std::pair<int, int>{a, b} : std::pair<int, int>{b, a}; };
  // Each crossed edge is a contour point; each cut triangle links its two crossed edges.
  std::map<std::pair<int, int>, std::vector<std::pair<int, int>>> links;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    std::pair<int, int> cut[2];
    int k = 0;
    for (int e = 0; e < 3; ++e) {
      const int a = F(f, e), b = F(f, (e + 1) % 3);
      if (above[a] != above[b]) cut[k++] = key(a, b);
    }
    if (k != 2) continue;
    links[cut[0]].push_back(cut[1]);
    links[cut[1]].push_back(cut[0]);
  }
  auto point = [&](const std::pair<int, int>& e) -> Vector3d {
    const Vector3d a = V.row(e.first), b = V.row(e.second);
    const double da = a.dot(n) - d, db = b.dot(n) - d;
    const double t = da / (da - db);
    return a + t * (b - a);
  };
  std::vector<Section> out;
  std::map<std::pair<int, int>, bool> used;
  for (const auto& [start, next] : links) {
    if (used[start]) continue;
    Section s;
    std::pair<int, int> prev{-1, -1}, cur = start;
    while (!used[cur]) {
      used[cur] = true;
      s.points.push_back(point(cur));
      const auto& nb = links[cur];
      std::pair<int, int> step = nb[0] == prev && nb.size() > 1 ? nb[1] : nb[0];
      if (used[step] && nb.size() > 1 && !used[nb[1]]) step = nb[1];
      prev = cur;
      cur = step;
    }
    if (s.points.size() < 3) continue;
    // Area and centroid by a fan from the first point, areas signed along n.
    double area = 0;
    Vector3d c = Vector3d::Zero();
    const Vector3d& o = s.points[0];
    for (size_t i = 1; i + 1 < s.points.size(); ++i) {
      const double a = 0.5 * (s.points[i] - o).cross(s.points[i + 1] - o).dot(n);
      area += a;
      c += a * (o + s.points[i] + s.points[i + 1]) / 3.0;
    }
    s.area = std::abs(area);
    s.centroid = std::abs(area) > 1e-300 ? Vector3d(c / area) : o;
    s.lo = s.hi = o;
    for (const Vector3d& p : s.points) s.lo = s.lo.cwiseMin(p), s.hi = s.hi.cwiseMax(p);
    out.push_back(std::move(s));
  }
  return out;
}

double winding_number(const Vertices& V, const Faces& F, const Vector3d& p) {
  // Van Oosterom & Strackee: the solid angle of each triangle seen from p.
  double total = 0;
  for (Eigen::Index f = 0; f < F.rows(); ++f) {
    const Vector3d a = V.row(F(f, 0)).transpose() - p, b = V.row(F(f, 1)).transpose() - p,
                   c = V.row(F(f, 2)).transpose() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    total += 2 * std::atan2(num, den);
  }
  return total / (4 * std::numbers::pi);
}

// ------------------------------------------------------------------ skeleton

const std::vector<std::string> kBodyJointNames = {
    "hips",      "spine",      "chest",   "neck",    "head",    "l_clavicle", "l_shoulder",
    "l_elbow",   "l_wrist",    "l_hip",   "l_knee",  "l_ankle", "l_toe",      "r_clavicle",
    "r_shoulder", "r_elbow",   "r_wrist", "r_hip",   "r_knee",  "r_ankle",    "r_toe"};
const std::vector<std::string> kBodyEndSiteNames = {"head_end", "l_hand_end", "l_toe_end", "r_hand_end",
                                                     "r_toe_end"};

namespace {

enum class Kind { root, ball, knee, elbow, toe, end };

struct JointSpec {
  const char* name;
  const char* parent;
  Kind kind;
};

// Parents before children.
const JointSpec kSpecs[] = {
    {"hips", nullptr, Kind::root},         {"spine", "hips", Kind::ball},
    {"chest", "spine", Kind::ball},        {"neck", "chest", Kind::ball},
    {"head", "neck", Kind::ball},          {"head_end", "head", Kind::end},
    {"l_clavicle", "chest", Kind::ball},   {"l_shoulder", "l_clavicle", Kind::ball},
    {"l_elbow", "l_shoulder", Kind::elbow}, {"l_wrist", "l_elbow", Kind::ball},
    {"l_hand_end", "l_wrist", Kind::end},  {"r_clavicle", "chest", Kind::ball},
    {"r_shoulder", "r_clavicle", Kind::ball}, {"r_elbow", "r_shoulder", Kind::elbow},
    {"r_wrist", "r_elbow", Kind::ball},    {"r_hand_end", "r_wrist", Kind::end},
    {"l_hip", "hips", Kind::ball},         {"l_knee", "l_hip", Kind::knee},
    {"l_ankle", "l_knee", Kind::ball},     {"l_toe", "l_ankle", Kind::toe},
    {"l_toe_end", "l_toe", Kind::end},     {"r_hip", "hips", Kind::ball},
    {"r_knee", "r_hip", Kind::knee},       {"r_ankle", "r_knee", Kind::ball},
    {"r_toe", "r_ankle", Kind::toe},       {"r_toe_end", "r_toe", Kind::end},
};

const Vector3d& at(const std::map<std::string, Vector3d>& m, const std::string& name) {
  const auto it = m.find(name);
  if (it == m.end()) fail("body skeleton: missing joint position '", name, "'");
  return it->second;
}

}  // namespace

Skeleton build_body_skeleton(const std::map<std::string, Vector3d>& pos,
                             const std::map<std::string, Vector3d>& markers) {
  Skeleton s;
  std::map<std::string, int> last;  // anatomical name → its chain's last joint index
  auto add_joint = [&](const std::string& name, JointType type, int parent, const Vector3d& offset,
                       const Vector3d& axis) {
    Joint j;
    j.name = name;
    j.type = type;
    j.parent = parent;
    j.offset = offset;
    j.axis = axis;
    s.joints.push_back(j);
    return s.num_joints() - 1;
  };
  auto add_dof = [&](const std::string& name, int joint, double lo = 0, double hi = 0) {
    Dof d;
    d.name = name;
    d.joints.push_back({joint, 1.0});
    d.limited = lo < hi;
    d.lower = lo;
    d.upper = hi;
    s.dofs.push_back(d);
  };
  const Vector3d X = Vector3d::UnitX(), Y = Vector3d::UnitY(), Z = Vector3d::UnitZ();
  for (const JointSpec& spec : kSpecs) {
    const std::string name = spec.name;
    const int parent = spec.parent ? last.at(spec.parent) : -1;
    // The zero pose is the bind pose and every joint frame is axis-aligned there, so an
    // offset is the difference of model-frame positions.
    const Vector3d offset = at(pos, name) - (spec.parent ? at(pos, spec.parent) : Vector3d::Zero());
    switch (spec.kind) {
      case Kind::root: {
        int j = add_joint(name + "_tx", JointType::prismatic, -1, offset, X);
        add_dof(name + "_tx", j);
        j = add_joint(name + "_ty", JointType::prismatic, j, Vector3d::Zero(), Y);
        add_dof(name + "_ty", j);
        j = add_joint(name + "_tz", JointType::prismatic, j, Vector3d::Zero(), Z);
        add_dof(name + "_tz", j);
        j = add_joint(name + "_rx", JointType::revolute, j, Vector3d::Zero(), X);
        add_dof(name + "_rx", j);
        j = add_joint(name + "_ry", JointType::revolute, j, Vector3d::Zero(), Y);
        add_dof(name + "_ry", j);
        j = add_joint(name, JointType::revolute, j, Vector3d::Zero(), Z);
        add_dof(name + "_rz", j);
        last[name] = j;
        break;
      }
      case Kind::ball: {
        int j = add_joint(name + "_rx", JointType::revolute, parent, offset, X);
        add_dof(name + "_rx", j);
        j = add_joint(name + "_ry", JointType::revolute, j, Vector3d::Zero(), Y);
        add_dof(name + "_ry", j);
        j = add_joint(name, JointType::revolute, j, Vector3d::Zero(), Z);
        add_dof(name + "_rz", j);
        last[name] = j;
        break;
      }
      case Kind::knee: {
        // +x rotation swings the shank backward (−z): flexion is positive.
        const int j = add_joint(name, JointType::revolute, parent, offset, X);
        add_dof(name + "_rx", j, -0.05, 2.6);
        last[name] = j;
        break;
      }
      case Kind::toe: {
        // +x rotation turns the toes down; extension (toes up) is negative.
        const int j = add_joint(name, JointType::revolute, parent, offset, X);
        add_dof(name + "_rx", j, -1.0, 0.6);
        last[name] = j;
        break;
      }
      case Kind::elbow: {
        // Hinge axis a = upper arm × forward, so that +angle swings the forearm to the
        // front (a × upper arm = +z): flexion is positive.
        const Vector3d upper = offset.normalized();
        Vector3d a = upper.cross(Z);
        if (a.norm() < 1e-6) a = X;
        const int j = add_joint(name, JointType::revolute, parent, offset, a.normalized());
        add_dof(name + "_flex", j, -0.05, 2.7);
        last[name] = j;
        break;
      }
      case Kind::end:
        last[name] = add_joint(name, JointType::revolute, parent, offset, X);
        break;
    }
  }
  // Markers: the face on the head, heels on the ankles, toes on the toe joints. Offsets
  // are model-frame points at the zero pose (= the bind pose here).
  for (const auto& [name, p] : markers) {
    std::string joint = "head";
    if (name.find("heel") != std::string::npos) joint = name.substr(0, 2) + "ankle";
    if (name.find("toe") != std::string::npos) joint = name.substr(0, 2) + "toe";
    Marker m;
    m.name = name;
    m.joint = last.at(joint);
    m.offset = p;
    m.size = 0.01;
    s.markers.push_back(m);
  }
  apply_dof_limits(s, default_body_dof_limits(), "body skeleton");
  validate_skeleton(s, "body skeleton");
  return s;
}

std::vector<std::string> body_skeleton_dof_names() {
  std::vector<std::string> out;
  for (const JointSpec& spec : kSpecs) {
    const std::string name = spec.name;
    switch (spec.kind) {
      case Kind::root:
        for (const char* a : {"_tx", "_ty", "_tz", "_rx", "_ry", "_rz"}) out.push_back(name + a);
        break;
      case Kind::ball:
        for (const char* a : {"_rx", "_ry", "_rz"}) out.push_back(name + a);
        break;
      case Kind::knee:
      case Kind::toe:
        out.push_back(name + "_rx");
        break;
      case Kind::elbow:
        out.push_back(name + "_flex");
        break;
      case Kind::end:
        break;
    }
  }
  return out;
}

// ------------------------------------------------------------------ the fit

namespace {

struct Fitter {
  const TriangleMesh& body;
  const std::string& what;
  double H = 0;     // height
  double step = 0;  // between the sections of a scan (0.002 H)

  std::vector<Section> horizontal(double y) const { return slice_mesh(body, Vector3d::UnitY(), y); }
  static bool straddles(const Section& s) { return s.lo.x() < 0 && s.hi.x() > 0; }

  // The section containing the midline (the torso, neck or head) at height y.
  Section midline(double y) const {
    const Section* best = nullptr;
    const auto sections = horizontal(y);
    for (const Section& s : sections)
      if (straddles(s) && (!best || s.area > best->area)) best = &s;
    if (!best) fail(what, ": no cross-section of the body crosses x = 0 at height ", y);
    return *best;
  }
  // The centroid of the midline section at height y, at that height.
  Vector3d mid(double y) const {
    Vector3d c = midline(y).centroid;
    c.y() = y;
    return c;
  }
  // The side section (not crossing x = 0) on side `sign` closest to `near` (x, z only).
  bool side_section(double y, double sign, const Vector3d& near, double max_dist, Section& out) const {
    double best = max_dist;
    bool found = false;
    for (Section& s : horizontal(y)) {
      if (straddles(s) || s.centroid.x() * sign <= 0) continue;
      const double d = std::hypot(s.centroid.x() - near.x(), s.centroid.z() - near.z());
      if (d < best) best = d, out = std::move(s), found = true;
    }
    return found;
  }
  // The section of plane (n, n·p) whose centroid is closest to p.
  bool section_near(const Vector3d& n, const Vector3d& p, double max_dist, Section& out) const {
    double best = max_dist;
    bool found = false;
    for (Section& s : slice_mesh(body, n, n.dot(p))) {
      const double d = (s.centroid - p).norm();
      if (d < best) best = d, out = std::move(s), found = true;
    }
    return found;
  }
};

// Least-squares line through points: centre and unit direction (largest principal axis).
std::pair<Vector3d, Vector3d> principal_axis(const std::vector<Vector3d>& pts) {
  Vector3d c = Vector3d::Zero();
  for (const auto& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) C += (p - c) * (p - c).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  return {c, es.eigenvectors().col(2)};
}


// ---- the stages of the fit

std::string side_prefix(double sign) { return sign > 0 ? "l_" : "r_"; }

// Crotch: the lowest height (above the knees) where a section crosses the midline.
double find_crotch(const Fitter& fx) {
  const double H = fx.H;
  for (double y = 0.30 * H; y < 0.70 * H; y += fx.step) {
    bool mid = false;
    for (const Section& s : fx.horizontal(y)) mid = mid || Fitter::straddles(s);
    if (mid) return y;
  }
  fail(fx.what, ": no crotch found between 0.3 and 0.7 of the height (legs not apart?)");
}

// Armpits: going down from the shoulders, the first height where both arms are separate
// sections next to the torso.
double find_armpits(const Fitter& fx, double crotch_y) {
  const double H = fx.H;
  for (double y = 0.84 * H; y > crotch_y + 0.1 * H; y -= fx.step) {
    bool left = false, right = false;
    for (const Section& s : fx.horizontal(y)) {
      if (Fitter::straddles(s)) continue;
      left = left || s.centroid.x() > 0;
      right = right || s.centroid.x() < 0;
    }
    if (left && right) return y;
  }
  fail(fx.what, ": no armpits found (arms not away from the torso?)");
}

// The height of the narrowest midline section in [y0, y1), or `none` if there is no step
// in that range.
double narrowest_midline(const Fitter& fx, double y0, double y1, double none) {
  double best = std::numeric_limits<double>::infinity(), at = none;
  for (double y = y0; y < y1; y += fx.step) {
    const Section s = fx.midline(y);
    if (s.area < best) best = s.area, at = y;
  }
  return at;
}

// The midline joints: hips, spine, chest, neck, head and the head's end site.
void fit_torso(const Fitter& fx, double hip_y, double ymax, BodySkeletonFit& fit) {
  const double H = fx.H;
  auto& J = fit.joints;
  J["hips"] = fx.mid(hip_y);
  J["neck"] = fx.mid(fit.neck_y - 0.03 * H);
  // The head joint sits above the mid-neck: a section at that height may take in the chin
  // and move its centroid forward, out of the neck.
  J["head"] = fx.mid(fit.neck_y) + Vector3d(0, 0.02 * H, 0);
  J["spine"] = fx.mid(hip_y + 0.35 * (J["neck"].y() - hip_y));
  J["chest"] = fx.mid(hip_y + 0.70 * (J["neck"].y() - hip_y));
  Vector3d top = fx.mid(ymax - 0.05 * H);
  top.y() = ymax - 0.02 * H;
  J["head_end"] = top;
}

// The narrowest section of the leg on side `sign` between heights y0 and y1, followed
// upwards from y1 starting near `near`; its centroid at its height.
Vector3d narrowest_leg(const Fitter& fx, double sign, double y0, double y1, Vector3d near) {
  double best = std::numeric_limits<double>::infinity();
  Vector3d at_best = near;
  for (double y = y1; y >= y0; y -= fx.step) {
    Section s;
    if (!fx.side_section(y, sign, near, 0.08 * fx.H, s)) continue;
    near = s.centroid;
    if (s.area < best) best = s.area, at_best = s.centroid, at_best.y() = y;
  }
  if (!std::isfinite(best)) fail(fx.what, ": no ", side_prefix(sign), "leg sections between heights ", y0, " and ", y1);
  return at_best;
}

// A leg's hip, knee and ankle on side `sign` (+1 left, -1 right): centroids of the leg
// sections below the crotch.
void fit_leg(const Fitter& fx, double sign, double hip_y, BodySkeletonFit& fit) {
  const double H = fx.H;
  const std::string p = side_prefix(sign);
  auto& J = fit.joints;
  Section leg;
  Vector3d guess(sign * 0.06 * H, 0, J["hips"].z());
  if (!fx.side_section(fit.crotch_y - 0.03 * H, sign, guess, 0.15 * H, leg))
    fail(fx.what, ": no ", p, "leg section below the crotch");
  J[p + "hip"] = Vector3d(leg.centroid.x(), hip_y, leg.centroid.z());
  // Knee: the narrowest leg section between 0.24 and 0.33 of the height.
  J[p + "knee"] = narrowest_leg(fx, sign, 0.24 * H, 0.33 * H, leg.centroid);
  // Ankle: on the line from the knee through the narrowest shin section, at 0.045 H
  // (the malleoli); the section itself would be pulled forward by the foot.
  const Vector3d shin = narrowest_leg(fx, sign, 0.07 * H, 0.14 * H, J[p + "knee"]);
  const Vector3d& knee = J[p + "knee"];
  const double ankle_y = 0.045 * H;
  J[p + "ankle"] = knee + (shin - knee) * (knee.y() - ankle_y) / (knee.y() - shin.y());
}

// A foot's toe joint and toe end on side `sign`, and its heel and toe markers.
void fit_foot(const Fitter& fx, double sign, BodySkeletonFit& fit) {
  const TriangleMesh& body = fx.body;
  const double H = fx.H;
  const std::string p = side_prefix(sign);
  auto& J = fit.joints;
  auto& M = fit.markers;
  const double ankle_y = 0.045 * H;
  const Vector3d ankle = J[p + "ankle"];
  // Foot: vertices below 1.3 × ankle height on this side.
  std::vector<int> foot;
  for (int v = 0; v < body.num_vertices(); ++v)
    if (body.V(v, 1) < 1.3 * ankle_y && body.V(v, 0) * sign > 0 && std::abs(body.V(v, 0) - ankle.x()) < 0.1 * H)
      foot.push_back(v);
  if (foot.size() < 10) fail(fx.what, ": no ", p, "foot found below the ankle");
  double heel_z = std::numeric_limits<double>::infinity(), tip_z = -heel_z;
  for (int v : foot) heel_z = std::min(heel_z, body.V(v, 2)), tip_z = std::max(tip_z, body.V(v, 2));
  const double foot_len = tip_z - heel_z;
  Section s;
  // Toe joint (ball of the foot) at 75 % of the foot length, toe end at 90 %.
  const Vector3d ball_guess(ankle.x(), 0.3 * ankle_y, heel_z + 0.75 * foot_len);
  if (!fx.section_near(Vector3d::UnitZ(), ball_guess, 0.08 * H, s))
    fail(fx.what, ": no ", p, "foot section at the ball of the foot");
  J[p + "toe"] = s.centroid;
  const Vector3d tip_guess(s.centroid.x(), s.centroid.y(), heel_z + 0.92 * foot_len);
  if (!fx.section_near(Vector3d::UnitZ(), tip_guess, 0.08 * H, s))
    fail(fx.what, ": no ", p, "foot section at the toes");
  J[p + "toe_end"] = s.centroid;
  // Markers: the heel (rearmost foot vertices), big and small toe (frontmost vertices on
  // the inner and outer side of the toe joint).
  Vector3d heel = Vector3d::Zero();
  int n_heel = 0;
  for (int v : foot)
    if (body.V(v, 2) < heel_z + 0.005 * H) heel += body.V.row(v).transpose(), ++n_heel;
  M[p + "heel"] = heel / n_heel;
  double outer = 0;
  for (int v : foot)
    if (body.V(v, 2) > J[p + "toe"].z()) outer = std::max(outer, sign * (body.V(v, 0) - J[p + "toe"].x()));
  int big = -1, small = -1;
  for (int v : foot) {
    const double lateral = sign * (body.V(v, 0) - J[p + "toe"].x());
    if (lateral <= 0 && (big < 0 || body.V(v, 2) > body.V(big, 2))) big = v;
    if (lateral >= 0.6 * outer && (small < 0 || body.V(v, 2) > body.V(small, 2))) small = v;
  }
  if (big < 0 || small < 0) fail(fx.what, ": cannot place the ", p, "toe markers");
  M[p + "big_toe"] = body.V.row(big).transpose();
  M[p + "small_toe"] = body.V.row(small).transpose();
}

// The centroids of the arm's horizontal sections on side `sign`, followed down from the
// armpit.
std::vector<Vector3d> arm_sections(const Fitter& fx, double sign, double armpit_y) {
  const std::string p = side_prefix(sign);
  std::vector<Vector3d> arm;
  Section a;
  double best = -1;
  for (const Section& sec : fx.horizontal(armpit_y - fx.step))
    if (!Fitter::straddles(sec) && sec.centroid.x() * sign > best) best = sec.centroid.x() * sign, a = sec;
  if (best < 0) fail(fx.what, ": no ", p, "arm section below the armpit");
  arm.push_back(a.centroid);
  for (double y = armpit_y - 2 * fx.step; y > 0.2 * fx.H; y -= fx.step) {
    Section next;
    // Each section must continue the last one (within 0.03 H): the thigh, far inside
    // the hand, never qualifies, and the arm ends below the finger tips.
    if (!fx.side_section(y, sign, arm.back(), 0.03 * fx.H, next)) break;
    arm.push_back(next.centroid);
  }
  if (arm.size() < 20) fail(fx.what, ": the ", p, "arm is too short to fit (", arm.size(), " sections)");
  return arm;
}

// Stations along the arm on side `sign`: sections perpendicular to the axis `dir`, from
// 20 % to 95 % of the length L from the shoulder, each near the previous one's centroid;
// with their distances from the shoulder.
std::vector<std::pair<double, Section>> arm_stations(const Fitter& fx, double sign, const Vector3d& shoulder,
                                                     const Vector3d& dir, double L) {
  std::vector<std::pair<double, Section>> stations;
  Vector3d near = shoulder;
  for (int i = 20; i <= 95; ++i) {
    const double sdist = L * i / 100.0;
    const Vector3d q = shoulder + sdist * dir;
    Section sec;
    if (!fx.section_near(dir, Vector3d(q + (near - q) - (near - q).dot(dir) * dir), 0.05 * fx.H, sec)) continue;
    near = sec.centroid;
    stations.emplace_back(sdist, sec);
  }
  if (stations.size() < 30)
    fail(fx.what, ": cannot follow the ", side_prefix(sign), "arm (", stations.size(), " sections)");
  return stations;
}

// An arm's shoulder, elbow, wrist and hand end on side `sign`: on the arm's axis, from
// sections across it.
void fit_arm(const Fitter& fx, double sign, BodySkeletonFit& fit) {
  const TriangleMesh& body = fx.body;
  const double H = fx.H;
  const std::string p = side_prefix(sign);
  auto& J = fit.joints;
  const std::vector<Vector3d> arm = arm_sections(fx, sign, fit.armpit_y);
  auto [centre, dir] = principal_axis(arm);
  if (dir.y() > 0) dir = -dir;  // from the shoulder down to the hand
  // Hand tip: the farthest vertex along the axis among vertices near the axis line.
  double tip = -std::numeric_limits<double>::infinity();
  for (int v = 0; v < body.num_vertices(); ++v) {
    const Vector3d q = body.V.row(v).transpose() - centre;
    if (body.V(v, 0) * sign > 0 && (q - q.dot(dir) * dir).norm() < 0.06 * H) tip = std::max(tip, q.dot(dir));
  }
  // Shoulder: 0.04 H above the armpit, on the upper arm's axis (the first third of the
  // sections) across, and above the first arm section front to back (the whole arm's
  // axis leans forward to the hands).
  const std::vector<Vector3d> upper(arm.begin(), arm.begin() + static_cast<long>(arm.size() / 3));
  auto [ucentre, udir] = principal_axis(upper);
  if (udir.y() > 0) udir = -udir;
  Vector3d shoulder = ucentre + (fit.armpit_y + 0.04 * H - ucentre.y()) / udir.y() * udir;
  shoulder.z() = arm.front().z();
  const double t_sh = (shoulder - centre).dot(dir);
  J[p + "shoulder"] = shoulder;
  const double L = tip - t_sh;  // shoulder to finger tip along the axis
  const std::vector<std::pair<double, Section>> stations = arm_stations(fx, sign, shoulder, dir, L);
  // Wrist: the narrowest section in 62–85 % of the length; elbow at the upper arm's
  // share of the shoulder–wrist distance (0.186 : 0.146 of the height, Drillis–Contini).
  double best = std::numeric_limits<double>::infinity(), s_wrist = 0;
  for (const auto& [sd, sec] : stations)
    if (sd > 0.62 * L && sd < 0.85 * L && sec.area < best) best = sec.area, s_wrist = sd, J[p + "wrist"] = sec.centroid;
  if (!std::isfinite(best)) fail(fx.what, ": no ", p, "wrist section");
  auto station_at = [&](double sd) {
    const auto* b = &stations.front();
    for (const auto& st : stations)
      if (std::abs(st.first - sd) < std::abs(b->first - sd)) b = &st;
    return b->second.centroid;
  };
  J[p + "elbow"] = station_at(s_wrist * 0.186 / (0.186 + 0.146));
  J[p + "hand_end"] = station_at(s_wrist + 0.6 * (L - s_wrist));
}

// Clavicles: the sternoclavicular joints, a fifth of the way to the shoulders.
void fit_clavicles(const Fitter& fx, BodySkeletonFit& fit) {
  auto& J = fit.joints;
  for (const double sign : {1.0, -1.0}) {
    const std::string p = side_prefix(sign);
    const Vector3d sh = J[p + "shoulder"];
    const Vector3d c = fx.mid(sh.y());
    J[p + "clavicle"] = Vector3d(c.x() + 0.2 * (sh.x() - c.x()), sh.y(), c.z());
  }
}

// Face markers. Nose: the frontmost head vertex; eyes: the front of each eyeball (or,
// without eyeballs, 3.5 cm up and 3.2 cm aside from the nose, scaled to the height);
// ears: the outermost head vertices around eye height.
void fit_face_markers(const Fitter& fx, const Vertices& eye_points, BodySkeletonFit& fit) {
  const TriangleMesh& body = fx.body;
  const double H = fx.H;
  auto& M = fit.markers;
  const double head_lo = fit.neck_y + 0.02 * H;
  int nose = -1;
  for (int v = 0; v < body.num_vertices(); ++v)
    if (body.V(v, 1) > head_lo && std::abs(body.V(v, 0)) < 0.02 * H && (nose < 0 || body.V(v, 2) > body.V(nose, 2)))
      nose = v;
  if (nose < 0) fail(fx.what, ": no head vertices above the neck");
  M["nose"] = body.V.row(nose).transpose();
  for (const double sign : {1.0, -1.0}) {
    const std::string p = side_prefix(sign);
    Vector3d eye = Vector3d::Zero();
    int n = 0;
    double front = -std::numeric_limits<double>::infinity();
    for (Eigen::Index v = 0; v < eye_points.rows(); ++v)
      if (eye_points(v, 0) * sign > 0 && eye_points(v, 1) > head_lo)
        eye += eye_points.row(v).transpose(), ++n, front = std::max(front, eye_points(v, 2));
    if (n > 0) {
      eye /= n;
      eye.z() = front;
    } else {
      eye = M["nose"] + Vector3d(sign * 0.032, 0.035, -0.02) * (H / 1.66);
    }
    M[p + "eye"] = eye;
    int ear = -1;
    for (int v = 0; v < body.num_vertices(); ++v) {
      if (std::abs(body.V(v, 1) - eye.y()) > 0.02 * H || body.V(v, 2) > eye.z()) continue;
      if (ear < 0 || sign * body.V(v, 0) > sign * body.V(ear, 0)) ear = v;
    }
    if (ear < 0) fail(fx.what, ": no ", p, "ear found");
    M[p + "ear"] = body.V.row(ear).transpose();
  }
}

// Every joint must lie inside the body.
void check_joints_inside(const Fitter& fx, const std::map<std::string, Vector3d>& J) {
  std::string outside;
  for (const auto& [name, q] : J)
    if (!inside_mesh(fx.body.V, fx.body.F, q))
      outside += " " + name + " (" + std::to_string(q.x()) + ", " + std::to_string(q.y()) + ", " +
                 std::to_string(q.z()) + ")";
  if (!outside.empty()) fail(fx.what, ": fitted joints outside the body:", outside);
}

// The BODY_25 keypoints as joints and markers of the fitted skeleton; every one must be
// mapped.
void map_body25(BodySkeletonFit& fit, const std::string& what) {
  const Skeleton& s = fit.skeleton;
  auto j = [&](const char* n) { return LandmarkSource{{s.joint_index(n)}, {}}; };
  auto mk = [&](const char* n) { return LandmarkSource{{}, {s.marker_index(n)}}; };
  auto& b = fit.body25;
  b[body25_index("Nose")] = mk("nose");
  b[body25_index("Neck")] = j("neck");
  b[body25_index("MidHip")] = LandmarkSource{{s.joint_index("l_hip"), s.joint_index("r_hip")}, {}};
  for (const char* side : {"L", "R"}) {
    const std::string w = side, p = side[0] == 'L' ? "l_" : "r_";
    auto jn = [&](const std::string& n) { return LandmarkSource{{s.joint_index(p + n)}, {}}; };
    auto mn = [&](const std::string& n) { return LandmarkSource{{}, {s.marker_index(p + n)}}; };
    b[body25_index(w + "Shoulder")] = jn("shoulder");
    b[body25_index(w + "Elbow")] = jn("elbow");
    b[body25_index(w + "Wrist")] = jn("wrist");
    b[body25_index(w + "Hip")] = jn("hip");
    b[body25_index(w + "Knee")] = jn("knee");
    b[body25_index(w + "Ankle")] = jn("ankle");
    b[body25_index(w + "Eye")] = mn("eye");
    b[body25_index(w + "Ear")] = mn("ear");
    b[body25_index(w + "BigToe")] = mn("big_toe");
    b[body25_index(w + "SmallToe")] = mn("small_toe");
    b[body25_index(w + "Heel")] = mn("heel");
  }
  for (int k = 0; k < kBody25Count; ++k)
    if (b[k].empty() || (b[k].joints.size() && b[k].joints[0] < 0) || (b[k].markers.size() && b[k].markers[0] < 0))
      fail(what, ": BODY_25 keypoint ", kBody25Names[k], " is not mapped");
}
}  // namespace

BodySkeletonFit fit_body_skeleton(const TriangleMesh& body, const Vertices& eye_points, const std::string& what) {
  if (body.num_vertices() < 100) fail(what, ": the body mesh is too small to fit a skeleton");
  BodySkeletonFit fit;
  Fitter fx{body, what};
  const double ymin = body.V.col(1).minCoeff(), ymax = body.V.col(1).maxCoeff();
  if (std::abs(ymin) > 1e-9 * (ymax - ymin) + 1e-12) fail(what, ": the body's feet must be on y = 0");
  const double H = fx.H = fit.height = ymax - ymin;
  fx.step = 0.002 * H;

  fit.crotch_y = find_crotch(fx);
  fit.armpit_y = find_armpits(fx, fit.crotch_y);
  // Neck: the narrowest midline section between the shoulders and the head top.
  fit.neck_y = narrowest_midline(fx, fit.armpit_y + 0.04 * H, 0.95 * H, fit.neck_y);
  const double hip_y = fit.crotch_y + 0.05 * H;
  fit_torso(fx, hip_y, ymax, fit);
  // Waist: the narrowest torso section between the hips and the chest (for garments).
  fit.waist_y = narrowest_midline(fx, hip_y, fit.joints["chest"].y(), fit.waist_y);
  for (const double sign : {1.0, -1.0}) {
    fit_leg(fx, sign, hip_y, fit);
    fit_foot(fx, sign, fit);
    fit_arm(fx, sign, fit);
  }
  fit_clavicles(fx, fit);
  fit_face_markers(fx, eye_points, fit);
  check_joints_inside(fx, fit.joints);

  fit.skeleton = build_body_skeleton(fit.joints, fit.markers);
  map_body25(fit, what);
  return fit;
}

std::vector<char> arm_vertices(const TriangleMesh& body, const BodySkeletonFit& fit) {
  const double step = 0.002 * fit.height;
  const double y0 = fit.crotch_y, y1 = fit.armpit_y;
  // Torso extent across (x) per height bin; arms are the sections beside it.
  const int bins = std::max(1, static_cast<int>(std::ceil((y1 - y0) / step)));
  std::vector<double> lo(bins), hi(bins);
  for (int b = 0; b < bins; ++b) {
    const double y = y0 + (b + 0.5) * (y1 - y0) / bins;
    lo[b] = -std::numeric_limits<double>::infinity(), hi[b] = -lo[b];
    for (const Section& s : slice_mesh(body, Vector3d::UnitY(), y))
      if (s.lo.x() < 0 && s.hi.x() > 0) lo[b] = s.lo.x(), hi[b] = s.hi.x();
  }
  std::vector<char> arm(body.num_vertices(), 0);
  for (const double sign : {1.0, -1.0}) {
    const std::string p = sign > 0 ? "l_" : "r_";
    const Vector3d sh = fit.joints.at(p + "shoulder");
    const Vector3d u = (fit.joints.at(p + "elbow") - sh).normalized();
    for (int v = 0; v < body.num_vertices(); ++v) {
      const Vector3d q = body.V.row(v).transpose();
      if (q.x() * sign <= 0 || q.y() < y0) continue;
      if (q.y() >= y1) {
        arm[v] = (q - sh).dot(u) > 0;
      } else {
        const int b = std::clamp(static_cast<int>((q.y() - y0) / (y1 - y0) * bins), 0, bins - 1);
        arm[v] = q.x() > hi[b] || q.x() < lo[b];
      }
    }
  }
  return arm;
}

}  // namespace weft::capture
