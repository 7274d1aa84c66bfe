#include "capture/character/appearance.h"


#include <cmath>
#include <numbers>

#include "files/strict_yaml.h"
#include "graph/error.h"

namespace weft::capture {

using Eigen::Vector3d;

AppearanceConfig parse_appearance(const StrictYaml& y, const YAML::Node& n, const std::string& key) {
  AppearanceConfig a;
  struct ColorKey {
    const char* name;
    Vector3d* value;
  };
  const std::vector<ColorKey> colors = {
      {"skin", &a.skin},           {"hair", &a.hair},
      {"shirt", &a.shirt},         {"print", &a.print},
      {"legs", &a.legs},           {"left_shoe", &a.left_shoe},
      {"right_shoe", &a.right_shoe}, {"garment", &a.garment},
      {"garment_trim", &a.garment_trim}};
  if (!n.IsMap()) y.fail_at(n, key, "expected a map (textured and colours as [r, g, b] in 0..1)");
  std::vector<const char*> known = {"textured"};
  for (const ColorKey& c : colors) known.push_back(c.name);
  y.check_keys(n, key + ".", known);
  if (n["textured"]) a.textured = y.get<bool>(n["textured"], key + ".textured", "true or false");
  for (const ColorKey& c : colors) {
    const YAML::Node v = n[c.name];
    if (!v) continue;
    const std::string k = key + "." + c.name;
    if (!v.IsSequence() || v.size() != 3) y.fail_at(v, k, "expected a colour [r, g, b] with each in 0..1");
    for (int i = 0; i < 3; ++i) (*c.value)(i) = y.number(v[i], k, 0, 1);
  }
  return a;
}

namespace {

const Vector3d& joint(const BodySkeletonFit& fit, const char* name) {
  const auto it = fit.joints.find(name);
  if (it == fit.joints.end()) fail("appearance: the fitted body has no joint '", name, "'");
  return it->second;
}
const Vector3d& marker(const BodySkeletonFit& fit, const char* name) {
  const auto it = fit.markers.find(name);
  if (it == fit.markers.end()) fail("appearance: the fitted body has no marker '", name, "'");
  return it->second;
}

// Where p projects on the segment a→b, as a fraction of its length (unclamped).
double along(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d d = b - a;
  return (p - a).dot(d) / std::max(d.squaredNorm(), 1e-12);
}

}  // namespace

Vertices body_colors(const TriangleMesh& body, const BodySkeletonFit& fit, const std::vector<char>& arm_vertices,
                     const AppearanceConfig& look) {
  const int n = body.num_vertices();
  WEFT_CHECK(arm_vertices.empty() || static_cast<int>(arm_vertices.size()) == n, "appearance: ",
             arm_vertices.size(), " arm flags for a body of ", n, " vertices");
  const double H = fit.height > 0 ? fit.height : 1.66;
  const double s = H / 1.66;  // lengths below are for a 1.66 m body
  const Vertices normals = vertex_normals(body.V, body.F);
  const Vector3d head = joint(fit, "head");
  const Vector3d nose = marker(fit, "nose"), l_eye = marker(fit, "l_eye"), r_eye = marker(fit, "r_eye");
  const double eye_y = 0.5 * (l_eye.y() + r_eye.y());
  const double ankle_y = std::max(joint(fit, "l_ankle").y(), joint(fit, "r_ankle").y());
  const double chest_y = 0.5 * (fit.armpit_y + fit.waist_y) + 0.03 * s;  // the print's centre height
  const double head_lo = fit.neck_y + 0.02 * H;
  Vertices C(n, 3);
  for (int v = 0; v < n; ++v) {
    const Vector3d p = body.V.row(v).transpose();
    const Vector3d nrm = normals.row(v).transpose();
    Vector3d c = look.skin;
    const bool arm = !arm_vertices.empty() && arm_vertices[size_t(v)];
    if (arm) {
      // Short sleeves: the first 45 % of the upper arm from the shoulder joint.
      const char* side = p.x() > 0 ? "l_" : "r_";
      const Vector3d& sh = joint(fit, (std::string(side) + "shoulder").c_str());
      const Vector3d& el = joint(fit, (std::string(side) + "elbow").c_str());
      if (along(p, sh, el) < 0.45) c = look.shirt;
    } else if (p.y() > head_lo) {
      // Hair: the back of the head (behind a plane a little in front of the head joint,
      // above the ears' lower edge) and the crown above the brows.
      const double back_plane_z = head.z() + 0.015 * s;
      const bool crown = p.y() > eye_y + 0.045 * s;
      const bool back = p.z() < back_plane_z && p.y() > eye_y - 0.06 * s;
      const bool nape = p.z() < head.z() - 0.03 * s && p.y() > fit.neck_y + 0.04 * s;
      if (crown || back || nape) c = look.hair;
      if ((p - l_eye).norm() < 0.014 * s || (p - r_eye).norm() < 0.014 * s) c = Vector3d(0.08, 0.06, 0.05);
      const Vector3d mouth = nose + Vector3d(0, -0.038 * s, -0.012 * s);
      if (std::abs(p.x() - mouth.x()) < 0.022 * s && std::abs(p.y() - mouth.y()) < 0.008 * s &&
          p.z() > mouth.z() - 0.02 * s && nrm.z() > 0.3)
        c = Vector3d(0.70, 0.18, 0.20);
    } else if (p.y() > fit.neck_y - 0.03 * s) {
      c = look.skin;  // the neck, above the collar
    } else if (p.y() > fit.waist_y - 0.08 * s) {
      c = look.shirt;
      // The print: on the front of the chest only (the normal faces +z).
      const double dx = p.x() - nose.x(), dy = p.y() - chest_y;
      const double r = std::hypot(dx, dy);
      if (nrm.z() > 0.35) {
        if (r < 0.075 * s) c = r < 0.03 * s ? Vector3d(0.10, 0.10, 0.12) : look.print;
        if (std::abs(dx) < 0.06 * s && dy < -0.09 * s && dy > -0.115 * s) c = look.print;
      }
    } else if (p.y() > ankle_y + 0.02 * s) {
      c = look.legs;
    } else {
      c = p.x() > 0 ? look.left_shoe : look.right_shoe;
    }
    C.row(v) = c.transpose();
  }
  return C;
}

Vertices garment_colors(const TriangleMesh& garment, double top_y, double length, const AppearanceConfig& look) {
  const int n = garment.num_vertices();
  WEFT_CHECK(length > 0, "appearance: garment length must be positive, found ", length);
  const Eigen::RowVector3d mean = garment.V.colwise().mean();
  Vertices C(n, 3);
  const double pi = std::numbers::pi;
  for (int v = 0; v < n; ++v) {
    const double x = garment.V(v, 0) - mean(0), z = garment.V(v, 2) - mean(2);
    const double angle = std::atan2(x, z);  // 0 at the front (+z), ±π at the back
    const double drop = (top_y - garment.V(v, 1)) / length;  // 0 at the top ring, 1 at the hem
    Vector3d c = look.garment;
    // Darker panels every 45° around.
    const int panel = static_cast<int>(std::floor((angle + pi) / (pi / 4)));
    if (panel % 2 == 1) c *= 0.72;
    if (drop > 0.82) c = look.garment_trim;                      // the hem band
    if (std::abs(angle) < 0.16 && drop > 0.05) c = look.garment_trim;  // the front stripe
    C.row(v) = c.transpose();
  }
  return C;
}

}  // namespace weft::capture
