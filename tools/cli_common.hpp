#pragma once
//! What several subcommands share: resolving inputs to frames, loading meshes with the file named in
//! every error, output folders.
#include <filesystem>
#include <string>
#include <vector>

#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack::cli {

//! One input frame: its file and frame number (-1 when the input was a single file without one).
struct InputFrame {
  std::filesystem::path path;
  long number = -1;
};

//! Each input is a mesh file, or a folder, glob or frame pattern of a sequence (io/sequence.hpp).
//! Sequence warnings (gaps, mixed formats) are appended to `warnings`.
std::vector<InputFrame> resolve_inputs(const std::vector<std::string>& inputs, std::vector<std::string>* warnings);

//! Read a mesh file (OBJ or PLY).
MeshData load_mesh_data(const std::filesystem::path& path);

//! Read a mesh file as a SurfaceMesh; with require_closed, an open or non-manifold surface is
//! rejected. \throw InvalidInput naming the file and the fault.
SurfaceMesh load_surface_mesh(const std::filesystem::path& path, bool require_closed = true);

//! Create the output folder (and parents). \throw IoError naming it.
void ensure_directory(const std::filesystem::path& dir);

//! Median of the values (0 for none): what every per-frame summary of the CLI reports.
double median(std::vector<double> values);

}  // namespace topotrack::cli
