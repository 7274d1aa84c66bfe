#include "capture/character/automatic_weights.h"

#include <algorithm>
#include <cmath>

#include "geometry/closest_point.h"
#include "graph/error.h"

namespace weft::capture {

namespace {
// Sorts by decreasing weight (ties: lower joint first), keeps the first k, renormalises.
void keep_top(std::vector<SkinInfluence>& infl, int k) {
  std::sort(infl.begin(), infl.end(), [](const SkinInfluence& a, const SkinInfluence& b) {
    return a.weight != b.weight ? a.weight > b.weight : a.joint < b.joint;
  });
  if (static_cast<int>(infl.size()) > k) infl.resize(k);
  double sum = 0;
  for (const auto& i : infl) sum += i.weight;
  for (auto& i : infl) i.weight /= sum;
}
}  // namespace

SkinningWeights transfer_weights_from_closest_point(const TriangleMesh& body,
                                                    const SkinningWeights& bw,
                                                    const TriangleMesh& target, int max_influences) {
  if (bw.num_vertices() != body.num_vertices())
    fail("weight transfer: body has ", body.num_vertices(), " vertices but weights for ", bw.num_vertices());
  if (max_influences < 1) fail("weight transfer: max_influences must be at least 1");
  const ClosestTriangleQuery query(body.V, body.F);
  SkinningWeights out;
  out.num_joints = bw.num_joints;
  out.vertices.resize(target.num_vertices());
#pragma omp parallel for schedule(dynamic, 64)
  for (int v = 0; v < target.num_vertices(); ++v) {
    const ClosestPoint cp = query.closest(target.V.row(v).transpose());
    std::vector<SkinInfluence> infl;
    for (int k = 0; k < 3; ++k) {
      const double b = cp.barycentric(k);
      if (b <= 0) continue;
      for (const SkinInfluence& s : bw.vertices[body.F(cp.face, k)]) {
        auto it = std::find_if(infl.begin(), infl.end(), [&](const SkinInfluence& x) { return x.joint == s.joint; });
        if (it == infl.end()) infl.push_back({s.joint, b * s.weight});
        else it->weight += b * s.weight;
      }
    }
    keep_top(infl, max_influences);
    out.vertices[v] = std::move(infl);
  }
  return out;
}

namespace {
double point_segment_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (a + t * ab - p).norm();
}
}  // namespace

SkinningWeights bone_distance_weights(const Vertices& V, const Skeleton& s, const Transforms& bind,
                                      const BoneDistanceOptions& o) {
  if (static_cast<int>(bind.size()) != s.num_joints())
    fail("bone-distance weights: ", bind.size(), " transforms for ", s.num_joints(), " joints");
  if (o.max_influences < 1 || !(o.falloff > 0) || !(o.epsilon > 0))
    fail("bone-distance weights: need max_influences ≥ 1, falloff > 0, epsilon > 0");
  // Segments parent→joint, driven by the parent.
  struct Segment { Eigen::Vector3d a, b; int joint; };
  std::vector<Segment> segments;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (int j = 0; j < s.num_joints(); ++j) {
    const Eigen::Vector3d pj = bind[j].translation();
    lo = lo.cwiseMin(pj);
    hi = hi.cwiseMax(pj);
    const int parent = s.joints[j].parent;
    if (parent < 0) continue;
    const Eigen::Vector3d pp = bind[parent].translation();
    if ((pj - pp).norm() > 1e-9) segments.push_back({pp, pj, parent});
  }
  if (segments.empty()) fail("bone-distance weights: the skeleton has no bone of non-zero length");
  const double eps = o.epsilon * std::max((hi - lo).norm(), 1e-12);
  SkinningWeights out;
  out.num_joints = s.num_joints();
  out.vertices.resize(V.rows());
#pragma omp parallel for schedule(static)
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d p = V.row(v).transpose();
    // Nearest segment per joint (a joint may drive several, e.g. the pelvis both hips).
    std::vector<std::pair<int, double>> best;
    for (const Segment& seg : segments) {
      const double d = point_segment_distance(p, seg.a, seg.b);
      auto it = std::find_if(best.begin(), best.end(), [&](const auto& x) { return x.first == seg.joint; });
      if (it == best.end()) best.emplace_back(seg.joint, d);
      else it->second = std::min(it->second, d);
    }
    std::vector<SkinInfluence> infl;
    infl.reserve(best.size());
    for (const auto& [joint, d] : best) infl.push_back({joint, std::pow(d + eps, -o.falloff)});
    keep_top(infl, o.max_influences);
    out.vertices[v] = std::move(infl);
  }
  return out;
}

}  // namespace weft::capture
