#include "kernels/gen/fill_voids.hpp"

#include <cmath>
#include <numeric>

#include "io/error.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/winding_number.hpp"

namespace topotrack {
namespace {

std::size_t find_root(std::vector<std::size_t>& parent, std::size_t v) {
  while (parent[v] != v) v = parent[v] = parent[parent[v]];
  return v;
}

Vec3 point(const MeshData& m, std::int64_t v) {
  const auto& p = m.positions[std::size_t(v)];
  return Vec3(p[0], p[1], p[2]);
}

}  // namespace

MeshData fill_voids(const MeshData& mesh, FillVoidsReport* report) {
  const std::size_t nv = mesh.vertex_count(), nt = mesh.triangle_count();
  for (std::size_t i = 0; i < nv; ++i)
    for (double c : mesh.positions[i])
      if (!std::isfinite(c)) TT_THROW(InvalidInput, "fill_voids: vertex " << i << " is not finite");
  for (std::size_t f = 0; f < nt; ++f)
    for (std::int64_t v : mesh.triangles[f])
      if (v < 0 || std::size_t(v) >= nv)
        TT_THROW(InvalidInput, "fill_voids: triangle " << f << " has vertex index " << v << " out of range");

  // Components through shared vertices, numbered in the order of their first triangle.
  std::vector<std::size_t> parent(nv);
  std::iota(parent.begin(), parent.end(), std::size_t(0));
  for (const auto& t : mesh.triangles)
    for (int j = 1; j < 3; ++j) {
      const std::size_t a = find_root(parent, std::size_t(t[0])), b = find_root(parent, std::size_t(t[j]));
      if (a != b) parent[std::max(a, b)] = std::min(a, b);
    }
  constexpr std::size_t kNone = ~std::size_t(0);
  std::vector<std::size_t> root_component(nv, kNone), triangle_component(nt);
  std::vector<std::vector<std::size_t>> component_triangles;
  for (std::size_t f = 0; f < nt; ++f) {
    std::size_t& c = root_component[find_root(parent, std::size_t(mesh.triangles[f][0]))];
    if (c == kNone) {
      c = component_triangles.size();
      component_triangles.emplace_back();
    }
    triangle_component[f] = c;
    component_triangles[c].push_back(f);
  }
  const std::size_t K = component_triangles.size();
  std::vector<BoundingBox> box(K);
  std::vector<double> volume(K, 0.0);
  for (std::size_t c = 0; c < K; ++c) {
    const Vec3 o = point(mesh, mesh.triangles[component_triangles[c][0]][0]);
    for (std::size_t f : component_triangles[c]) {
      const auto& t = mesh.triangles[f];
      const Vec3 a = point(mesh, t[0]), b = point(mesh, t[1]), d = point(mesh, t[2]);
      box[c].extend(a), box[c].extend(b), box[c].extend(d);
      volume[c] += (a - o).dot((b - o).cross(d - o)) / 6;
    }
  }

  // A enclosed by B needs box(A) inside box(B); only such pairs get a winding number.
  std::vector<char> enclosed(K, 0);
  for (std::size_t b = 0; b < K && K > 1; ++b) {
    std::vector<std::size_t> candidates;
    for (std::size_t a = 0; a < K; ++a)
      if (a != b && !enclosed[a] && (box[a].min.array() >= box[b].min.array()).all() &&
          (box[a].max.array() <= box[b].max.array()).all())
        candidates.push_back(a);
    if (candidates.empty()) continue;
    std::vector<Index> local(nv, kInvalidIndex);
    std::vector<Vec3> positions;
    std::vector<std::array<Index, 3>> triangles;
    triangles.reserve(component_triangles[b].size());
    for (std::size_t f : component_triangles[b]) {
      std::array<Index, 3> t;
      for (int j = 0; j < 3; ++j) {
        Index& l = local[std::size_t(mesh.triangles[f][j])];
        if (l == kInvalidIndex) {
          l = Index(positions.size());
          positions.push_back(point(mesh, mesh.triangles[f][j]));
        }
        t[j] = l;
      }
      triangles.push_back(t);
    }
    const WindingNumber winding(positions, triangles);
    std::vector<Vec3> queries;
    for (std::size_t a : candidates) queries.push_back(point(mesh, mesh.triangles[component_triangles[a][0]][0]));
    const std::vector<double> w = winding.evaluate(queries);
    for (std::size_t i = 0; i < candidates.size(); ++i)
      if (std::abs(w[i]) > 0.5) enclosed[candidates[i]] = 1;
  }

  FillVoidsReport r;
  r.components = K;
  for (std::size_t c = 0; c < K; ++c)
    if (enclosed[c]) ++(volume[c] < 0 ? r.voids_filled : r.islands_removed);
  // Vertices of removed components go; unreferenced vertices stay (they belong to no component).
  std::vector<char> drop_vertex(nv, 0);
  for (std::size_t f = 0; f < nt; ++f)
    if (enclosed[triangle_component[f]])
      for (std::int64_t v : mesh.triangles[f]) drop_vertex[std::size_t(v)] = 1;
  std::vector<std::int64_t> new_index(nv, -1);
  MeshData out;
  for (std::size_t i = 0; i < nv; ++i)
    if (!drop_vertex[i]) {
      new_index[i] = std::int64_t(out.positions.size());
      out.positions.push_back(mesh.positions[i]);
    }
  for (std::size_t f = 0; f < nt; ++f)
    if (!enclosed[triangle_component[f]]) {
      const auto& t = mesh.triangles[f];
      out.triangles.push_back({new_index[std::size_t(t[0])], new_index[std::size_t(t[1])], new_index[std::size_t(t[2])]});
    }
  if (mesh.ids) {
    out.ids.emplace();
    for (std::size_t i = 0; i < nv && i < mesh.ids->size(); ++i)
      if (!drop_vertex[i]) out.ids->push_back((*mesh.ids)[i]);
  }
  for (const auto& attr : mesh.attributes) {
    VertexAttribute kept{attr.name, attr.width, {}};
    const std::size_t w = std::size_t(std::max(attr.width, 0));
    for (std::size_t i = 0; i < nv && (i + 1) * w <= attr.values.size(); ++i)
      if (!drop_vertex[i]) kept.values.insert(kept.values.end(), attr.values.begin() + long(i * w), attr.values.begin() + long((i + 1) * w));
    out.attributes.push_back(std::move(kept));
  }
  r.vertices_removed = nv - out.positions.size();
  r.triangles_removed = nt - out.triangles.size();
  if (report) *report = r;
  return out;
}

}  // namespace topotrack
