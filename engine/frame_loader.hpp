#pragma once
//! One input frame of the tracker from disk: a closed mesh (OBJ, PLY) or an OpenVDB level set (.vdb).
//! The tracker needs closed 2-manifold surfaces (the paper's stated limitation, §7); an open frame is
//! rejected naming its holes, or, on request, closed through the level set (docs/robustness.md).
#include <openvdb/openvdb.h>

#include <filesystem>
#include <string>
#include <vector>

#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! How load_frame treats a mesh that is not closed.
struct FrameLoadParams {
  //! Close the holes of an open mesh (close_holes below) instead of rejecting it.
  bool close_holes = false;
  //! The voxel size of that level set: the tracker's (Tracker::voxel_size()). <= 0: the frame's mean edge length.
  double voxel_size = 0;
  //! Largest hole closed, as its extent (bounding-box diagonal of its boundary loop) in voxels.
  double max_hole_voxels = 8;
};

//! What load_frame did to the input (empty when the file was used as it is).
struct FrameLoadReport {
  std::size_t holes_closed = 0;         //!< boundary loops capped
  std::size_t hole_boundary_edges = 0;  //!< boundary edges of the input, all in those loops
  double largest_hole = 0;              //!< extent of the largest loop (world units)
  double voxel_size = 0;                //!< of the level set the closed frame was rebuilt from
  std::vector<std::string> warnings;    //!< one line per repair, for track.json and the console
};

struct LoadedFrame {
  SurfaceMesh mesh;                //!< the surface, when the file is a mesh
  openvdb::FloatGrid::Ptr grid;    //!< the level set, when the file is a .vdb
  FrameLoadReport report;
};

//! Read a .vdb file's level set: the first FloatGrid of class level set (or, failing that, the first
//! FloatGrid). \throw IoError (unreadable) or InvalidInput (no float grid, not a level set), naming the file.
openvdb::FloatGrid::Ptr read_level_set(const std::filesystem::path& path);

//! Mean length of the triangle soup's edges, each edge once (the tracker's default L for this frame, §4.1).
double soup_mean_edge_length(const MeshData& data);

//! The boundary loops (holes) of a triangle soup: each a closed chain of vertex indices along directed
//! boundary edges (an edge a->b of a triangle whose reverse b->a belongs to no triangle), sorted by their
//! smallest directed edge. Empty for a closed surface.
std::vector<std::vector<std::int64_t>> boundary_loops(const MeshData& data);

//! Close the holes of an open surface through the level set at `params.voxel_size` (kernels/sdf/close_holes.hpp:
//! caps, winding-number signed distance, thin parts thickened, marching cubes): a closed 2-manifold. The
//! whole surface is resampled at that voxel size, the resolution the tracker's level sets have anyway (§4.3).
//! \pre data has triangles.
//! \throw InvalidInput naming `name` when a hole is larger than params.max_hole_voxels voxels or the result
//! is empty (the surface is thinner than a voxel).
SurfaceMesh close_holes(const MeshData& data, const FrameLoadParams& params, const std::string& name,
                        FrameLoadReport* report = nullptr);

//! A mesh must be a closed 2-manifold: an open one is closed (params.close_holes) or rejected.
//! \throw InvalidInput naming the file and the fault (for an open surface: its boundary edges and holes),
//! IoError.
LoadedFrame load_frame(const std::filesystem::path& path, const FrameLoadParams& params = {});

}  // namespace topotrack
