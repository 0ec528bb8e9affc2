#pragma once
//! CalculateSignedDistance of §4.3 / Algorithm 1 (lines 8 and 10): a narrow-band signed distance
//! level set of a closed triangle mesh, voxelized with OpenVDB.
//!
//! Grid convention (shared by marching_cubes): the transform is a uniform scale by `voxel_size`, so
//! the voxel with index (i, j, k) has its centre at the world point (i, j, k) * voxel_size (no offset); a
//! lattice through another origin (SignedDistanceParams::origin: the grid a surface was extracted on) adds a
//! translation, and the code downstream reads positions through the grid's transform.
//! Values are world-space distances, negative inside, positive outside; active voxels form a band of
//! `half_width_voxels` voxels on each side of the surface; inactive voxels and tiles hold the
//! background +-half_width_voxels * voxel_size with the sign of their side. Grid class GRID_LEVEL_SET.
#include <array>
#include <openvdb/openvdb.h>
#include <span>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/sdf/exact_sign.hpp"

namespace topotrack {

//! openvdb::initialize(), once per process (thread-safe). Called by every function of this module
//! that creates grids; callers that read or write .vdb files may call it too.
void ensure_openvdb_initialized();

//! The transform of the convention above: uniform scale, voxel centres at integer multiples.
//! \throw InvalidInput when voxel_size is not finite and positive.
openvdb::math::Transform::Ptr voxel_transform(double voxel_size);
//! The same with voxel centres at origin + (i, j, k) * voxel_size (voxel_transform when origin is 0).
openvdb::math::Transform::Ptr lattice_transform(double voxel_size, const Vec3& origin);
//! Whether `xform` is that lattice (linear, unrotated, voxel size and origin within 1e-9 voxel): a level
//! set on it can stand in for signed_distance's at (voxel_size, origin), node for node.
bool is_lattice(const openvdb::math::Transform& xform, double voxel_size, const Vec3& origin);

//! The input check shared by every signed-distance entry point (signed_distance, narrow_band_signed_distance).
//! \throw InvalidInput when half_width_voxels is below 1 or not finite, a coordinate is not finite or a
//! triangle index is out of range (the voxel size is checked by voxel_transform).
void check_signed_distance_input(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                                 double half_width_voxels);

//! How the distance is computed; kAuto is the one place that picks.
enum class SdfMethod {
  //! kNarrowBand for the tracker's closed meshes (sign_method kPseudonormal, no thickening, extent within
  //! narrow_band_fits), OpenVDB otherwise.
  kAuto,
  kNarrowBand,  //!< narrow_band.hpp: exact distances, winding sign along lattice columns (closed meshes)
  kOpenVdb,     //!< OpenVDB meshToVolume and the passes below: any soup (self-intersecting, open, thin parts)
};

struct SignedDistanceParams {
  double voxel_size = 0;            //!< required: finite, > 0
  Vec3 origin = Vec3::Zero();       //!< the lattice's node (0, 0, 0) (lattice_transform); finite
  double half_width_voxels = 3.0;   //!< active band on each side of the surface, >= 1
  //! > 0: voxels closer to the surface than that many voxels get their sign decided exactly
  //! (exact_sign.hpp), as ConstrainTopology needs (§4.3) and as marching cubes of real data needs.
  double exact_sign_band_voxels = 0.0;
  SignMethod sign_method = SignMethod::kPseudonormal;  //!< kWindingNumber for surfaces that cross themselves
  //! > 0: parts thinner than that many voxels are thickened to it (thicken.hpp) so that the zero set keeps
  //! them in one piece; needs half_width_voxels >= min_thickness_voxels / 2 + 1.5.
  double min_thickness_voxels = 0.0;
  SdfMethod method = SdfMethod::kAuto;
};

struct SignedDistanceReport {
  std::size_t active_voxels = 0;
  std::size_t signs_flipped = 0;     //!< voxels whose OpenVDB sign the exact-sign pass changed
  std::size_t thin_vertices = 0;     //!< vertices on parts thinner than min_thickness_voxels
  std::size_t thickened_voxels = 0;  //!< voxels the thickening lowered
  SdfMethod method = SdfMethod::kAuto;  //!< the method used (kNarrowBand or kOpenVdb)
  double seconds_volume = 0, seconds_sign = 0, seconds_thicken = 0;
};

//! Signed distance to the triangle mesh (positions, triangles) in a narrow band (§4.3), with the passes
//! `params` asks for. With kNarrowBand (what kAuto picks for the tracker) every sign is exact and
//! exact_sign_band_voxels has nothing left to do; seconds_volume is the whole computation. \pre the mesh is closed and outward oriented (for an open mesh the sign is what
//! the sign method makes of it). \throw InvalidInput on a bad parameter (see SignedDistanceParams), a
//! non-finite coordinate or a triangle index out of range. An empty mesh gives an empty grid.
openvdb::FloatGrid::Ptr signed_distance(std::span<const Vec3> positions,
                                        std::span<const std::array<Index, 3>> triangles,
                                        const SignedDistanceParams& params, SignedDistanceReport* report = nullptr);

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
                                        double exact_sign_band_voxels = 0.0, const Vec3& origin = Vec3::Zero());

}  // namespace topotrack
