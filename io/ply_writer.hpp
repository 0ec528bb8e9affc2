#pragma once
//! PLY writer: binary little endian (default) or ascii, written atomically.
#include <filesystem>
#include <string>

#include "io/mesh_data.hpp"

namespace topotrack {

struct PlyWriteOptions {
  bool ascii = false;
  bool double_positions = false;  //!< x y z as double instead of float
  bool big_endian = false;        //!< binary_big_endian instead of binary_little_endian (ignored with ascii)
};

//! The PLY bytes for `mesh`: vertex properties `x y z` (float), `id` (int, when mesh.ids is set), then each
//! attribute: "color" -> `red green blue [alpha]` (uchar, from floats in [0,1]), "v" -> `vx vy vz` (float),
//! "normal" -> `nx ny nz`, any other of width 1 -> `<name>` (float), of width k > 1 -> `<name>_0 .. <name>_{k-1}`.
//! Faces as `list uchar int vertex_indices`. read_ply(encode_ply(m)) gives m back (floats rounded).
//! `id` is written as `int64` when an id does not fit in int; indices as `int64` beyond 2^31 - 1 vertices.
//! Conventions are documented in docs/formats.md.
//! \throw InvalidInput when an attribute's size is not width * vertex count, an index is out of range, a
//!        position is not finite (or overflows float without double_positions), a colour is not finite, an
//!        attribute name is empty, holds whitespace or clashes with another property.
std::string encode_ply(const MeshData& mesh, const PlyWriteOptions& options = {});

//! Write atomically (temporary file + rename). \throw IoError naming the path; InvalidInput as encode_ply.
void write_ply(const std::filesystem::path& path, const MeshData& mesh, const PlyWriteOptions& options = {});

}  // namespace topotrack
