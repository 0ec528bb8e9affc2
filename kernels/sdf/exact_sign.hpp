#pragma once
//! Exact inside/outside near the surface for a voxelized signed distance (§4.3).
//!
//! OpenVDB's meshToVolume decides the sign of voxels next to the surface from the normal of one closest
//! face. Where the closest point lies on an edge or a vertex (every concave crease of a tessellated
//! surface), that test can put a lattice node on the wrong side by a fraction of a voxel. Marching cubes
//! does not mind, but ConstrainTopology compares the signs with the mesh's exact edge crossings, and
//! every such node made the cells around it "complex": hundreds of needless resamplings per frame. The
//! angle-weighted pseudonormal of the closest feature (Bærentzen and Aanæs 2005) gives the exact side for
//! a closed, consistently oriented mesh that does not intersect itself; where it does (real scans and
//! animations do), the generalized winding number (winding_number.hpp) gives the side instead.
#include <openvdb/openvdb.h>

#include <array>
#include <span>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! How correct_signs_near_surface decides a side.
enum class SignMethod {
  kPseudonormal,   //!< closest feature's pseudonormal: exact for an embedded mesh, fast (one closest point)
  kWindingNumber,  //!< winding number >= 1/2: also right where the surface crosses itself or has small holes
};

//! Re-decide the sign of every active voxel of `phi` whose |value| is below `band` (world units) from the
//! closest point of the mesh (positions, triangles) and its pseudonormal, or from the winding number;
//! magnitudes are kept. With the winding number, inactive voxels whose sign contradicts an active face
//! neighbour's (OpenVDB's flood-filled sign beyond the band goes wrong next to self-intersections) are
//! decided by it too, and made active; the pseudonormal method is for embedded meshes, where that sign is
//! right. Parallel, deterministic. Returns the number of voxels whose sign changed.
//! \pre the mesh is closed and consistently oriented (outward normals); phi is on that mesh.
std::size_t correct_signs_near_surface(openvdb::FloatGrid& phi, std::span<const Vec3> positions,
                                       std::span<const std::array<Index, 3>> triangles, double band,
                                       SignMethod method = SignMethod::kPseudonormal);

}  // namespace topotrack
