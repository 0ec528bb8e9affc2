#include "kernels/registration/deformation_graph.hpp"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

#include "kernels/mesh/edge_graph.hpp"

namespace topotrack {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
// Geodesic radius, in node spacings, of the search for each vertex's k + 1 nearest nodes. With
// Poisson-disk nodes at spacing r a disk of radius 2.5 r holds about 12 nodes, comfortably more than 5.
constexpr double kSearchRadiusFactor = 2.5;
// The first search radius, in node spacings (see build_deformation_graph): 0.64 of the work of the full
// radius. Measured on blobs at 100k vertices (quarter density): at 1.5 r 1.9% of the vertices have
// fewer than k + 1 = 5 nodes within it, which sends almost every node into the second search; at 1.75 r
// one vertex; at 2 r none. 2 r also holds 5 nodes along a tube thinner than the spacing.
constexpr double kFirstRadiusFactor = 2.0;

// Scratch of one bounded Dijkstra run, reset through the list of touched vertices.
struct DijkstraScratch {
  std::vector<double> dist;
  std::vector<Index> touched;
  DistanceQueue queue;
};

// Distances from `source` to every vertex within `radius`, as (vertex, distance), in settling order.
void bounded_dijkstra(const EdgeGraph& adj, Index source, double radius, DijkstraScratch& s,
                      std::vector<std::pair<Index, double>>& out) {
  out.clear();
  s.dist[source] = 0;
  s.touched.push_back(source);
  s.queue.push({0.0, source});
  while (!s.queue.empty()) {
    const auto [d, u] = s.queue.top();
    s.queue.pop();
    if (d > s.dist[u]) continue;
    out.push_back({u, d});
    for (Index i = adj.offset[u]; i < adj.offset[u + 1]; ++i) {
      const Index w = adj.target[i];
      const double nd = d + adj.length[i];
      if (nd <= radius && nd < s.dist[w]) {
        if (s.dist[w] == kInf) s.touched.push_back(w);
        s.dist[w] = nd;
        s.queue.push({nd, w});
      }
    }
  }
  for (Index v : s.touched) s.dist[v] = kInf;
  s.touched.clear();
}

// The nodes: geodesic Poisson-disk samples (a deleted vertex has no live edge, so none is a node).
std::vector<Vertex> sample_nodes(const EdgeGraph& adj, double spacing) {
  std::vector<Vertex> nodes;
  for (const Index v : poisson_disk_samples(adj, spacing)) nodes.push_back(Vertex(v));
  return nodes;
}

void check_graph_input(const SurfaceMesh& mesh, double spacing) {
  if (!(spacing > 0) || !std::isfinite(spacing))
    TT_THROW(InvalidInput, "deformation graph: node spacing must be positive, got " << spacing);
  if (mesh.n_vertices() == 0 || mesh.n_edges() == 0) TT_THROW(InvalidInput, "deformation graph: empty mesh");
}

}  // namespace

std::vector<Vertex> sample_graph_nodes(const SurfaceMesh& mesh, double spacing) {
  check_graph_input(mesh, spacing);
  return sample_nodes(edge_graph(mesh), spacing);
}

DeformationGraph build_deformation_graph(const SurfaceMesh& mesh, double spacing, int k) {
  check_graph_input(mesh, spacing);
  return build_deformation_graph(mesh, sample_graph_nodes(mesh, spacing), spacing, k);
}

