#pragma once
//! A tracked frame as the applications of §5 use it: positions, triangles and persistent vertex ids taken
//! from the flat MeshData of io/ (ids from the PLY `id` property of the tracker's output).
#include <array>
#include <string>
#include <vector>

#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/render/raytracer.hpp"

namespace topotrack {

struct FrameGeometry {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  std::vector<VertexId> ids;  //!< empty when the data has none
};

//! \throw InvalidInput on a non-finite position, an index out of range, a negative or repeated id.
FrameGeometry frame_geometry(const MeshData& data);

//! The mesh to render, with the colours of attribute `color_attribute` (width 3 or 4; alpha dropped) when
//! present. \throw InvalidInput as frame_geometry, or for a colour attribute of another width.
RenderMesh to_render_mesh(const MeshData& data, const std::string& color_attribute = "color");

//! Set (replace or add) attribute `name` of `data`. \throw InvalidInput when values.size() != width * vertices.
void set_attribute(MeshData& data, const std::string& name, int width, std::vector<float> values);

}  // namespace topotrack
