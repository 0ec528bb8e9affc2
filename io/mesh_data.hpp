#pragma once
//! Flat arrays of a triangle mesh as read from or written to disk: what io/ deals in.
//! io/ knows nothing of half-edges; kernels/mesh converts to and from SurfaceMesh.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace topotrack {

//! A named per-vertex attribute: `width` floats per vertex, row-major (vertex-major).
//! Colours are stored as floats in [0,1] under the name "color" (width 3 or 4); velocities as "v" (width 3).
struct VertexAttribute {
  std::string name;
  int width = 1;
  std::vector<float> values;  //!< size = width * vertex count
};

//! A triangle mesh as flat arrays.
struct MeshData {
  std::vector<std::array<double, 3>> positions;
  std::vector<std::array<std::int64_t, 3>> triangles;  //!< indices into positions
  std::optional<std::vector<std::int64_t>> ids;         //!< persistent vertex ids, when the file has them
  std::vector<VertexAttribute> attributes;              //!< further per-vertex properties

  std::size_t vertex_count() const { return positions.size(); }
  std::size_t triangle_count() const { return triangles.size(); }
  //! The attribute with this name, or nullptr.
  const VertexAttribute* attribute(const std::string& name) const {
    for (const auto& a : attributes)
      if (a.name == name) return &a;
    return nullptr;
  }
  VertexAttribute* attribute(const std::string& name) {
    for (auto& a : attributes)
      if (a.name == name) return &a;
    return nullptr;
  }
};

}  // namespace topotrack