DeformationGraph build_deformation_graph(const SurfaceMesh& mesh, std::vector<Vertex> nodes, double spacing, int k) {
  check_graph_input(mesh, spacing);
  if (k < 1 || k > 16) TT_THROW(InvalidInput, "deformation graph: k must be in [1, 16], got " << k);
  for (Vertex v : nodes)
    if (v.idx >= mesh.vertices_size() || mesh.is_deleted(v))
      TT_THROW(InvalidInput, "deformation graph: node " << v.idx << " is not a live vertex");

  DeformationGraph g;
  g.k = k;
  g.spacing = spacing;
  const EdgeGraph adj = edge_graph(mesh);
  const std::size_t nv = mesh.vertices_size();
  g.node_vertex = std::move(nodes);
  const std::size_t nn = g.node_vertex.size();
  g.node_position.resize(nn);
  for (std::size_t j = 0; j < nn; ++j) g.node_position[j] = mesh.position(g.node_vertex[j]);

  // Each node's geodesic neighbourhood, in parallel, into per-node arrays: first within the smaller
  // radius, which holds the k + 1 nearest nodes of almost every vertex; then, for the vertices where it
  // does not, every node within the full radius of them again with the full radius. A vertex's k + 1
  // nearest nodes and their distances are then exactly those of a search with the full radius from
  // every node (distances within a radius do not depend on it), at a fraction of the cost.
  const double radius = kSearchRadiusFactor * spacing, first_radius = kFirstRadiusFactor * spacing;
  const auto K = std::size_t(k);
  std::vector<std::vector<std::pair<Index, double>>> reach(nn);
  tbb::enumerable_thread_specific<DijkstraScratch> scratch([nv] {
    DijkstraScratch s;
    s.dist.assign(nv, kInf);
    return s;
  });
  auto search = [&](const std::vector<Index>& which, double r) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, which.size(), 8), [&](const auto& range) {
      DijkstraScratch& s = scratch.local();
      for (std::size_t i = range.begin(); i != range.end(); ++i)
        bounded_dijkstra(adj, g.node_vertex[which[i]].idx, r, s, reach[which[i]]);
    });
  };
  std::vector<Index> all(nn);
  for (std::size_t j = 0; j < nn; ++j) all[j] = Index(j);
  search(all, first_radius);
  // Candidates per vertex, counted and later placed by atomic counters (their order within a vertex
  // does not matter: they are sorted by (distance, node) below).
  std::vector<std::atomic<std::uint32_t>> counter(nv);
  auto count = [&] {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const auto& r) {
      for (std::size_t v = r.begin(); v != r.end(); ++v) counter[v].store(0, std::memory_order_relaxed);
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 16), [&](const auto& r) {
      for (std::size_t j = r.begin(); j != r.end(); ++j)
        for (const auto& [v, d] : reach[j]) counter[v].fetch_add(1, std::memory_order_relaxed);
    });
  };
  count();
  {
    std::vector<double> dist(nv, kInf);
    DistanceQueue queue;
    for (Index v = 0; v < nv; ++v)
      if (counter[v].load(std::memory_order_relaxed) <= K && adj.offset[v] != adj.offset[v + 1] &&
          !mesh.is_deleted(Vertex(v))) {
        dist[v] = 0;
        queue.push({0.0, v});
      }
    if (!queue.empty()) {
      grow_distances(adj, radius, dist, queue);
      std::vector<Index> again;
      for (std::size_t j = 0; j < nn; ++j)
        if (dist[g.node_vertex[j].idx] <= radius) again.push_back(Index(j));
      search(again, radius);
      count();
    }
  }

  // Per vertex the (distance, node) pairs (CSR).
  std::vector<std::size_t> offset(nv + 1, 0);
  for (std::size_t v = 0; v < nv; ++v) {
    offset[v + 1] = offset[v] + counter[v].load(std::memory_order_relaxed);
    counter[v].store(0, std::memory_order_relaxed);
  }
  std::vector<std::pair<double, Index>> cand(offset[nv]);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 16), [&](const auto& r) {
    for (std::size_t j = r.begin(); j != r.end(); ++j)
      for (const auto& [v, d] : reach[j])
        cand[offset[v] + counter[v].fetch_add(1, std::memory_order_relaxed)] = {d, Index(j)};
  });
  reach.clear();
  reach.shrink_to_fit();

  g.influence_node.assign(nv * K, kInvalidIndex);
  g.influence_weight.assign(nv * K, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 1024), [&](const auto& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      auto first = cand.begin() + std::ptrdiff_t(offset[v]), last = cand.begin() + std::ptrdiff_t(offset[v + 1]);
      const std::size_t m = std::size_t(last - first);
      if (m == 0) continue;
      const std::size_t keep = std::min(m, K + 1);
      std::partial_sort(first, first + std::ptrdiff_t(keep), last);
      const std::size_t used = std::min(m, K);
      // d_max: distance to the (k+1)-th node; the search radius when the neighbourhood holds fewer.
      const double dmax = m > K ? first[std::ptrdiff_t(K)].first : radius;
      double sum = 0;
      for (std::size_t s = 0; s < used; ++s) {
        const double t = dmax > 0 ? std::max(0.0, 1.0 - first[std::ptrdiff_t(s)].first / dmax) : 1.0;
        g.influence_node[v * K + s] = first[std::ptrdiff_t(s)].second;
        g.influence_weight[v * K + s] = t * t;
        sum += t * t;
      }
      for (std::size_t s = 0; s < used; ++s)
        g.influence_weight[v * K + s] = sum > 0 ? g.influence_weight[v * K + s] / sum : 1.0 / double(used);
    }
  });

  // A graph edge wherever one vertex is influenced by two nodes.
  std::vector<std::uint64_t> keys;
  keys.reserve(nv * K * (K - 1) / 2);
  for (std::size_t v = 0; v < nv; ++v)
    for (std::size_t a = 0; a < K; ++a)
      for (std::size_t b = a + 1; b < K; ++b) {
        const Index i = g.influence_node[v * K + a], j = g.influence_node[v * K + b];
        if (i == kInvalidIndex || j == kInvalidIndex) continue;
        keys.push_back((std::uint64_t(std::min(i, j)) << 32) | std::max(i, j));
      }
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  g.edges.resize(keys.size());
  for (std::size_t e = 0; e < keys.size(); ++e) g.edges[e] = {Index(keys[e] >> 32), Index(keys[e] & 0xffffffffu)};

  g.neighbor_offset.assign(nn + 1, 0);
  for (const auto& [i, j] : g.edges) {
    ++g.neighbor_offset[i + 1];
    ++g.neighbor_offset[j + 1];
  }
  for (std::size_t j = 0; j < nn; ++j) g.neighbor_offset[j + 1] += g.neighbor_offset[j];
  g.neighbors.resize(g.neighbor_offset[nn]);
  std::vector<Index> fill(g.neighbor_offset.begin(), g.neighbor_offset.end() - 1);
  for (const auto& [i, j] : g.edges) {
    g.neighbors[fill[i]++] = j;
    g.neighbors[fill[j]++] = i;
  }
  for (std::size_t j = 0; j < nn; ++j)
    std::sort(g.neighbors.begin() + g.neighbor_offset[j], g.neighbors.begin() + g.neighbor_offset[j + 1]);
  return g;
}

}  // namespace topotrack
