#include "kernels/mesh/soup_stats.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace topotrack {
namespace {

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), std::size_t(0)); }
  std::size_t find(std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::size_t a, std::size_t b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[std::max(a, b)] = std::min(a, b);
  }
};

Vec3 vec(const std::array<double, 3>& p) { return {p[0], p[1], p[2]}; }

}  // namespace

SoupStats analyze_soup(const MeshData& m) {
  SoupStats s;
  const std::size_t nv = m.positions.size(), nf = m.triangles.size();
  s.vertices = nv;
  s.triangles = nf;
  std::vector<std::uint8_t> referenced(nv, 0);
  std::vector<std::uint8_t> valid(nf, 1);
  for (std::size_t f = 0; f < nf; ++f)
    for (std::int64_t i : m.triangles[f]) {
      if (i < 0 || std::size_t(i) >= nv) valid[f] = 0;
      else referenced[std::size_t(i)] = 1;
    }
  for (std::size_t v = 0; v < nv; ++v) {
    const auto& p = m.positions[v];
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) ++s.non_finite_vertices;
    else if (referenced[v]) s.bbox.extend(vec(p));
    if (!referenced[v]) ++s.unreferenced_vertices;
  }
  // Undirected edges with their direction, sorted so equal edges are adjacent.
  struct E {
    std::int64_t a, b;
    std::size_t corner;
    bool forward;
  };
  std::vector<E> edges;
  edges.reserve(3 * nf);
  std::vector<double> angles_min(nf, 180.0);
  for (std::size_t f = 0; f < nf; ++f) {
    if (!valid[f]) continue;
    const auto& t = m.triangles[f];
    const Vec3 p[3] = {vec(m.positions[t[0]]), vec(m.positions[t[1]]), vec(m.positions[t[2]])};
    const double area2 = (p[1] - p[0]).cross(p[2] - p[0]).norm();
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || !(area2 > 0)) {
      ++s.degenerate_triangles;
      angles_min[f] = 0;
    } else {
      for (int k = 0; k < 3; ++k) {
        const Vec3 a = p[(k + 1) % 3] - p[k], b = p[(k + 2) % 3] - p[k];
        angles_min[f] = std::min(angles_min[f], std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI);
      }
    }
    for (int k = 0; k < 3; ++k) {
      const std::int64_t u = t[k], w = t[(k + 1) % 3];
      if (u == w) continue;
      edges.push_back({std::min(u, w), std::max(u, w), 3 * f + std::size_t(k), u < w});
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const E& x, const E& y) { return std::tie(x.a, x.b, x.corner) < std::tie(y.a, y.b, y.corner); });
  // Corners joined across manifold edges; a vertex whose corners form several groups is non-manifold.
  UnionFind corners(3 * nf);
  auto corner_of = [&](std::size_t c, std::int64_t v) {
    const std::size_t f = c / 3;
    for (std::size_t k = 0; k < 3; ++k)
      if (m.triangles[f][k] == v) return 3 * f + k;
    return c;
  };
  std::vector<double> lengths;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    while (j < edges.size() && edges[j].a == edges[i].a && edges[j].b == edges[i].b) ++j;
    const std::size_t n = j - i;
    ++s.edges;
    lengths.push_back((vec(m.positions[edges[i].a]) - vec(m.positions[edges[i].b])).norm());
    if (n == 1) ++s.boundary_edges;
    else if (n > 2) ++s.non_manifold_edges;
    else {
      if (edges[i].forward == edges[i + 1].forward) ++s.inconsistent_edges;
      for (std::int64_t v : {edges[i].a, edges[i].b})
        corners.unite(corner_of(edges[i].corner, v), corner_of(edges[i + 1].corner, v));
    }
    i = j;
  }
  std::vector<std::size_t> root_of_vertex(nv, SIZE_MAX);
  std::vector<std::uint8_t> nm_vertex(nv, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    if (!valid[f]) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      const auto v = std::size_t(m.triangles[f][k]);
      const std::size_t r = corners.find(3 * f + k);
      if (root_of_vertex[v] == SIZE_MAX) root_of_vertex[v] = r;
      else if (root_of_vertex[v] != r) nm_vertex[v] = 1;
    }
  }
  s.non_manifold_vertices = std::size_t(std::count(nm_vertex.begin(), nm_vertex.end(), 1));
  UnionFind comps(nv);
  for (std::size_t f = 0; f < nf; ++f)
    if (valid[f]) {
      comps.unite(std::size_t(m.triangles[f][0]), std::size_t(m.triangles[f][1]));
      comps.unite(std::size_t(m.triangles[f][0]), std::size_t(m.triangles[f][2]));
    }
  std::size_t used = 0;
  for (std::size_t v = 0; v < nv; ++v)
    if (referenced[v]) {
      ++used;
      if (comps.find(v) == v) ++s.components;
    }
  s.euler = long(used) - long(s.edges) + long(nf);
  s.closed = s.boundary_edges == 0;
  s.manifold = s.non_manifold_edges == 0 && s.non_manifold_vertices == 0 && s.inconsistent_edges == 0;
  if (s.closed && s.manifold && nf > 0) s.genus = (2 * long(s.components) - s.euler) / 2;
  s.edge_length = make_stats(std::move(lengths));
  std::size_t below = 0;
  for (std::size_t f = 0; f < nf; ++f)
    if (valid[f]) {
      s.min_angle_deg = std::min(s.min_angle_deg, angles_min[f]);
      below += angles_min[f] < 10.0;
    }
  s.share_below_10deg = nf ? double(below) / double(nf) : 0.0;
  return s;
}

}  // namespace topotrack
