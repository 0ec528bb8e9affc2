#pragma once
//! The per-cell test of classify.hpp (§4.3, Wojtan et al. 2009 §4) on cell-local flat arrays: the same
//! checks, in the same order, with the same verdict as the reference implementation in classify.cpp, but
//! with no sorting of 16-byte keys, no binary searches and no allocation. Points of the subdivision are
//! renamed by a 64-bit key that is local to the cell (every corner of a piece lies on the closed cell, so a
//! plane is the cell's lower or upper one: one bit), ordered like PointKey, so point ids are the same ranks
//! as in the reference; directed edges live in a 64 x 64 bit matrix, so the duplicate-edge test and the
//! boundary test (is the reverse edge there?) are single bit tests.
#include <cstdint>
#include <optional>

#include "kernels/topology/classify.hpp"

namespace topotrack::topology {

//! Reused buffers of the fast test (one per task; about 9 KB).
struct FastCellScratch {
  static constexpr int kMaxCorners = 255;  //!< piece corners per cell
  static constexpr int kMaxPoints = 64;    //!< distinct points per cell
  std::uint64_t sorted[kMaxCorners];       // (local key << 8) | corner
  std::uint32_t global[kMaxCorners];       // corner -> index into cut.keys
  std::uint8_t next[kMaxCorners];          // corner -> next corner of its piece
  std::uint8_t id[kMaxCorners];            // corner -> point id
  std::uint32_t point_key[kMaxPoints];     // point id -> index into cut.keys of one of its corners
  std::uint64_t adj[kMaxPoints];           // bit t of adj[f]: directed edge f -> t
  std::uint8_t tag[kMaxPoints * kMaxPoints];  // tag of the edge f -> t (valid where adj says so)
  std::uint8_t parent[kMaxPoints];
  std::int8_t out[kMaxPoints];             // the boundary edge leaving a point: its head, or -1
  std::uint8_t used[kMaxPoints];
  std::uint8_t loop[kMaxPoints];
  std::uint8_t loop_root[kMaxPoints];
};

//! The verdict of indexed cell `ci` with Θ's corner mask `mask`, identical to the reference test; nullopt
//! when the cell exceeds the scratch limits (kMaxCorners, kMaxPoints) and the reference must decide.
std::optional<CellVerdict> classify_cell_fast(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
                                              std::size_t ci, std::uint8_t mask, FastCellScratch& s);

}  // namespace topotrack::topology
