// Embedded graphs, attachment and weight transfer on small generated meshes.
#include <gtest/gtest.h>

#include <cmath>

#include "capture/character/attachment.h"
#include "capture/character/automatic_weights.h"
#include "geometry/closest_point.h"
#include "capture/character/embedded_graph.h"
#include "graph/error.h"

using namespace weft;
using namespace weft::capture;

namespace {

// A UV sphere-like closed cylinder grid: rings × segments, radius r, height h.
TriangleMesh cylinder(int rings, int segments, double r, double h) {
  TriangleMesh m;
  m.V.resize(rings * segments, 3);
  for (int i = 0; i < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const double a = 2 * M_PI * j / segments;
      m.V.row(i * segments + j) << r * std::cos(a), h * i / (rings - 1), r * std::sin(a);
    }
  std::vector<Eigen::RowVector3i> f;
  for (int i = 0; i + 1 < rings; ++i)
    for (int j = 0; j < segments; ++j) {
      const int a = i * segments + j, b = i * segments + (j + 1) % segments;
      const int c = a + segments, d = b + segments;
      f.emplace_back(a, c, b);
      f.emplace_back(b, c, d);
    }
  m.F.resize(f.size(), 3);
  for (size_t k = 0; k < f.size(); ++k) m.F.row(k) = f[k];
  return m;
}

TEST(EmbeddedGraph, SamplingIsDeterministicAndWeightsAreNormalised) {
  const TriangleMesh m = cylinder(20, 24, 1.0, 4.0);
  EmbeddedGraphOptions o;
  o.num_nodes = 40;
  const EmbeddedGraph a = sample_embedded_graph(m, o);
  const EmbeddedGraph b = sample_embedded_graph(m, o);
  ASSERT_EQ(a.num_nodes(), 40);
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.edges, b.edges);
  EXPECT_EQ(a.vertex_nodes, b.vertex_nodes);
  EXPECT_EQ(a.vertex_weights, b.vertex_weights);
  EXPECT_TRUE(a.nodes.row(0).isApprox(m.V.row(0)));  // fixed start
  ASSERT_EQ(a.vertex_weights.rows(), m.num_vertices());
  ASSERT_EQ(a.vertex_weights.cols(), 4);
  for (int v = 0; v < m.num_vertices(); ++v) {
    EXPECT_NEAR(a.vertex_weights.row(v).sum(), 1.0, 1e-12);
    EXPECT_GE(a.vertex_weights.row(v).minCoeff(), 0.0);
    // Compact support: the influencing nodes are close (within a few node spacings).
    for (int k = 0; k < 4; ++k)
      if (a.vertex_weights(v, k) > 0) {
        EXPECT_LT((a.nodes.row(a.vertex_nodes(v, k)) - m.V.row(v)).norm(), 2.5);
      }
  }
  for (int k = 0; k < a.num_nodes(); ++k) EXPECT_GE(a.neighbours[k].size(), 3u) << "node " << k;
  for (Eigen::Index e = 0; e < a.edges.rows(); ++e) EXPECT_LT(a.edges(e, 0), a.edges(e, 1));
  // Nodes spread over the surface: the farthest vertex from any node is small.
  double worst = 0;
  for (int v = 0; v < m.num_vertices(); ++v)
    worst = std::max(worst, (a.nodes.rowwise() - m.V.row(v)).rowwise().norm().minCoeff());
  EXPECT_LT(worst, 1.0);
}

TEST(EmbeddedGraph, RigidityFromLabelsAndGraphFromMesh) {
  const TriangleMesh m = cylinder(10, 12, 1.0, 2.0);
  EmbeddedGraphOptions o;
  o.num_nodes = 20;
  EmbeddedGraph g = sample_embedded_graph(m, o);
  std::vector<int> labels(m.num_vertices());
  for (int v = 0; v < m.num_vertices(); ++v) labels[v] = m.V(v, 1) < 1.0 ? 0 : 18;
  const Eigen::VectorXd r = node_rigidity(g, m.V, labels, {{0, 0.1}, {18, 1.0}});
  for (int k = 0; k < g.num_nodes(); ++k) {
    EXPECT_GE(r(k), 0.1 - 1e-12);
    EXPECT_LE(r(k), 1.0 + 1e-12);
    if (g.nodes(k, 1) < 0.5) EXPECT_NEAR(r(k), 0.1, 1e-12);
    if (g.nodes(k, 1) > 1.5) EXPECT_NEAR(r(k), 1.0, 1e-12);
  }
  // A coarse cylinder as a given graph mesh: its edges are the neighbourhoods.
  const TriangleMesh coarse = cylinder(3, 6, 1.0, 2.0);
  const EmbeddedGraph h = embedded_graph_from_mesh(coarse, m);
  EXPECT_EQ(h.num_nodes(), 18);
  EXPECT_EQ(h.edges, unique_edges(coarse.F));
  for (int v = 0; v < m.num_vertices(); ++v) EXPECT_NEAR(h.vertex_weights.row(v).sum(), 1.0, 1e-12);
}

