#pragma once
//! Read a mesh file of any supported format, chosen by extension (.obj, .ply; case-insensitive).
#include <filesystem>

#include "io/mesh_data.hpp"

namespace topotrack {

//! \throw InvalidInput naming the file for an unknown extension or malformed content; IoError when
//! it cannot be read.
MeshData read_mesh(const std::filesystem::path& path);

}  // namespace topotrack
