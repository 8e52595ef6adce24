#pragma once
/// \file
/// Conversion between g2o file contents and semlio's PoseGraph.
///
/// Nodes are created in file order of the vertices. The gauge: when the file
/// has FIX lines those vertices are held fixed (and only those); otherwise the
/// first vertex in the file is (PoseGraphConfig::fix_first_node).

#include <cstddef>
#include <string>
#include <unordered_map>
#include <vector>

#include <semlio/core/error.hpp>
#include <semlio/graph/pose_graph.hpp>
#include <semlio/io/g2o.hpp>

namespace semlio::io {

namespace detail {

template <typename Graph, typename Vertices, typename Edges>
Graph build_graph(const G2oGraph& file, PoseGraphConfig config, const Vertices& vertices, const Edges& edges) {
  if (!file.fixed.empty()) config.fix_first_node = false;
  Graph graph(config);
  std::unordered_map<long, NodeId> node_of;
  node_of.reserve(vertices.size());
  for (const auto& v : vertices) node_of.emplace(v.id, graph.add_node(v.pose));
  auto node = [&](long id) {
    const auto it = node_of.find(id);
    if (it == node_of.end()) throw ValueError("g2o graph: unknown vertex id " + std::to_string(id));
    return it->second;
  };
  for (const long id : file.fixed) graph.set_fixed(node(id), true);
  for (const auto& e : edges) graph.add_between(node(e.from), node(e.to), e.measured, e.information);
  return graph;
}

}  // namespace detail

/// A 3D pose graph with one node per VERTEX_SE3:QUAT and a between factor per edge.
inline PoseGraph3d make_pose_graph3(const G2oGraph& file, const PoseGraphConfig& config = {}) {
  if (file.dimension == 2) throw ValueError("make_pose_graph3: the g2o graph is 2D");
  return detail::build_graph<PoseGraph3d>(file, config, file.vertices3, file.edges3);
}

/// A 2D pose graph with one node per VERTEX_SE2 and a between factor per edge.
inline PoseGraph2d make_pose_graph2(const G2oGraph& file, const PoseGraphConfig& config = {}) {
  if (file.dimension == 3) throw ValueError("make_pose_graph2: the g2o graph is 3D");
  return detail::build_graph<PoseGraph2d>(file, config, file.vertices2, file.edges2);
}

/// Copies the graph's estimates into the file's vertices (same order).
inline void store_poses(const PoseGraph3d& graph, G2oGraph& file) {
  if (graph.num_nodes() != file.vertices3.size())
    throw ValueError("store_poses: node count differs from the g2o vertices");
  for (std::size_t k = 0; k < file.vertices3.size(); ++k) file.vertices3[k].pose = graph.pose(static_cast<NodeId>(k));
}

/// Copies the graph's estimates into the file's vertices (same order).
inline void store_poses(const PoseGraph2d& graph, G2oGraph& file) {
  if (graph.num_nodes() != file.vertices2.size())
    throw ValueError("store_poses: node count differs from the g2o vertices");
  for (std::size_t k = 0; k < file.vertices2.size(); ++k) file.vertices2[k].pose = graph.pose(static_cast<NodeId>(k));
}

}  // namespace semlio::io
