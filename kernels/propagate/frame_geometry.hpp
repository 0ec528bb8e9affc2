#pragma once
//! A tracked frame as the applications of §5 use it: positions, triangles and persistent vertex ids taken
//! from the flat MeshData of io/ (ids from the PLY `id` property of the tracker's output), and whether two
//! frames share their connectivity (export of constant-connectivity stretches).
#include <array>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "io/event_list.hpp"
#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct FrameGeometry {
  std::vector<Vec3> positions;
  std::vector<std::array<Index, 3>> triangles;
  std::vector<VertexId> ids;  //!< empty when the data has none
};

//! \throw InvalidInput on a non-finite position, an index out of range, a negative or repeated id.
FrameGeometry frame_geometry(const MeshData& data);

//! A frame file read with its geometry.
struct FrameFile {
  MeshData data;
  FrameGeometry geometry;
};
//! Read a mesh file (io/mesh_reader.hpp) and its geometry. \throw IoError, InvalidInput naming the file; with
//! `require_ids`, InvalidInput for a frame without vertex ids (not `topotrack track` output).
FrameFile read_frame_file(const std::filesystem::path& path, bool require_ids);

//! Set (replace or add) attribute `name` of `data`. \throw InvalidInput when values.size() != width * vertices.
void set_attribute(MeshData& data, const std::string& name, int width, std::vector<float> values);

//! Move each vertex of `data` to `positions` (same count). \throw InvalidInput on a different count.
void set_positions(MeshData& data, std::span<const Vec3> positions);

//! When frame b has the connectivity of frame a — the same vertex ids (or, without ids, the same vertex
//! count) and the same triangles up to triangle order and rotation — the index in b of each vertex of a;
//! otherwise nullopt. Empty id spans mean "no ids" (vertices matched by index).
std::optional<std::vector<Index>> match_connectivity(std::span<const VertexId> ids_a,
                                                     std::span<const std::array<Index, 3>> triangles_a,
                                                     std::span<const VertexId> ids_b,
                                                     std::span<const std::array<Index, 3>> triangles_b);

}  // namespace topotrack
