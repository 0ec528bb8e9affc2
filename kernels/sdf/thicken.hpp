#pragma once
//! Thin parts made thick enough for a level set to represent them.
//!
//! A level set sampled at voxel size h cannot represent a part thinner than about h: where a sheet is
//! thinner, marching cubes finds it only at the lattice nodes that happen to fall inside it, and turns it
//! into a lace of holes and single-voxel specks. The elephant of /work/shared/data has ears 0.1 voxel
//! thick at 128 voxels across: resurfaced as it is, frame 1 had 97 components (96 one-voxel specks) and
//! genus 3, and finer voxels only make more specks (2849 components at 512). Thickening each such part
//! to a minimum thickness before marching cubes keeps it, closed, in one piece.
#include <openvdb/openvdb.h>

#include <array>
#include <span>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

struct ThickenParams {
  //! World units: parts thinner than this (measured along the inward vertex normal) are thickened to it.
  double min_thickness = 0;
};

struct ThickenReport {
  std::size_t thin_vertices = 0;   //!< vertices whose inward thickness is below min_thickness
  std::size_t voxels_changed = 0;  //!< active voxels whose value the thickening lowered
};

//! phi := min(phi, |phi| - t(x)), where t(x) is half of what the part under x's closest surface point
//! lacks of min_thickness (interpolated over the closest triangle from per-vertex values): the surface
//! moves out by t on both sides of a thin part and stays where it is elsewhere. Parallel, deterministic.
//! \pre phi is the signed distance of the mesh (positions, triangles), closed and outward oriented, with
//! correct signs, and its half width exceeds min_thickness / 2 by at least 1.5 voxels.
ThickenReport thicken_thin_parts(openvdb::FloatGrid& phi, std::span<const Vec3> positions,
                                 std::span<const std::array<Index, 3>> triangles, const ThickenParams& params);

}  // namespace topotrack
