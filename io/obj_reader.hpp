#pragma once
//! Wavefront OBJ reader (geometry subset): `v` and `f` statements.
#include <filesystem>
#include <string>
#include <string_view>

#include "io/mesh_data.hpp"

namespace topotrack {

//! Read an OBJ file through a memory map.
//! Reads `v x y z [w]` (w and any further numbers, e.g. vertex colours, ignored) and
//! `f` with `v`, `v/vt`, `v//vn`, `v/vt/vn` corners; negative indices count back from the last vertex
//! defined so far (OBJ spec); polygons are fan-triangulated (v0 vi vi+1). `vt`, `vn`, `g`, `o`, `s`,
//! `usemtl`, `mtllib`, comments and any other statements are ignored.
//! \throw IoError when the file cannot be mapped.
//! \throw InvalidInput "<path>:<line>: <fault>" for an empty file, no vertices, a non-numeric or
//!        non-finite coordinate, a garbage token, index 0, an index out of range, a face with < 3 corners.
MeshData read_obj(const std::filesystem::path& path);

//! Parse OBJ text already in memory; `name` (usually the path) starts every error message.
MeshData parse_obj(std::string_view text, const std::string& name);

}  // namespace topotrack
