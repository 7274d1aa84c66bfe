#pragma once
// Embedded deformation graphs (Sumner et al. 2007) over a template mesh: K nodes at rest
// positions g_k, node neighbourhoods (the ARAP edges), per-vertex node weights with
// compact support, and per-node rigidity. The deformation itself,
//   v' = Σ_k w_vk [R_k (v − g_k) + g_k + t_k],
// is a differentiable op in ops/; this file builds its inputs.
#include <Eigen/Core>
#include <map>
#include <vector>

#include "geometry/mesh.h"

namespace weft::capture {

struct EmbeddedGraph {
  Vertices nodes;  // K×3 rest positions (character units)
  Edges edges;     // E×2 undirected node pairs (i < j), sorted: the ARAP terms
  std::vector<std::vector<int>> neighbours;  // per node, sorted (the same edges)
  // Per-vertex influences, fixed width: vertex v is driven by nodes vertex_nodes(v, i)
  // with weights vertex_weights(v, i) (each row sums to 1; unused slots: node 0, weight 0).
  Eigen::Matrix<int, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> vertex_nodes;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> vertex_weights;
  Eigen::VectorXi vertex_region;  // V: the node each vertex is closest to (its region)
  Eigen::VectorXd rigidity;       // K per-node rigidity weights (1: stiff, 0: free)

  int num_nodes() const { return static_cast<int>(nodes.rows()); }
};

struct EmbeddedGraphOptions {
  int num_nodes = 500;          // K (clamped to the vertex count)
  int nodes_per_vertex = 4;     // influences per vertex
  int min_neighbours = 4;       // nodes with fewer region neighbours get k-nearest ones
};

// Deterministic graph by farthest-point sampling of the mesh vertices, starting at
// vertex 0 (ties: lowest vertex index). Each vertex belongs to the region of its nearest
// node; two nodes are neighbours when a mesh edge joins their regions (so legs do not
// link through the air), topped up with nearest nodes to at least `min_neighbours`.
EmbeddedGraph sample_embedded_graph(const TriangleMesh& mesh, const EmbeddedGraphOptions& options = {});

// A given graph mesh (e.g. ddc_graph.obj): its vertices are the nodes and its face edges
// the neighbourhoods; vertex weights and regions are computed for `mesh`.
EmbeddedGraph embedded_graph_from_mesh(const TriangleMesh& graph_mesh, const TriangleMesh& mesh,
                                       const EmbeddedGraphOptions& options = {});

// Recomputes vertex_nodes / vertex_weights / vertex_region for `V`: each vertex takes its
// nearest node and the nearest of that node's neighbours (2 rings), k of them, with
//   w ∝ (1 − d / d_max)², d_max the distance to the (k+1)-th candidate,
// normalised. Deterministic (ties by node index).
void compute_vertex_weights(EmbeddedGraph& graph, const Vertices& V, int nodes_per_vertex);

// Per-node rigidity: the mean, over the vertices of each node's region, of
// label_rigidity[label(v)] (labels without an entry get `default_rigidity`); a node with
// an empty region takes its nearest vertex's value.
Eigen::VectorXd node_rigidity(const EmbeddedGraph& graph, const Vertices& V,
                              const std::vector<int>& vertex_labels,
                              const std::map<int, double>& label_rigidity, double default_rigidity = 1.0);

}  // namespace weft::capture
