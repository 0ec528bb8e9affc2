#pragma once
// MeshData samples built in code for the io tests (io/ knows nothing of SurfaceMesh).
#include <cmath>
#include <numbers>

#include "io/mesh_data.hpp"

namespace topotrack::test {

//! The octahedron, closed and consistently oriented.
inline MeshData octahedron() {
  MeshData m;
  m.positions = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.triangles = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  return m;
}

//! The octahedron with ids and every kind of attribute the PLY conventions name.
inline MeshData attributed_octahedron() {
  MeshData m = octahedron();
  m.positions[0] = {0.1, 1.0 / 3.0, -2.5e-7};
  m.ids = std::vector<std::int64_t>{10, 11, 12, 40, 7, 3};
  const std::size_t V = m.vertex_count();
  VertexAttribute color{"color", 3, {}}, rgba{"paint", 1, {}}, v{"v", 3, {}}, n{"normal", 3, {}},
      s{"curvature", 1, {}}, uv{"uv", 2, {}};
  for (std::size_t i = 0; i < V; ++i) {
    for (int c = 0; c < 3; ++c) {
      color.values.push_back(static_cast<float>((i * 3 + c) % 7) / 6.0f);
      v.values.push_back(0.25f * static_cast<float>(i) - static_cast<float>(c));
      n.values.push_back(c == static_cast<int>(i % 3) ? 1.0f : 0.0f);
    }
    rgba.values.push_back(static_cast<float>(i));
    s.values.push_back(-1.5f * static_cast<float>(i) + 0.1f);
    uv.values.push_back(0.5f * static_cast<float>(i));
    uv.values.push_back(1e-3f * static_cast<float>(i));
  }
  m.attributes = {color, v, n, s, uv, rgba};
  return m;
}

//! A UV sphere of about 2 * rings * segments triangles (closed: poles are single vertices).
inline MeshData uv_sphere(int rings, int segments) {
  MeshData m;
  m.positions.push_back({0, 0, 1});
  for (int r = 1; r < rings; ++r) {
    const double t = std::numbers::pi * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double p = 2 * std::numbers::pi * s / segments;
      m.positions.push_back({std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)});
    }
  }
  m.positions.push_back({0, 0, -1});
  const auto ring = [&](int r, int s) -> std::int64_t { return 1 + (r - 1) * segments + (s % segments); };
  const std::int64_t south = static_cast<std::int64_t>(m.positions.size()) - 1;
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, ring(1, s), ring(1, s + 1)});
  for (int r = 1; r + 1 < rings; ++r)
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)});
      m.triangles.push_back({ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
    }
  for (int s = 0; s < segments; ++s)
    m.triangles.push_back({south, ring(rings - 1, s + 1), ring(rings - 1, s)});
  return m;
}

}  // namespace topotrack::test
