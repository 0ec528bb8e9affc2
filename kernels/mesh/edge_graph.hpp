#pragma once
//! A surface's edge graph with edge lengths (CSR by vertex index) and shortest paths along it: the
//! geodesic distance of the deformation graph's node sampling and skinning (§4.2), and of the
//! intrinsic matches of the large-motion alignment. Dijkstra over edges overestimates the surface's
//! geodesic distance by a few percent on any triangulation; both uses compare such distances only
//! with each other.
#include <array>
#include <functional>
#include <queue>
#include <span>
#include <utility>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct EdgeGraph {
  std::vector<Index> offset;   //!< n + 1 entries: the neighbours of v are target[offset[v] .. offset[v + 1])
  std::vector<Index> target;
  std::vector<double> length;  //!< of each entry of target
  std::size_t n_vertices() const { return offset.empty() ? 0 : offset.size() - 1; }
  bool isolated(Index v) const { return offset[v] == offset[v + 1]; }
};

//! The live edges of `mesh` at its current positions, by vertex handle index, in edge order.
EdgeGraph edge_graph(const SurfaceMesh& mesh);
//! The edges of a triangle set (each once, however many triangles share it), neighbours ascending.
//! \throw InvalidInput on an index out of range.
EdgeGraph edge_graph(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles);

using DistanceItem = std::pair<double, Index>;
using DistanceQueue = std::priority_queue<DistanceItem, std::vector<DistanceItem>, std::greater<>>;

//! Multi-source Dijkstra: lower the distance field `dist` (infinity where unreached) from the vertices
//! queued, settling no vertex beyond `limit` (inclusive). `dist` persists across calls, so repeated
//! calls grow one field from more and more sources.
void grow_distances(const EdgeGraph& graph, double limit, std::vector<double>& dist, DistanceQueue& queue);

//! Distances from each of `sources` to every vertex: [s][v], infinity where unreached, in single
//! precision (what the intrinsic matches need, 32 fields per surface; the deformation graph keeps
//! grow_distances'). In parallel over the sources, on a copy of the graph laid out for the walk (built
//! once per call: pass all sources at once); each field is exactly a Dijkstra's over the graph in float
//! arithmetic, whatever the thread count. \throw InvalidInput on a source out of range.
std::vector<std::vector<float>> geodesic_distances(const EdgeGraph& graph, std::span<const Index> sources);

//! The vertices in breadth-first order over a graph given as CSR (the neighbours of v are
//! target[offset[v]] .. target[offset[v + 1] - 1]): from each vertex not yet reached, in index order, every vertex
//! it reaches, level by level. new number -> vertex. Adjacent vertices get near numbers, which is what the walks
//! over a mesh's rows want from it (a mesh's own numbering can put an edge's ends tens of thousands apart).
std::vector<Index> breadth_first_order(std::span<const Index> offset, std::span<const Index> target);

//! Geodesic Poisson-disk sampling: visit vertices in index order and make each non-isolated vertex
//! farther than `spacing` from every sample so far a sample (coverage: distances strictly below
//! `spacing`). Deterministic.
std::vector<Index> poisson_disk_samples(const EdgeGraph& graph, double spacing);

}  // namespace topotrack
