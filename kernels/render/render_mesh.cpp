#include "kernels/render/render_mesh.hpp"

#include "io/error.hpp"

namespace topotrack {

RenderMesh to_render_mesh(const MeshData& data, const std::string& color_attribute) {
  RenderMesh m;
  const std::size_t n = data.positions.size();
  if (n >= kInvalidIndex) TT_THROW(InvalidInput, "too many vertices: " << n);
  m.positions.resize(n);
  for (std::size_t i = 0; i < n; ++i) m.positions[i] = Vec3(data.positions[i][0], data.positions[i][1], data.positions[i][2]);
  m.triangles.resize(data.triangles.size());
  for (std::size_t f = 0; f < data.triangles.size(); ++f)
    for (int c = 0; c < 3; ++c) {
      const std::int64_t v = data.triangles[f][c];
      if (v < 0 || std::uint64_t(v) >= n)
        TT_THROW(InvalidInput, "triangle " << f << " has vertex index " << v << " outside [0, " << n << ")");
      m.triangles[f][c] = Index(v);
    }
  if (const VertexAttribute* a = data.attribute(color_attribute)) {
    if (a->width != 3 && a->width != 4)
      TT_THROW(InvalidInput, "colour attribute '" << color_attribute << "' has width " << a->width << ", not 3 or 4");
    if (a->values.size() != std::size_t(a->width) * n)
      TT_THROW(InvalidInput, "colour attribute '" << color_attribute << "' has " << a->values.size() << " values");
    m.colors.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) m.colors[3 * i + c] = a->values[i * a->width + c];
  }
  return m;
}

}  // namespace topotrack
