#pragma once
//! Closing the small holes of an open surface through the level set (issue 9; the paper's stated limitation,
//! §7, is closed input surfaces): each boundary loop is capped by a fan around its centroid, the capped soup
//! becomes a narrow-band signed distance (§4.3's CalculateSignedDistance, with the winding-number sign and
//! the thickening of thin parts, as resurfacing real frames needs: kernels/gen/resurface.hpp), and its
//! marching-cubes zero set is the closed 2-manifold returned. The whole surface is resampled at that voxel
//! size, the resolution the tracker's level sets have anyway.
#include <array>
#include <limits>
#include <span>
#include <vector>

#include "io/mesh_data.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! The boundary loops (holes) of a triangle soup: each a closed chain of vertex indices along directed
//! boundary edges (an edge a->b of a triangle whose reverse b->a belongs to no triangle), sorted by their
//! smallest directed edge. A walk ends at its start vertex or, on a pinched or inconsistently oriented
//! boundary, where no unused boundary edge leaves. Empty for a closed surface.
std::vector<std::vector<Index>> boundary_loops(std::span<const std::array<Index, 3>> triangles);

//! Bounding-box diagonal of a loop's vertices: the size of the hole.
double loop_extent(std::span<const Vec3> positions, std::span<const Index> loop);

struct CloseHolesParams {
  double voxel_size = 0;  //!< of the level set; required, > 0
  //! Largest hole closed, as its extent (loop_extent) in voxels.
  double max_hole_voxels = std::numeric_limits<double>::infinity();
  //! Parts thinner than this are thickened to it (kernels/sdf/thicken.hpp); 0: as they are.
  double min_thickness_voxels = 1.75;
};

struct CloseHolesReport {
  std::size_t holes_closed = 0;         //!< boundary loops capped
  std::size_t hole_boundary_edges = 0;  //!< boundary edges, all in those loops
  double largest_hole = 0;              //!< extent of the largest loop (world units)
  std::size_t signs_flipped = 0;        //!< voxels whose OpenVDB sign the winding number corrected
  std::size_t thin_vertices = 0;        //!< input vertices on parts thinner than min_thickness_voxels
};

//! The closed 2-manifold of the capped surface, world positions (no ids). A closed input is resampled too.
//! \pre positions and triangles are finite and in range (the signed distance checks).
//! \throw InvalidInput when there are no triangles, the voxel size is not finite and positive, a hole is
//! larger than max_hole_voxels voxels, or the result is empty (the surface is thinner than a voxel).
MeshData close_holes(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                     const CloseHolesParams& params, CloseHolesReport* report = nullptr);

}  // namespace topotrack
