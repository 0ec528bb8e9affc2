#pragma once
//! Recognise a surface extracted from a grid by marching cubes (a simulation's level set, `gen resurface`):
//! each of its vertices lies on a grid edge, so two of its three coordinates are integer multiples of the
//! grid's spacing. The tracker's lattice on that grid (or half its spacing) samples the extraction's own signs
//! and so sees every handle and bridge the input has (TrackerParams::voxel_size).
#include <optional>
#include <span>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! The spacing r of the grid the points were extracted on, with its nodes at integer multiples of r (the
//! convention of signed_distance.hpp, OpenVDB's without a translation), or nothing when they were not: at
//! least 60 % of the points must have two or more coordinates within 1e-3 r of a multiple of r (marching cubes'
//! vertices on the grid's edges; its others lie inside cells: 16-18 % of resurfaced pcow, samba and blobs), at
//! most 2 % exactly one (points off any grid: ~40 % of a capture's own frames), at most half all three
//! (coordinates merely rounded to a fixed number of decimals), and r must lie within [0.1, 10] × `edge_length`
//! (the mesh's mean edge length; <= 0: not checked). A grid with another origin is not recognised. The
//! spacing is the largest divisor (by 1 to 8) of the smallest gap between the most frequent coordinate values
//! that passes; where none does (flat faces off the grid's planes, a tank's walls, recur more than any lattice
//! plane), the largest spacing that passes among the divisors of the gaps between the 16 most frequent values
//! of each axis. Nothing for a non-finite coordinate. O(n log n).
std::optional<double> extraction_grid_spacing(std::span<const Vec3> points, double edge_length);

}  // namespace topotrack
