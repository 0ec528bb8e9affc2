#include "kernels/propagate/frame_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "io/error.hpp"
#include "io/mesh_reader.hpp"

namespace topotrack {

FrameGeometry frame_geometry(const MeshData& data) {
  FrameGeometry g;
  const std::size_t n = data.positions.size();
  if (n >= kInvalidIndex) TT_THROW(InvalidInput, "too many vertices: " << n);
  g.positions.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto& p = data.positions[i];
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
      TT_THROW(InvalidInput, "vertex " << i << " is not finite");
    g.positions[i] = Vec3(p[0], p[1], p[2]);
  }
  g.triangles.resize(data.triangles.size());
  for (std::size_t f = 0; f < data.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t v = data.triangles[f][c];
      if (v < 0 || std::uint64_t(v) >= n)
        TT_THROW(InvalidInput, "triangle " << f << " has vertex index " << v << " outside [0, " << n << ")");
      g.triangles[f][c] = Index(v);
    }
  if (data.ids) {
    if (data.ids->size() != n) TT_THROW(InvalidInput, data.ids->size() << " ids for " << n << " vertices");
    g.ids.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      if ((*data.ids)[i] < 0) TT_THROW(InvalidInput, "vertex " << i << " has negative id " << (*data.ids)[i]);
      g.ids[i] = VertexId((*data.ids)[i]);
    }
    std::vector<VertexId> sorted = g.ids;
    std::sort(sorted.begin(), sorted.end());
    const auto dup = std::adjacent_find(sorted.begin(), sorted.end());
    if (dup != sorted.end()) TT_THROW(InvalidInput, "vertex id " << *dup << " appears twice");
  }
  return g;
}

FrameFile read_frame_file(const std::filesystem::path& path, bool require_ids) {
  FrameFile l;
  l.data = read_mesh(path);
  try {
    l.geometry = frame_geometry(l.data);
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, path.string() << ": " << e.what());
  }
  if (require_ids && l.geometry.ids.empty())
    TT_THROW(InvalidInput, path.string() << ": no vertex ids (`id` property): not a tracked frame (topotrack track)");
  return l;
}

void set_attribute(MeshData& data, const std::string& name, int width, std::vector<float> values) {
  if (width < 1 || values.size() != std::size_t(width) * data.positions.size())
    TT_THROW(InvalidInput, "attribute '" << name << "': " << values.size() << " values of width " << width << " for "
                                         << data.positions.size() << " vertices");
  VertexAttribute* a = data.attribute(name);
  if (!a) {
    data.attributes.push_back({name, width, {}});
    a = &data.attributes.back();
  }
  a->width = width;
  a->values = std::move(values);
}

void set_positions(MeshData& data, std::span<const Vec3> positions) {
  if (positions.size() != data.positions.size())
    TT_THROW(InvalidInput, "set_positions: " << positions.size() << " positions for " << data.positions.size()
                                             << " vertices");
  for (std::size_t i = 0; i < positions.size(); ++i)
    data.positions[i] = {positions[i].x(), positions[i].y(), positions[i].z()};
}

std::optional<std::vector<Index>> match_connectivity(std::span<const VertexId> ids_a,
                                                     std::span<const std::array<Index, 3>> triangles_a,
                                                     std::span<const VertexId> ids_b,
                                                     std::span<const std::array<Index, 3>> triangles_b) {
  if (ids_a.empty() != ids_b.empty() || ids_a.size() != ids_b.size() || triangles_a.size() != triangles_b.size())
    return std::nullopt;
  std::vector<Index> a_to_b;
  if (ids_a.empty()) {
    // Without ids only identical index triangles (in any order) count; the vertex count is implied by them.
    Index n = 0;
    for (const auto& t : triangles_a) n = std::max({n, t[0] + 1, t[1] + 1, t[2] + 1});
    a_to_b.resize(n);
    for (Index i = 0; i < n; ++i) a_to_b[i] = i;
  } else if (std::equal(ids_a.begin(), ids_a.end(), ids_b.begin())) {
    a_to_b.resize(ids_a.size());
    for (std::size_t i = 0; i < ids_a.size(); ++i) a_to_b[i] = Index(i);
  } else {
    std::unordered_map<VertexId, Index> in_b;
    in_b.reserve(ids_b.size());
    for (std::size_t i = 0; i < ids_b.size(); ++i) in_b.emplace(ids_b[i], Index(i));
    if (in_b.size() != ids_b.size()) return std::nullopt;  // repeated ids
    a_to_b.resize(ids_a.size());
    std::vector<std::uint8_t> used(ids_b.size(), 0);
    for (std::size_t i = 0; i < ids_a.size(); ++i) {
      const auto it = in_b.find(ids_a[i]);
      if (it == in_b.end() || used[it->second]) return std::nullopt;
      used[it->second] = 1;
      a_to_b[i] = it->second;
    }
  }
  // Canonical triangles: rotated so the smallest index comes first (orientation kept), then sorted.
  auto canon = [](std::array<Index, 3> t) {
    while (t[0] > t[1] || t[0] > t[2]) t = {t[1], t[2], t[0]};
    return t;
  };
  std::vector<std::array<Index, 3>> ta, tb;
  ta.reserve(triangles_a.size());
  tb.reserve(triangles_b.size());
  for (const auto& t : triangles_a) {
    for (Index v : t)
      if (v >= a_to_b.size()) return std::nullopt;
    ta.push_back(canon({a_to_b[t[0]], a_to_b[t[1]], a_to_b[t[2]]}));
  }
  for (const auto& t : triangles_b) tb.push_back(canon(t));
  std::sort(ta.begin(), ta.end());
  std::sort(tb.begin(), tb.end());
  if (ta != tb) return std::nullopt;
  return a_to_b;
}

}  // namespace topotrack
