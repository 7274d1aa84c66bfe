#include "capture/deformation/losses.h"

#include <Eigen/Geometry>

#include <cmath>
#include <limits>

#include "ops/ops.h"

namespace weft::capture {

ops::PinholeCamera pinhole(const Camera& c) {
  ops::PinholeCamera p;
  p.fx = c.K(0, 0), p.fy = c.K(1, 1), p.cx = c.K(0, 2), p.cy = c.K(1, 2);
  p.k1 = c.dist[0], p.k2 = c.dist[1], p.p1 = c.dist[2], p.p2 = c.dist[3], p.k3 = c.dist[4];
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) p.R[3 * r + k] = c.R(r, k);
    p.t[r] = c.t[r];
  }
  return p;
}

Tensor landmark_loss(const Tensor& projected, const Tensor& detections, const Tensor& confidence) {
  if (projected.shape() != detections.shape() || projected.dim() != 3 || projected.size(2) != 2)
    fail("landmark_loss: projected ", shape_str(projected.shape()), " and detections ",
         shape_str(detections.shape()), " must both be [B, M, 2]");
  if (confidence.shape() != Shape{projected.size(0), projected.size(1)})
    fail("landmark_loss: confidence must be [B, M] = ", shape_str({projected.size(0), projected.size(1)}),
         ", got ", shape_str(confidence.shape()));
  const Tensor d = ops::sub(projected, detections);
  const Tensor sq = ops::sum(ops::mul(d, d), {2});  // [B,M]
  return ops::scale(ops::sum(ops::mul(sq, confidence)), 1.0 / static_cast<double>(projected.size(0)));
}

Tensor keypoint_3d_loss(const Tensor& points, const Tensor& targets, const Tensor& weights) {
  if (points.shape() != targets.shape() || points.dim() != 3 || points.size(2) != 3)
    fail("keypoint_3d_loss: points ", shape_str(points.shape()), " and targets ", shape_str(targets.shape()),
         " must both be [B, M, 3]");
  if (weights.shape() != Shape{points.size(0), points.size(1)})
    fail("keypoint_3d_loss: weights must be [B, M] = ", shape_str({points.size(0), points.size(1)}), ", got ",
         shape_str(weights.shape()));
  const Tensor d = ops::sub(points, targets);
  const Tensor sq = ops::sum(ops::mul(d, d), {2});  // [B,M]
  return ops::scale(ops::sum(ops::mul(sq, weights)), 1.0 / static_cast<double>(points.size(0)));
}

Tensor lumbopelvic_loss(const Tensor& rotations, const Tensor& targets) {
  if (rotations.dim() != 3 || rotations.size(1) != 3 || rotations.size(2) != 3)
    fail("lumbopelvic_loss: rotations must be [B, 3, 3], got ", shape_str(rotations.shape()));
  if (targets.shape() != Shape{rotations.size(0), 3})
    fail("lumbopelvic_loss: targets must be [B, 3] = ", shape_str({rotations.size(0), 3}), ", got ",
         shape_str(targets.shape()));
  const Tensor up = ops::reshape(ops::slice(rotations, 2, 1, 2), {rotations.size(0), 3});  // R ŷ
  const Tensor d = ops::sub(up, targets);
  return ops::scale(ops::sum(ops::mul(d, d)), 1.0 / static_cast<double>(rotations.size(0)));
}

Eigen::Vector3d lumbopelvic_target(const Eigen::Vector3d& trunk, const Eigen::Vector3d& rest_trunk,
                                   double lumbar_share) {
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  if (!(trunk.norm() > 0) || !(rest_trunk.norm() > 0) || !trunk.allFinite() || !rest_trunk.allFinite()) return y;
  const Eigen::Vector3d a = rest_trunk.normalized(), b = trunk.normalized();
  const Eigen::Vector3d axis = a.cross(b);
  const double angle = std::atan2(axis.norm(), a.dot(b));
  if (axis.norm() < 1e-12) return y;  // no turn, or half a turn: no unique axis
  return Eigen::AngleAxisd((1 - lumbar_share) * angle, axis.normalized()) * y;
}

