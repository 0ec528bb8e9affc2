#pragma once
//! Wavefront OBJ writer (v and f only; ids and attributes are not representable), written atomically.
#include <filesystem>
#include <string>

#include "io/mesh_data.hpp"

namespace topotrack {

//! `v x y z` with the shortest decimal that reads back to the same double, then `f a b c` (1-based).
//! \throw InvalidInput on a non-finite position or an index out of range.
std::string encode_obj(const MeshData& mesh);
//! Write atomically. \throw IoError naming the path; InvalidInput as encode_obj, naming the path.
void write_obj(const std::filesystem::path& path, const MeshData& mesh);

//! Write by extension (.ply binary, .obj). \throw InvalidInput for another extension, IoError.
void write_mesh(const std::filesystem::path& path, const MeshData& mesh);

}  // namespace topotrack
