#pragma once
//! PLY reader: ascii, binary_little_endian and binary_big_endian.
#include <filesystem>
#include <string>
#include <string_view>

#include "io/mesh_data.hpp"

namespace topotrack {

//! Read a PLY file through a memory map.
//!
//! Elements may come in any order; elements other than `vertex` and `face` are skipped (list
//! properties included). `vertex` needs scalar x y z; its other scalar properties are kept:
//!   `id` -> MeshData::ids;  `red green blue [alpha]` -> attribute "color" (width 3/4; uchar/ushort
//!   scaled to [0,1], floats kept);  `vx vy vz` -> "v";  `nx ny nz` -> "normal";
//!   `<name>_0 .. <name>_k` (k >= 1) -> "<name>" of width k+1;  any other scalar -> "<name>" (width 1).
//! `face` needs a list `vertex_indices` (or `vertex_index`) of any count/index type; polygons are
//! fan-triangulated. Any property type is accepted (see PlyScalar).
//! \throw IoError when the file cannot be mapped.
//! \throw InvalidInput "<path>:<line>: <fault>" (header, ascii body) or "<path>: byte <offset>: <fault>"
//!        (binary body): empty file, bad header, no vertices, truncated data, lying counts, trailing
//!        bytes, non-finite coordinates, index negative or out of range, face with < 3 vertices,
//!        non-numeric token.
MeshData read_ply(const std::filesystem::path& path);

//! Parse PLY bytes already in memory; `name` (usually the path) starts every error message.
MeshData parse_ply(std::string_view bytes, const std::string& name);

}  // namespace topotrack
