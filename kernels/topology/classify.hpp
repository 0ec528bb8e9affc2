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
#include <array>
#include <cstdint>
#include <span>
#include <openvdb/openvdb.h>
#include <vector>

#include "kernels/topology/lattice_cut.hpp"

namespace topotrack::topology {

//! The cells to examine (those holding pieces of M and those where Θ changes sign), sorted by cell key,
//! with the range of each cell's pieces in `piece_order`, and the lattice nodes whose sign is taken from M.
struct CellIndex {
  std::vector<std::uint64_t> cells;        //!< sorted cell keys
  std::vector<std::uint32_t> piece_begin;  //!< cell i has pieces piece_order[piece_begin[i], piece_begin[i+1])
  HugeVector<std::uint32_t> piece_order;   //!< piece indices grouped by cell, by piece index within a cell
  //! Sorted keys (cell_key of the node) of the lattice nodes whose sign is the opposite of Θ's: see
  //! kSignTolerance.
  std::vector<std::uint64_t> flipped;
  //! The piece range of a cell (empty when the cell has no piece).
  std::pair<std::uint32_t, std::uint32_t> pieces_of(std::uint64_t cell) const;
  bool is_flipped(const openvdb::Coord& node) const;
};

//! Lattice nodes closer than this to Θ's zero set (in voxels) take their sign from M's crossings of the
//! lattice edges around them. The cut works on M moved by up to kSnap + kShift per axis (lattice_cut.hpp),
//! at most 0.018 voxel, so a node that close to M may lie on the other side of the cut mesh than of M; its
//! sign then disagrees with M's crossings in the cells around it, and a well-represented surface would be
//! resampled there (Wojtan et al. 2009 push nearly-zero lattice values off zero for the same reason). The
//! margin above 0.018 covers meshToVolume's distances, which can overestimate the true distance near
//! vertices by a few hundredths of a voxel. Such a node takes the sign that its lattice-edge neighbours
//! farther from the zero set imply through the parity of M's crossings of the edge between them, when they
//! all agree; otherwise Θ's sign. For Θ = φ_M this is M's own side; for Θ = φ_S it moves S's zero set by at
//! most this much towards M (the tracker's topology_tolerance already allows 0.5 voxel). With
//! `flips_keep_topology` (index_cells) only flips that keep Θ's topology are taken (simple points,
//! simple_point.hpp): across a gap or a sheet of Θ that close to a node, M's side is Θ's topology lost.
inline constexpr double kSignTolerance = 0.1;

//! Group the pieces by cell, decide the signs of the nodes within kSignTolerance of Θ's zero set, and add
//! the cells where Θ (with those signs) changes sign. The sign-change cells are found in parallel over Θ's
//! leaf nodes: from their minimum corner when it is active, else from a lattice edge with an active end
//! along which Θ changes sign. Θ need not be a distance; only a sign change between two inactive nodes (a
//! band broken through) goes unseen.
//! With `only`, just the cells that are active voxels of it (keyed by their minimum corner) are indexed: a
//! local ConstrainTopology (constrain.hpp), where the others count as simple.
CellIndex index_cells(const LatticeCut& cut, const openvdb::FloatGrid& theta, bool flips_keep_topology = true,
                      const openvdb::MaskGrid* only = nullptr);

//! Θ's value at a lattice node, with the sign decided by index_cells (a flipped zero becomes negative).
float node_value(const openvdb::FloatGrid::ConstAccessor& acc, const CellIndex& index, const openvdb::Coord& node);
//! Corner signs of Θ at a cell as index_cells decided them (bit c set: corner c inside, value < 0).
std::uint8_t theta_mask(const openvdb::FloatGrid::ConstAccessor& acc, const CellIndex& index, const openvdb::Coord& cell);

//! Why a cell is complex (kSimple: it is not).
enum class CellVerdict : std::uint8_t {
  kSimple = 0,
  kMissed,         //!< Θ has more marching-cubes polygons in the cell than M has boundary loops
  kDuplicateEdge,  //!< two pieces share a directed edge (M folds over itself)
  kPinch,          //!< two boundary loops of M ∩ cell touch at a point
  kMeshBoundary,   //!< M has a boundary edge in the cell
  kBrokenLoop,     //!< a boundary loop leaves the cell's edges or does not close
  kLoopInFace,     //!< a boundary loop crosses no cube edge (a closed curve inside a cube face)
  kUnmatchedLoop,  //!< a boundary loop runs through other cube edges than any polygon of Θ
  kNotDisk,        //!< a component of M ∩ cell is not a disk with one boundary loop
  kCurvesCross,    //!< two of M's cut curves cross on a cube face
  //! A boundary loop runs through other cube edges than any polygon of Θ because it crosses one cube edge
  //! twice: M grazes a lattice edge (a near-tangency or a part thinner than a voxel). Otherwise as
  //! kUnmatchedLoop, which it refines.
  kEdgeCrossedTwice,
};
inline constexpr int kVerdictKinds = 11;
//! A short lower-case name of a verdict ("simple", "missed", ..., "edge_crossed_twice"), for reports.
const char* verdict_name(CellVerdict v);
//! Cells counted by verdict (index: int(CellVerdict)).
using VerdictCounts = std::array<std::uint32_t, kVerdictKinds>;

//! Whether a boundary loop, given as the cube edges (0..11) it crosses in order, crosses one of them twice:
//! tells kEdgeCrossedTwice from kUnmatchedLoop (both per-cell tests use it).
template <class Edge>
bool crosses_an_edge_twice(std::span<const Edge> loop) {
  unsigned seen = 0;
  for (const Edge e : loop) {
    if ((seen >> e) & 1u) return true;
    seen |= 1u << e;
  }
  return false;
}

//! Which implementation of the per-cell test runs. Both give the same verdict for every cell (tested):
//! kFast (classify_fast.hpp) works on cell-local flat arrays and falls back to kReference only for cells
//! beyond its limits; kReference is the plain version, kept as the specification.
enum class ClassifyPath : std::uint8_t { kFast, kReference };

//! The verdict of every indexed cell (parallel, per-cell results, deterministic).
std::vector<CellVerdict> classify_cells(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
                                        const openvdb::FloatGrid& theta, ClassifyPath path = ClassifyPath::kFast);

//! Classify every indexed cell in parallel (per-cell results, deterministic). Returns the sorted keys of
//! the complex cells, including every cell of the boxes of the cut's bad faces; `by_verdict`, when given,
//! receives the number of indexed cells of each verdict (the bad faces' boxes not included).
std::vector<std::uint64_t> complex_cells(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
                                         const openvdb::FloatGrid& theta, ClassifyPath path = ClassifyPath::kFast,
                                         VerdictCounts* by_verdict = nullptr);

//! The face test of both cell tests (classify.cpp, classify_fast.cpp; Wojtan et al. 2009): whether the 2D segments
//! (p[0], p[1])-(p[2], p[3]) and (q[0], q[1])-(q[2], q[3]) cross at a point inside both (touching does not count).
inline bool segments_cross(const double* p, const double* q) {
  const auto orient = [](double ax, double ay, double bx, double by, double cx, double cy) {
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
  };
  const double o1 = orient(p[0], p[1], p[2], p[3], q[0], q[1]), o2 = orient(p[0], p[1], p[2], p[3], q[2], q[3]);
  const double o3 = orient(q[0], q[1], q[2], q[3], p[0], p[1]), o4 = orient(q[0], q[1], q[2], q[3], p[2], p[3]);
  return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) && ((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

}  // namespace topotrack::topology
