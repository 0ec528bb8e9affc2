#pragma once
//! The deformation graph of the coarse non-rigid alignment (§4.2, after Li et al. 2009 and Sumner et
//! al. 2007): nodes sampled uniformly over the mesh by geodesic (Dijkstra over edges) Poisson-disk
//! sampling, each vertex skinned to its k geodesically nearest nodes with weights
//! w = (1 - d / d_max)^2 (d_max: distance to the (k+1)-th node), normalised; a graph edge wherever a
//! vertex is influenced by two nodes. Geodesic distances keep surfaces that are close in space but far
//! along the surface (a breaking wave's tip) apart; every connected component gets its own nodes.
#include <utility>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct DeformationGraph {
  int k = 4;                              //!< influences per vertex (fewer when a component has fewer nodes)
  double spacing = 0;                     //!< geodesic node spacing used
  std::vector<Vertex> node_vertex;        //!< mesh vertex of each node
  std::vector<Vec3> node_position;        //!< rest position g_j of each node
  //! Skinning, k slots per vertex handle (vertices_size() * k): node index and weight; unused slots
  //! have node kInvalidIndex and weight 0. Weights of a live vertex sum to 1.
  std::vector<Index> influence_node;
  std::vector<double> influence_weight;
  std::vector<std::pair<Index, Index>> edges;  //!< undirected, (i < j), sorted
  //! Graph neighbours of each node, ascending (CSR over edges).
  std::vector<Index> neighbor_offset, neighbors;

  std::size_t n_nodes() const { return node_vertex.size(); }
};

//! Build the graph with geodesic node spacing `spacing` (§4.2: 4 x the mean edge length) and k
//! influences per vertex. Deterministic for any thread count.
//! \pre no isolated live vertex.  \throw InvalidInput when spacing <= 0, k < 1 or the mesh is empty.
DeformationGraph build_deformation_graph(const SurfaceMesh& mesh, double spacing, int k = 4);

//! The graph's nodes alone, the first step of build_deformation_graph (cheap: one bounded Dijkstra
//! per node, radius `spacing`), in the order the graph numbers them.
//! \throw InvalidInput when spacing <= 0 or the mesh is empty.
std::vector<Vertex> sample_graph_nodes(const SurfaceMesh& mesh, double spacing);

//! build_deformation_graph on nodes already sampled by sample_graph_nodes(mesh, spacing).
//! \throw InvalidInput as build_deformation_graph, or on a node that is not a live vertex.
DeformationGraph build_deformation_graph(const SurfaceMesh& mesh, std::vector<Vertex> nodes, double spacing, int k = 4);

}  // namespace topotrack
