#pragma once
//! Topologically complex cells (§4.3, Wojtan et al. 2009 §4; generalised to any implicit surface Θ as the
//! paper does). A cell is simple when M restricted to the cell is exactly what marching cubes of Θ puts
//! there, up to deformation:
//!  - the boundary of M ∩ cell (on the cube faces) is a set of closed loops, each passing through the
//!    crossings of M with the cube edges in exactly the cyclic order and direction of one marching-cubes
//!    polygon of Θ's corner signs, every polygon matched once (this covers the edge test — one crossing
//!    on each edge where Θ changes sign, none elsewhere — and the face test — the curves on each face
//!    join the same crossings as the marching-cubes face segments, no closed curve inside a face);
//!  - every connected component of M ∩ cell is a disk (Euler characteristic 1, one boundary loop);
//!  - no two of M's cut curves cross on a cube face (two sheets of M intersecting in the cell).
//! Anything else, including a cell that Θ crosses and M misses, is complex. Being conservative costs
//! only resampling.
#include <cstdint>
#include <openvdb/openvdb.h>
#include <vector>

#include "kernels/topology/lattice_cut.hpp"

namespace topotrack::topology {

//! The cells to examine (those holding pieces of M and those where Θ changes sign), sorted by cell key,
//! with the range of each cell's pieces in `piece_order`.
struct CellIndex {
  std::vector<std::uint64_t> cells;        //!< sorted cell keys
  std::vector<std::uint32_t> piece_begin;  //!< cell i has pieces piece_order[piece_begin[i], piece_begin[i+1])
  std::vector<std::uint32_t> piece_order;  //!< piece indices grouped by cell, by piece index within a cell
  //! The piece range of a cell (empty when the cell has no piece).
  std::pair<std::uint32_t, std::uint32_t> pieces_of(std::uint64_t cell) const;
};

//! Group the pieces by cell and add the cells where Θ changes sign. The sign-change cells are found
//! in parallel over Θ's leaf nodes (a cell is visited from its minimum corner, which must be active:
//! true for any level set whose band is at least 2 voxels wide on each side).
CellIndex index_cells(const LatticeCut& cut, const openvdb::FloatGrid& theta);

//! Corner signs of Θ at a cell (bit c set: corner c inside, value < 0).
std::uint8_t theta_mask(const openvdb::FloatGrid::ConstAccessor& acc, const openvdb::Coord& cell);

//! Classify every indexed cell in parallel (per-cell results, deterministic). Returns the sorted keys of
//! the complex cells, including every cell of the boxes of the cut's bad faces.
std::vector<std::uint64_t> complex_cells(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index, const openvdb::FloatGrid& theta);

}  // namespace topotrack::topology
