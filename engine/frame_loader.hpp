#pragma once
//! One input frame of the tracker from disk: a closed mesh (OBJ, PLY) or an OpenVDB level set (.vdb).
#include <openvdb/openvdb.h>

#include <filesystem>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct LoadedFrame {
  SurfaceMesh mesh;                //!< the surface, when the file is a mesh
  openvdb::FloatGrid::Ptr grid;    //!< the level set, when the file is a .vdb
};

//! Read a .vdb file's level set: the first FloatGrid of class level set (or, failing that, the first
//! FloatGrid). \throw IoError (unreadable) or InvalidInput (no float grid, not a level set), naming the file.
openvdb::FloatGrid::Ptr read_level_set(const std::filesystem::path& path);

//! A mesh must be a closed 2-manifold. \throw InvalidInput naming the file and the fault, IoError.
LoadedFrame load_frame(const std::filesystem::path& path);

}  // namespace topotrack
