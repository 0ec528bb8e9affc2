#pragma once
//! Sampling an implicit function onto a sparse OpenVDB grid and meshing it with the sdf module's
//! marching cubes: how every synthetic input sequence is made (issue 2 item 7).
#include <functional>
#include <openvdb/openvdb.h>

#include "io/mesh_data.hpp"
#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack {

//! A scalar function of a world point, negative inside the shape.
using ImplicitFunction = std::function<double(const Vec3&)>;

//! Sample f at the voxel centres (index (i,j,k) at world (i,j,k) * voxel_size, as signed_distance) of
//! every 8^3 block that may contain a sign change; a block is skipped (stored as an inactive tile of the
//! sign at its centre) when |f(centre)| exceeds `lipschitz` times the distance to the farthest sample
//! the block's cells touch, which proves f has one sign there. So `lipschitz` must bound |grad f|
//! (1 for signed distance functions and their convex blends and smooth minima).
//! \pre f is positive outside `box`. \throw InvalidInput on voxel_size <= 0, lipschitz <= 0, an empty box or
//! more than 2^30 blocks.
openvdb::FloatGrid::Ptr sample_implicit(const ImplicitFunction& f, const BoundingBox& box, double voxel_size,
                                        double lipschitz = 1.0);

//! marching_cubes(sample_implicit(...)): a closed 2-manifold of the zero set of f.
MeshData mesh_implicit(const ImplicitFunction& f, const BoundingBox& box, double voxel_size, double lipschitz = 1.0);

}  // namespace topotrack