TEST(ClosestPoint, TriangleRegions) {
  const Eigen::Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  Eigen::Vector3d bary;
  EXPECT_TRUE(closest_point_on_triangle({0.2, 0.2, 3}, a, b, c, bary).isApprox(Eigen::Vector3d(0.2, 0.2, 0)));
  EXPECT_TRUE(bary.isApprox(Eigen::Vector3d(0.6, 0.2, 0.2)));
  EXPECT_TRUE(closest_point_on_triangle({-1, -1, 0}, a, b, c, bary).isApprox(a));
  EXPECT_TRUE(closest_point_on_triangle({2, 0.5, 0}, a, b, c, bary).isApprox(b));
  EXPECT_TRUE(closest_point_on_triangle({1, 1, 0}, a, b, c, bary).isApprox(Eigen::Vector3d(0.5, 0.5, 0)));
  EXPECT_TRUE(bary.isApprox(Eigen::Vector3d(0, 0.5, 0.5)));
}

TEST(Attachment, BarycentricsReproduceTheAnchor) {
  const TriangleMesh body = cylinder(12, 16, 1.0, 3.0);
  // A "skirt" slightly outside the body, whose top ring is the waistband.
  TriangleMesh cloth = cylinder(4, 20, 1.05, 1.0);
  cloth.V.col(1).array() += 1.5;
  std::vector<int> anchors;
  for (int j = 0; j < 20; ++j) anchors.push_back(3 * 20 + j);
  const Attachment att = attach_to_body(body, cloth, anchors);
  ASSERT_EQ(att.size(), 20);
  const Vertices targets = att.targets(body.V);
  for (int i = 0; i < att.size(); ++i) {
    EXPECT_NEAR(att.barycentric.row(i).sum(), 1.0, 1e-12);
    EXPECT_GE(att.barycentric.row(i).minCoeff(), -1e-12);
    // The target is the closest body point: within the offset plus the facet sag.
    const double d = (targets.row(i) - cloth.V.row(anchors[i])).norm();
    EXPECT_NEAR(d, att.rest_distance(i), 1e-12);
    EXPECT_LT(d, 0.05 + 0.03);
    // And no body vertex is closer than the closest surface point.
    EXPECT_LE(d, (body.V.rowwise() - cloth.V.row(anchors[i])).rowwise().norm().minCoeff() + 1e-12);
  }
  // An anchor exactly on the body is reproduced exactly.
  TriangleMesh on = cloth;
  on.V.row(anchors[0]) = 0.2 * body.V.row(5) + 0.3 * body.V.row(6) + 0.5 * body.V.row(5 + 16);
  const Attachment exact = attach_to_body(body, on, {anchors[0]});
  EXPECT_NEAR((exact.targets(body.V).row(0) - on.V.row(anchors[0])).norm(), 0, 1e-12);
  EXPECT_THROW(attach_to_body(body, cloth, {9999}), weft::Error);
}

TEST(AutomaticWeights, ClothTakesTheBodyWeightsNearby) {
  const TriangleMesh body = cylinder(12, 16, 1.0, 3.0);
  SkinningWeights bw;
  bw.num_joints = 2;
  for (int v = 0; v < body.num_vertices(); ++v) {
    const double t = body.V(v, 1) / 3.0;  // bottom: joint 0, top: joint 1
    bw.vertices.push_back(t <= 0 ? std::vector<SkinInfluence>{{0, 1.0}}
                          : t >= 1 ? std::vector<SkinInfluence>{{1, 1.0}}
                                   : std::vector<SkinInfluence>{{0, 1 - t}, {1, t}});
  }
  TriangleMesh cloth = cylinder(5, 20, 1.1, 3.0);
  const SkinningWeights cw = transfer_weights_from_closest_point(body, bw, cloth);
  ASSERT_EQ(cw.num_vertices(), cloth.num_vertices());
  const Eigen::MatrixXd D = cw.dense();
  for (int v = 0; v < cloth.num_vertices(); ++v) {
    const double t = cloth.V(v, 1) / 3.0;
    EXPECT_NEAR(D(v, 1), t, 1e-9);  // weights vary linearly along the body: reproduced
    EXPECT_NEAR(D.row(v).sum(), 1.0, 1e-12);
    EXPECT_GE(cw.vertices[v][0].weight, cw.vertices[v].back().weight);  // sorted
  }
}

}  // namespace
