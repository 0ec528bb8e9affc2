#include "kernels/mesh/mesh_convert.hpp"

#include <algorithm>
#include <cmath>

namespace topotrack {

SurfaceMesh to_surface_mesh(const MeshData& data) {
  const std::size_t n = data.positions.size();
  std::vector<Index> remap(n, kInvalidIndex);
  for (std::size_t f = 0; f < data.triangles.size(); ++f)
    for (std::int64_t i : data.triangles[f]) {
      if (i < 0 || std::size_t(i) >= n)
        TT_THROW(InvalidInput, "triangle " << f << ": vertex index " << i << " out of range [0, " << n << ")");
      remap[std::size_t(i)] = 0;
    }
  std::vector<Vec3> pos;
  std::vector<VertexId> ids;
  std::vector<Index> kept;
  for (std::size_t v = 0; v < n; ++v) {
    if (remap[v] == kInvalidIndex) continue;
    const auto& p = data.positions[v];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      TT_THROW(InvalidInput, "vertex " << v << " has a non-finite coordinate");
    remap[v] = Index(pos.size());
    kept.push_back(Index(v));
    pos.emplace_back(p[0], p[1], p[2]);
    if (data.ids) {
      const std::int64_t id = (*data.ids)[v];
      if (id < 0) TT_THROW(InvalidInput, "vertex " << v << " has a negative id " << id);
      ids.push_back(VertexId(id));
    }
  }
  if (!ids.empty()) {
    std::vector<VertexId> sorted = ids;
    std::sort(sorted.begin(), sorted.end());
    auto dup = std::adjacent_find(sorted.begin(), sorted.end());
    if (dup != sorted.end()) TT_THROW(InvalidInput, "vertex id " << *dup << " is used twice");
  }
  std::vector<std::array<Index, 3>> tris(data.triangles.size());
  for (std::size_t f = 0; f < tris.size(); ++f)
    for (int k = 0; k < 3; ++k) tris[f][k] = remap[std::size_t(data.triangles[f][k])];
  SurfaceMesh mesh = SurfaceMesh::from_triangles(pos, tris, ids);
  for (const VertexAttribute& a : data.attributes) {
    if (a.width < 1 || a.values.size() != std::size_t(a.width) * n)
      TT_THROW(InvalidInput, "attribute '" << a.name << "' has " << a.values.size() << " values for " << n
                                           << " vertices of width " << a.width);
    auto prop = mesh.add_vertex_property<float>(a.name, a.width);
    auto& out = prop.vector();
    for (std::size_t i = 0; i < kept.size(); ++i)
      std::copy_n(a.values.begin() + std::ptrdiff_t(kept[i]) * a.width, a.width, out.begin() + std::ptrdiff_t(i) * a.width);
  }
  return mesh;
}

void extract_triangles(const SurfaceMesh& mesh, std::vector<Vec3>& positions, std::vector<std::array<Index, 3>>& triangles,
                       std::vector<Vertex>* vertex_of_index) {
  std::vector<Index> remap(mesh.vertices_size(), kInvalidIndex);
  positions.clear();
  triangles.clear();
  if (vertex_of_index) vertex_of_index->clear();
  for (Index v = 0; v < mesh.vertices_size(); ++v) {
    if (mesh.is_deleted(Vertex(v))) continue;
    remap[v] = Index(positions.size());
    positions.push_back(mesh.position(Vertex(v)));
    if (vertex_of_index) vertex_of_index->push_back(Vertex(v));
  }
  triangles.reserve(mesh.n_faces());
  for (Index f = 0; f < mesh.faces_size(); ++f) {
    if (mesh.is_deleted(Face(f))) continue;
    const auto t = mesh.vertices(Face(f));
    triangles.push_back({remap[t[0].idx], remap[t[1].idx], remap[t[2].idx]});
  }
}

MeshData to_mesh_data(const SurfaceMesh& mesh, bool with_properties) {
  MeshData d;
  std::vector<Vec3> pos;
  std::vector<std::array<Index, 3>> tris;
  std::vector<Vertex> verts;
  extract_triangles(mesh, pos, tris, &verts);
  d.positions.resize(pos.size());
  for (std::size_t i = 0; i < pos.size(); ++i) d.positions[i] = {pos[i].x(), pos[i].y(), pos[i].z()};
  d.triangles.resize(tris.size());
  for (std::size_t f = 0; f < tris.size(); ++f) d.triangles[f] = {tris[f][0], tris[f][1], tris[f][2]};
  d.ids.emplace(verts.size());
  for (std::size_t i = 0; i < verts.size(); ++i) (*d.ids)[i] = std::int64_t(mesh.id(verts[i]));
  if (with_properties)
    for (const std::string& name : mesh.vertex_property_names()) {
      const auto prop = mesh.get_vertex_property<float>(name);
      if (!prop.is_valid()) continue;
      VertexAttribute a{name, prop.width(), {}};
      a.values.reserve(verts.size() * std::size_t(prop.width()));
      for (Vertex v : verts)
        for (float x : prop[v]) a.values.push_back(x);
      d.attributes.push_back(std::move(a));
    }
  return d;
}

std::vector<Vec3> positions_of(const MeshData& data) {
  std::vector<Vec3> positions(data.positions.size());
  for (std::size_t i = 0; i < positions.size(); ++i)
    positions[i] = Vec3(data.positions[i][0], data.positions[i][1], data.positions[i][2]);
  return positions;
}

}  // namespace topotrack