std::vector<int> boundary_vertices(const Camera& camera, const Vertices& V, const Faces& F,
                                   double max_cos) {
  const Vertices N = vertex_normals(V, F);
  const Eigen::Vector3d centre = camera.center();
  // Point z-buffer at a quarter of the image resolution: the smallest depth per cell.
  const int cell = 4;
  const int W = std::max(1, camera.width / cell + 1), H = std::max(1, camera.height / cell + 1);
  std::vector<double> zbuf(static_cast<size_t>(W) * H, std::numeric_limits<double>::infinity());
  std::vector<Eigen::Vector2i> cells(V.rows(), Eigen::Vector2i(-1, -1));
  std::vector<double> depth(V.rows());
  double extent = (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  for (int v = 0; v < V.rows(); ++v) {
    depth[v] = camera.depth(V.row(v).transpose());
    if (depth[v] <= 0) continue;
    const Eigen::Vector2d px = camera.project(V.row(v).transpose());
    const int cx = static_cast<int>(std::floor(px.x() / cell)), cy = static_cast<int>(std::floor(px.y() / cell));
    if (cx < 0 || cy < 0 || cx >= W || cy >= H) continue;
    cells[v] = {cx, cy};
    double& z = zbuf[static_cast<size_t>(cy) * W + cx];
    z = std::min(z, depth[v]);
  }
  const double tolerance = 0.03 * extent;  // surface thickness seen as one layer
  std::vector<int> out;
  for (int v = 0; v < V.rows(); ++v) {
    if (cells[v].x() < 0) continue;
    const Eigen::Vector3d ray = (V.row(v).transpose() - centre).normalized();
    if (std::abs(ray.dot(N.row(v).transpose())) > max_cos) continue;
    double nearest = std::numeric_limits<double>::infinity();
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = cells[v].x() + dx, y = cells[v].y() + dy;
        if (x >= 0 && y >= 0 && x < W && y < H) nearest = std::min(nearest, zbuf[static_cast<size_t>(y) * W + x]);
      }
    if (depth[v] <= nearest + tolerance) out.push_back(v);
  }
  return out;
}

std::vector<double> silhouette_weights(const Camera& camera, const Vertices& V,
                                       const Vertices& normals, const std::vector<int>& boundary,
                                       const cv::Mat& dt) {
  if (dt.type() != CV_32F || dt.cols != camera.width || dt.rows != camera.height)
    fail("silhouette_weights: distance transform must be CV_32F ", camera.width, "x",
         camera.height, " for camera ", camera.name);
  std::vector<double> rho;
  // A short step along the normal, projected, gives its image direction.
  const double step = 1e-3 * (V.colwise().maxCoeff() - V.colwise().minCoeff()).norm();
  for (int v : boundary) {
    const Eigen::Vector3d p = V.row(v).transpose();
    const Eigen::Vector2d a = camera.project(p);
    const Eigen::Vector2d n2 = camera.project(p + step * normals.row(v).transpose()) - a;
    const int x = static_cast<int>(std::lround(a.x())), y = static_cast<int>(std::lround(a.y()));
    if (x < 1 || y < 1 || x >= dt.cols - 1 || y >= dt.rows - 1) {
      rho.push_back(0);
      continue;
    }
    const double gx = 0.5 * (dt.at<float>(y, x + 1) - dt.at<float>(y, x - 1));
    const double gy = 0.5 * (dt.at<float>(y + 1, x) - dt.at<float>(y - 1, x));
    rho.push_back(n2.x() * gx + n2.y() * gy >= 0 ? 1.0 : 0.0);
  }
  return rho;
}

