#include "capture/character/embedded_graph.h"

#include <algorithm>
#include <limits>
#include <numeric>
#include <set>

#include "graph/error.h"

namespace weft::capture {

namespace {

void set_edges(EmbeddedGraph& g, std::set<std::pair<int, int>> pairs) {
  g.edges.resize(pairs.size(), 2);
  g.neighbours.assign(g.num_nodes(), {});
  int e = 0;
  for (const auto& [a, b] : pairs) {
    g.edges.row(e++) << a, b;
    g.neighbours[a].push_back(b);
    g.neighbours[b].push_back(a);
  }
  for (auto& n : g.neighbours) std::sort(n.begin(), n.end());
}

// Indices of the `k` nodes nearest to p, ties by index.
std::vector<int> nearest_nodes(const Vertices& nodes, const Eigen::Vector3d& p, int k, int exclude) {
  std::vector<std::pair<double, int>> d;
  d.reserve(nodes.rows());
  for (Eigen::Index i = 0; i < nodes.rows(); ++i)
    if (i != exclude) d.emplace_back((nodes.row(i).transpose() - p).squaredNorm(), static_cast<int>(i));
  const int m = std::min<int>(k, d.size());
  std::partial_sort(d.begin(), d.begin() + m, d.end());
  std::vector<int> out(m);
  for (int i = 0; i < m; ++i) out[i] = d[i].second;
  return out;
}

}  // namespace

void compute_vertex_weights(EmbeddedGraph& g, const Vertices& V, int k) {
  const int K = g.num_nodes();
  if (K == 0) fail("embedded graph: no nodes");
  if (k < 1) fail("embedded graph: nodes_per_vertex must be at least 1");
  k = std::min(k, K);
  g.vertex_nodes.setZero(V.rows(), k);
  g.vertex_weights.setZero(V.rows(), k);
  g.vertex_region.resize(V.rows());
#pragma omp parallel for schedule(static)
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    const Eigen::Vector3d p = V.row(v).transpose();
    int nearest = 0;
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i < K; ++i) {
      const double d = (g.nodes.row(i).transpose() - p).squaredNorm();
      if (d < best) {
        best = d;
        nearest = i;
      }
    }
    g.vertex_region(v) = nearest;
    // Candidates: the nearest node and two rings of its graph neighbours.
    std::vector<int> cand{nearest};
    for (int a : g.neighbours[nearest]) {
      cand.push_back(a);
      for (int b : g.neighbours[a]) cand.push_back(b);
    }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    if (static_cast<int>(cand.size()) < k + 1) cand = nearest_nodes(g.nodes, p, k + 1, -1);
    std::vector<std::pair<double, int>> d;
    for (int c : cand) d.emplace_back((g.nodes.row(c).transpose() - p).norm(), c);
    std::sort(d.begin(), d.end());
    const int used = std::min<int>(k, d.size());
    const double d_max = (static_cast<int>(d.size()) > used ? d[used].first : d.back().first * 1.5) * (1 + 1e-9) + 1e-12;
    double sum = 0;
    for (int i = 0; i < used; ++i) {
      const double x = 1.0 - d[i].first / d_max;
      g.vertex_nodes(v, i) = d[i].second;
      g.vertex_weights(v, i) = x * x;
      sum += x * x;
    }
    g.vertex_weights.row(v) /= sum;
  }
}

