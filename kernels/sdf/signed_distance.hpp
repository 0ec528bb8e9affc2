#pragma once
//! CalculateSignedDistance of §4.3 / Algorithm 1 (lines 8 and 10): a narrow-band signed distance
//! level set of a closed triangle mesh, voxelized with OpenVDB.
//!
//! Grid convention (shared by marching_cubes): the transform is a uniform scale by `voxel_size`, so
//! the voxel with index (i, j, k) has its centre at the world point (i, j, k) * voxel_size (no offset).
//! Values are world-space distances, negative inside, positive outside; active voxels form a band of
//! `half_width_voxels` voxels on each side of the surface; inactive voxels and tiles hold the
//! background +-half_width_voxels * voxel_size with the sign of their side. Grid class GRID_LEVEL_SET.
#include <array>
#include <openvdb/openvdb.h>
#include <span>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! openvdb::initialize(), once per process (thread-safe). Called by every function of this module
//! that creates grids; callers that read or write .vdb files may call it too.
void ensure_openvdb_initialized();

//! The transform of the convention above: uniform scale, voxel centres at integer multiples.
//! \throw InvalidInput when voxel_size is not finite and positive.
openvdb::math::Transform::Ptr voxel_transform(double voxel_size);

//! Signed distance to the triangle mesh (positions, triangles) in a narrow band (§4.3).
//! \pre the mesh is closed (for an open mesh the sign is what OpenVDB's flood fill makes of it).
//! \throw InvalidInput on voxel_size <= 0 or not finite, half_width_voxels < 1 or not finite,
//! a non-finite coordinate or a triangle index out of range. An empty mesh gives an empty grid.
openvdb::FloatGrid::Ptr signed_distance(std::span<const Vec3> positions,
                                        std::span<const std::array<Index, 3>> triangles, double voxel_size,
                                        double half_width_voxels = 3.0, double exact_sign_band_voxels = 0.0);

//! The same for the live triangles of a SurfaceMesh.
//! `exact_sign_band_voxels` > 0: voxels closer to the surface than that many voxels get their sign decided
//! exactly (kernels/sdf/exact_sign.hpp), as ConstrainTopology needs (§4.3).
openvdb::FloatGrid::Ptr signed_distance(const SurfaceMesh& mesh, double voxel_size, double half_width_voxels = 3.0,
                                        double exact_sign_band_voxels = 0.0);

}  // namespace topotrack
