#pragma once
//! The mesh to render from a frame as io/ reads it: positions, triangles and the per-vertex colours of an
//! attribute (the `red green blue` or `color` property of a PLY written by `topotrack propagate`).
#include <string>

#include "io/mesh_data.hpp"
#include "kernels/render/raytracer.hpp"

namespace topotrack {

//! The colours of attribute `color_attribute` (width 3 or 4; alpha dropped) when present, else none.
//! \throw InvalidInput for a triangle index outside the vertices or a colour attribute of another width;
//! RenderScene checks the rest (finite positions).
RenderMesh to_render_mesh(const MeshData& data, const std::string& color_attribute = "color");

}  // namespace topotrack