Tensor silhouette_loss(const Tensor& projected, const Tensor& distance_transforms, const Tensor& rho) {
  const Tensor d = ops::image_sample_bilinear(distance_transforms, projected);  // [B,N]
  if (rho.shape() != d.shape())
    fail("silhouette_loss: rho must be ", shape_str(d.shape()), ", got ", shape_str(rho.shape()));
  return ops::sum(ops::mul(rho, ops::mul(d, d)));
}

Tensor select_vertices(const Tensor& vertices, const Tensor& index) {
  if (vertices.dim() != 3 || vertices.size(2) != 3 || index.dim() != 2 ||
      index.size(0) != vertices.size(0) || index.dtype() != DType::I64)
    fail("select_vertices: expected vertices [B,V,3] and int64 index [B,N], got ",
         describe(vertices), " and ", describe(index));
  const int64_t B = index.size(0), N = index.size(1);
  std::vector<int64_t> idx3(static_cast<size_t>(B * N * 3));
  const int64_t* p = index.data<int64_t>();
  for (int64_t i = 0; i < B * N; ++i)
    for (int a = 0; a < 3; ++a) idx3[3 * i + a] = p[i];
  return ops::gather(vertices, 1, Tensor::from_indices({B, N, 3}, idx3));
}

ArapTerms arap_terms(const EmbeddedGraph& graph, DType dtype) {
  ArapTerms t;
  const int64_t K = graph.num_nodes(), E = graph.edges.rows();
  std::vector<double> nodes(graph.nodes.data(), graph.nodes.data() + graph.nodes.size());
  t.nodes = Tensor::from_data({K, 3}, nodes, dtype);
  std::vector<int64_t> edges;
  std::vector<double> weights;
  for (int64_t e = 0; e < E; ++e) {
    const int j = graph.edges(e, 0), k = graph.edges(e, 1);
    edges.push_back(j);
    edges.push_back(k);
    const bool has_rigidity = graph.rigidity.size() == K;
    weights.push_back(has_rigidity ? 0.5 * (graph.rigidity[j] + graph.rigidity[k]) : 1.0);
  }
  t.edges = Tensor::from_indices({E, 2}, edges);
  t.edge_weights = Tensor::from_data({E}, weights, dtype);
  return t;
}

Tensor arap_loss(const ArapTerms& terms, const Tensor& rotations, const Tensor& translations) {
  return ops::scale(ops::arap_energy(terms.nodes, rotations, translations, terms.edges, terms.edge_weights),
                    1.0 / static_cast<double>(rotations.size(0)));
}

AttachmentTerms attachment_terms(const Attachment& a, DType dtype) {
  AttachmentTerms t;
  const int64_t A = a.size();
  std::vector<int64_t> anchors(a.anchors.data(), a.anchors.data() + A), tri;
  std::vector<double> bary;
  for (int64_t i = 0; i < A; ++i)
    for (int k = 0; k < 3; ++k) {
      tri.push_back(a.body_vertices(i, k));
      bary.push_back(a.barycentric(i, k));
    }
  t.anchors = Tensor::from_indices({A}, anchors);
  t.body_vertices = Tensor::from_indices({3 * A}, tri);
  t.barycentric = Tensor::from_data({A, 3, 1}, bary, dtype);
  return t;
}

Tensor attachment_loss(const AttachmentTerms& t, const Tensor& cloth, const Tensor& body) {
  const int64_t B = cloth.size(0), A = t.anchors.size(0);
  const Tensor anchored = ops::index_select(cloth, 1, t.anchors);                     // [B,A,3]
  const Tensor corners = ops::reshape(ops::index_select(body, 1, t.body_vertices), {B, A, 3, 3});
  const Tensor target = ops::sum(ops::mul(corners, t.barycentric), {2});             // [B,A,3]
  const Tensor d = ops::sub(anchored, target);
  return ops::scale(ops::sum(ops::mul(d, d)), 1.0 / static_cast<double>(B));
}

}  // namespace weft::capture
