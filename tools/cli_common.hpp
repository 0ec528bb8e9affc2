#pragma once
//! What several subcommands share: resolving inputs to frames, loading meshes with the file named in
//! every error, output folders.
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/topology/classify.hpp"
#include "kernels/propagate/tracked_sequence.hpp"

namespace topotrack::cli {

//! One input frame: its file and frame number (-1 when the input was a single file without one).
struct InputFrame {
  std::filesystem::path path;
  long number = -1;
};

//! Each input is a mesh file, or a folder, glob or frame pattern of a sequence (io/sequence.hpp).
//! Sequence warnings (gaps, mixed formats) are appended to `warnings`.
std::vector<InputFrame> resolve_inputs(const std::vector<std::string>& inputs, std::vector<std::string>* warnings);

//! resolve_inputs with the warnings printed to stderr ("topotrack: warning: ..."), as every subcommand
//! reports them. \throw InvalidInput "no frames" when nothing is found.
std::vector<InputFrame> resolve_frames(const std::vector<std::string>& inputs);

//! The frames of a tracked sequence (resolve_frames, then each frame's events file next to it).
std::vector<TrackedFrame> resolve_tracked_frames(const std::vector<std::string>& inputs);

//! The sequence name for output files: the first frame's stem without its frame number ("blobs.0001" -> "blobs").
std::string sequence_name(const std::filesystem::path& first);

//! Read a mesh file (OBJ or PLY).
MeshData load_mesh_data(const std::filesystem::path& path);

//! Read a mesh file as a SurfaceMesh; with require_closed, an open or non-manifold surface is
//! rejected. \throw InvalidInput naming the file and the fault.
SurfaceMesh load_surface_mesh(const std::filesystem::path& path, bool require_closed = true);

//! Create the output folder (and parents). \throw IoError naming it.
void ensure_directory(const std::filesystem::path& dir);

//! The non-zero counts of complex cells by verdict, keyed by verdict name (the complex_by_reason of
//! `constrain --json` and of track.json).
nlohmann::json complex_reasons_json(const topology::VerdictCounts& counts);

//! Median of the values (0 for none): what every per-frame summary of the CLI reports.
double median(std::vector<double> values);

}  // namespace topotrack::cli