EmbeddedGraph sample_embedded_graph(const TriangleMesh& mesh, const EmbeddedGraphOptions& o) {
  const int n = mesh.num_vertices();
  if (n == 0) fail("embedded graph: the mesh has no vertices");
  if (o.num_nodes < 1) fail("embedded graph: num_nodes must be at least 1, got ", o.num_nodes);
  const int K = std::min(o.num_nodes, n);
  // Farthest-point sampling from vertex 0.
  std::vector<int> picked;
  picked.reserve(K);
  Eigen::VectorXd dist = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::infinity());
  int next = 0;
  for (int s = 0; s < K; ++s) {
    picked.push_back(next);
    const Eigen::Vector3d c = mesh.V.row(next).transpose();
    int far = 0;
    double far_d = -1;
    for (int v = 0; v < n; ++v) {
      dist(v) = std::min(dist(v), (mesh.V.row(v).transpose() - c).squaredNorm());
      if (dist(v) > far_d) {
        far_d = dist(v);
        far = v;
      }
    }
    next = far;
  }
  EmbeddedGraph g;
  g.nodes.resize(K, 3);
  for (int i = 0; i < K; ++i) g.nodes.row(i) = mesh.V.row(picked[i]);
  // Regions by nearest node, then neighbours across mesh edges.
  g.neighbours.assign(K, {});
  compute_vertex_weights(g, mesh.V, 1);  // regions only (no edges yet: falls back to nearest)
  std::set<std::pair<int, int>> pairs;
  const Edges E = unique_edges(mesh.F);
  for (Eigen::Index e = 0; e < E.rows(); ++e) {
    const int a = g.vertex_region(E(e, 0)), b = g.vertex_region(E(e, 1));
    if (a != b) pairs.emplace(std::min(a, b), std::max(a, b));
  }
  std::vector<int> degree(K, 0);
  for (const auto& [a, b] : pairs) ++degree[a], ++degree[b];
  for (int i = 0; i < K; ++i)
    if (degree[i] < o.min_neighbours)
      for (int j : nearest_nodes(g.nodes, g.nodes.row(i).transpose(), o.min_neighbours, i))
        pairs.emplace(std::min(i, j), std::max(i, j));
  set_edges(g, std::move(pairs));
  compute_vertex_weights(g, mesh.V, o.nodes_per_vertex);
  g.rigidity = Eigen::VectorXd::Ones(K);
  return g;
}

EmbeddedGraph embedded_graph_from_mesh(const TriangleMesh& graph_mesh, const TriangleMesh& mesh,
                                       const EmbeddedGraphOptions& o) {
  if (graph_mesh.num_vertices() == 0) fail("embedded graph: the graph mesh has no vertices");
  EmbeddedGraph g;
  g.nodes = graph_mesh.V;
  std::set<std::pair<int, int>> pairs;
  const Edges E = unique_edges(graph_mesh.F);
  for (Eigen::Index e = 0; e < E.rows(); ++e) pairs.emplace(E(e, 0), E(e, 1));
  set_edges(g, std::move(pairs));
  compute_vertex_weights(g, mesh.V, o.nodes_per_vertex);
  g.rigidity = Eigen::VectorXd::Ones(g.num_nodes());
  return g;
}

Eigen::VectorXd node_rigidity(const EmbeddedGraph& g, const Vertices& V, const std::vector<int>& labels,
                              const std::map<int, double>& label_rigidity, double default_rigidity) {
  if (static_cast<Eigen::Index>(labels.size()) != V.rows())
    fail("node rigidity: ", labels.size(), " labels for ", V.rows(), " vertices");
  if (g.vertex_region.size() != V.rows())
    fail("node rigidity: the graph's vertex regions were computed for ", g.vertex_region.size(), " vertices, not ", V.rows());
  auto value = [&](int v) {
    const auto it = label_rigidity.find(labels[v]);
    return it == label_rigidity.end() ? default_rigidity : it->second;
  };
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(g.num_nodes());
  Eigen::VectorXi count = Eigen::VectorXi::Zero(g.num_nodes());
  for (Eigen::Index v = 0; v < V.rows(); ++v) {
    sum(g.vertex_region(v)) += value(v);
    ++count(g.vertex_region(v));
  }
  Eigen::VectorXd r(g.num_nodes());
  for (int k = 0; k < g.num_nodes(); ++k) {
    if (count(k) > 0) {
      r(k) = sum(k) / count(k);
    } else {
      Eigen::Index nearest = 0;
      (V.rowwise() - g.nodes.row(k)).rowwise().squaredNorm().minCoeff(&nearest);
      r(k) = value(static_cast<int>(nearest));
    }
  }
  return r;
}

}  // namespace weft::capture
