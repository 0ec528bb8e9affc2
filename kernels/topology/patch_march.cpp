#include "kernels/topology/patch_march.hpp"

#include <algorithm>

namespace topotrack::topology {

namespace {

void adjacency_rows(const SurfaceMesh& mesh, const std::vector<std::uint8_t>* rows, std::vector<std::uint32_t>& adj_begin,
                    std::vector<Index>& adj) {
  const std::size_t nv = mesh.vertices_size();
  adj_begin.assign(nv + 1, 0);
  adj.clear();
  if (!rows) adj.reserve(mesh.n_edges() * 2);
  std::vector<Vertex> ring;
  for (std::size_t v = 0; v < nv; ++v) {
    const Vertex vh(static_cast<Index>(v));
    if ((!rows || (*rows)[v]) && !mesh.is_deleted(vh) && !mesh.is_isolated(vh)) {
      mesh.one_ring(vh, ring);
      for (Vertex w : ring) adj.push_back(w.idx);
    }
    adj_begin[v + 1] = std::uint32_t(adj.size());
  }
}

}  // namespace

void mesh_adjacency(const SurfaceMesh& mesh, std::vector<std::uint32_t>& adj_begin, std::vector<Index>& adj) {
  adjacency_rows(mesh, nullptr, adj_begin, adj);
}

void mesh_adjacency(const SurfaceMesh& mesh, const std::vector<std::uint8_t>& rows, std::vector<std::uint32_t>& adj_begin,
                    std::vector<Index>& adj) {
  if (rows.size() != mesh.vertices_size())
    TT_THROW(InvalidInput, "mesh_adjacency: " << rows.size() << " row flags for " << mesh.vertices_size() << " vertices");
  adjacency_rows(mesh, &rows, adj_begin, adj);
}

std::vector<MarchedPatch> march_patches(const std::vector<std::uint8_t>& in_patch,
                                        const std::vector<std::uint32_t>& adj_begin, const std::vector<Index>& adj) {
  const std::size_t n = in_patch.size();
  std::vector<MarchedPatch> patches;
  std::vector<std::int32_t> label(n, -1);
  std::vector<std::uint8_t> visited(n, 0), queued(n, 0);
  std::vector<Index> stack, members, queue;
  for (std::size_t s = 0; s < n; ++s) {
    if (!in_patch[s] || label[s] >= 0) continue;
    // The connected patch of s.
    const auto id = std::int32_t(patches.size());
    MarchedPatch& P = patches.emplace_back();
    members.clear();
    stack.assign(1, Index(s));
    label[s] = id;
    while (!stack.empty()) {
      const Index v = stack.back();
      stack.pop_back();
      members.push_back(v);
      for (std::uint32_t k = adj_begin[v]; k < adj_begin[v + 1]; ++k) {
        const Index w = adj[k];
        if (in_patch[w] && label[w] < 0) {
          label[w] = id;
          stack.push_back(w);
        } else if (!in_patch[w]) {
          P.boundary.push_back(w);
        }
      }
    }
    std::sort(members.begin(), members.end());
    std::sort(P.boundary.begin(), P.boundary.end());
    P.boundary.erase(std::unique(P.boundary.begin(), P.boundary.end()), P.boundary.end());
    // Breadth-first from the boundary: the first layer are the members next to it, by index.
    queue.clear();
    for (Index v : members)
      for (std::uint32_t k = adj_begin[v]; k < adj_begin[v + 1]; ++k)
        if (!in_patch[adj[k]]) {
          queue.push_back(v);
          queued[v] = 1;
          break;
        }
    P.rule_begin.push_back(0);
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const Index v = queue[head];
      std::size_t count = 0;
      for (std::uint32_t k = adj_begin[v]; k < adj_begin[v + 1]; ++k) {
        const Index w = adj[k];
        if (!in_patch[w] || visited[w]) ++count;
      }
      for (std::uint32_t k = adj_begin[v]; k < adj_begin[v + 1]; ++k) {
        const Index w = adj[k];
        if (!in_patch[w] || visited[w]) P.terms.emplace_back(w, 1.0 / double(count));
        else if (!queued[w]) {
          queued[w] = 1;
          queue.push_back(w);
        }
      }
      visited[v] = 1;
      P.order.push_back(v);
      P.rule_begin.push_back(std::uint32_t(P.terms.size()));
    }
    P.ruled = P.order.size();
    for (Index v : members)
      if (!visited[v]) P.order.push_back(v);
  }
  return patches;
}

}  // namespace topotrack::topology
