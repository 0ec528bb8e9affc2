#include "kernels/render/frame_geometry.hpp"

#include <algorithm>
#include <cmath>

#include "io/error.hpp"

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

RenderMesh to_render_mesh(const MeshData& data, const std::string& color_attribute) {
  FrameGeometry g = frame_geometry(data);
  RenderMesh m;
  m.positions = std::move(g.positions);
  m.triangles = std::move(g.triangles);
  if (const VertexAttribute* a = data.attribute(color_attribute)) {
    if (a->width != 3 && a->width != 4)
      TT_THROW(InvalidInput, "colour attribute '" << color_attribute << "' has width " << a->width << ", not 3 or 4");
    if (a->values.size() != std::size_t(a->width) * m.positions.size())
      TT_THROW(InvalidInput, "colour attribute '" << color_attribute << "' has " << a->values.size() << " values");
    m.colors.resize(3 * m.positions.size());
    for (std::size_t i = 0; i < m.positions.size(); ++i)
      for (int c = 0; c < 3; ++c) m.colors[3 * i + c] = a->values[i * a->width + c];
  }
  return m;
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

}  // namespace topotrack
