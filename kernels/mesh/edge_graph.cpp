#include "kernels/mesh/edge_graph.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace topotrack {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}  // namespace

EdgeGraph edge_graph(const SurfaceMesh& mesh) {
  EdgeGraph a;
  const std::size_t nv = mesh.vertices_size();
  a.offset.assign(nv + 1, 0);
  for (std::size_t e = 0; e < mesh.edges_size(); ++e) {
    if (mesh.is_deleted(Edge(Index(e)))) continue;
    ++a.offset[mesh.vertex(Edge(Index(e)), 0).idx + 1];
    ++a.offset[mesh.vertex(Edge(Index(e)), 1).idx + 1];
  }
  for (std::size_t v = 0; v < nv; ++v) a.offset[v + 1] += a.offset[v];
  a.target.resize(a.offset[nv]);
  a.length.resize(a.offset[nv]);
  std::vector<Index> fill(a.offset.begin(), a.offset.end() - 1);
  for (std::size_t e = 0; e < mesh.edges_size(); ++e) {
    const Edge edge{Index(e)};
    if (mesh.is_deleted(edge)) continue;
    const Vertex u = mesh.vertex(edge, 0), w = mesh.vertex(edge, 1);
    const double len = (mesh.position(u) - mesh.position(w)).norm();
    a.target[fill[u.idx]] = w.idx;
    a.length[fill[u.idx]++] = len;
    a.target[fill[w.idx]] = u.idx;
    a.length[fill[w.idx]++] = len;
  }
  return a;
}

EdgeGraph edge_graph(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles) {
  const std::size_t nv = positions.size();
  // Both directions of every triangle edge as (from << 32 | to), sorted and deduplicated: the CSR rows.
  std::vector<std::uint64_t> keys;
  keys.reserve(6 * triangles.size());
  for (const auto& t : triangles)
    for (int c = 0; c < 3; ++c) {
      const Index u = t[c], w = t[(c + 1) % 3];
      if (u >= nv || w >= nv) TT_THROW(InvalidInput, "edge graph: vertex index out of range");
      if (u == w) continue;
      keys.push_back((std::uint64_t(u) << 32) | w);
      keys.push_back((std::uint64_t(w) << 32) | u);
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  EdgeGraph a;
  a.offset.assign(nv + 1, 0);
  a.target.resize(keys.size());
  a.length.resize(keys.size());
  for (std::size_t i = 0; i < keys.size(); ++i) {
    const Index u = Index(keys[i] >> 32), w = Index(keys[i] & 0xffffffffu);
    ++a.offset[u + 1];
    a.target[i] = w;
    a.length[i] = (positions[u] - positions[w]).norm();
  }
  for (std::size_t v = 0; v < nv; ++v) a.offset[v + 1] += a.offset[v];
  return a;
}

void grow_distances(const EdgeGraph& graph, double limit, std::vector<double>& dist, DistanceQueue& queue) {
  while (!queue.empty()) {
    const auto [d, u] = queue.top();
    queue.pop();
    if (d > dist[u]) continue;
    for (Index i = graph.offset[u]; i < graph.offset[u + 1]; ++i) {
      const Index w = graph.target[i];
      const double nd = d + graph.length[i];
      if (nd <= limit && nd < dist[w]) {
        dist[w] = nd;
        queue.push({nd, w});
      }
    }
  }
}

void geodesic_distances(const EdgeGraph& graph, Index source, std::vector<float>& dist) {
  // A non-negative float's bits order as its value: (bits << 32 | vertex) orders by distance, then vertex.
  const auto key = [](float d, Index v) { return (std::uint64_t(std::bit_cast<std::uint32_t>(d)) << 32) | v; };
  dist.assign(graph.n_vertices(), std::numeric_limits<float>::infinity());
  std::vector<std::uint64_t> heap;
  heap.reserve(2 * graph.n_vertices());
  std::priority_queue<std::uint64_t, std::vector<std::uint64_t>, std::greater<>> queue(std::greater<>{}, std::move(heap));
  dist[source] = 0;
  queue.push(key(0, source));
  while (!queue.empty()) {
    const std::uint64_t top = queue.top();
    queue.pop();
    const Index u = Index(top & 0xffffffffu);
    const float d = std::bit_cast<float>(std::uint32_t(top >> 32));
    if (d > dist[u]) continue;
    for (Index i = graph.offset[u]; i < graph.offset[u + 1]; ++i) {
      const Index w = graph.target[i];
      const float nd = d + float(graph.length[i]);
      if (nd < dist[w]) {
        dist[w] = nd;
        queue.push(key(nd, w));
      }
    }
  }
}

std::vector<Index> poisson_disk_samples(const EdgeGraph& graph, double spacing) {
  const std::size_t nv = graph.n_vertices();
  const double below_spacing = std::nextafter(spacing, 0.0);
  std::vector<double> dist(nv, kInf);
  std::vector<Index> samples;
  DistanceQueue queue;
  for (Index v = 0; v < nv; ++v) {
    if (graph.isolated(v) || dist[v] < spacing) continue;
    samples.push_back(v);
    dist[v] = 0;
    queue.push({0.0, v});
    grow_distances(graph, below_spacing, dist, queue);
  }
  return samples;
}

}  // namespace topotrack
