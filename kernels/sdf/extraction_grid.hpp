#pragma once
//! Recognise a surface extracted from a grid by marching cubes (a simulation's level set, `gen resurface`):
//! each of its vertices lies on a grid edge, so two of its three coordinates are the grid's origin plus integer
//! multiples of its spacing. The tracker's lattice on that grid (or half its spacing) samples the extraction's own signs
//! and so sees every handle and bridge the input has (TrackerParams::voxel_size).
#include <optional>
#include <span>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! A grid found by extraction_grid: nodes at origin + (i, j, k) * spacing.
struct ExtractionGrid {
  double spacing = 0;
  //! Per axis in [-spacing/2, spacing/2]; exactly 0 on an axis where the nodes lie within 1e-3 spacing of the
  //! multiples of the spacing (OpenVDB's convention without a translation, signed_distance.hpp).
  Vec3 origin = Vec3::Zero();
};

//! The grid the points were extracted on, or nothing when they were not: at least 60 % of the points must
//! have two or more coordinates within 1e-3 r of a grid plane (marching cubes' vertices on the grid's edges;
//! its others lie inside cells: 16-18 % of resurfaced pcow, samba and blobs), at most 2 % exactly one (points
//! off any grid: ~40 % of a capture's own frames), at most half all three (coordinates merely rounded to a
//! fixed number of decimals), and the spacing r must lie within [0.1, 10] × `edge_length` (the mesh's mean
//! edge length; <= 0: not checked). The spacing is the largest divisor (by 1 to 8) of the smallest gap between
//! the most frequent coordinate values that passes; where none does (flat faces off the grid's planes, a
//! tank's walls, recur more than any lattice plane), the largest spacing that passes among the divisors of the
//! gaps between the 16 most frequent values of each axis. The origin is where most of each axis's planes lie
//! between multiples of the spacing (a simulation domain's corner, cell-centred samples). Nothing
//! for a non-finite coordinate. O(n log n).
std::optional<ExtractionGrid> extraction_grid(std::span<const Vec3> points, double edge_length);

}  // namespace topotrack
