#pragma once
//! The replacement step of ConstrainTopology (§4.3): keep M's pieces in simple cells, put the
//! marching-cubes polygons of Θ in complex cells, stitched to M's cut curves (see constrain.hpp).
#include <cstdint>
#include <openvdb/openvdb.h>
#include <string>
#include <vector>

#include "kernels/topology/classify.hpp"
#include "kernels/topology/lattice_cut.hpp"

namespace topotrack::topology {

//! The new surface as flat arrays. Output vertices come in three runs: [0, n_kept) kept vertices of M
//! (kept_old[i] is the old handle), then the derived points of M's subdivision that were kept
//! (derived[i]: an EdgePoint, a FacePoint, or an Other key whose `a` is the face whose centroid it is),
//! then the patch vertices (marching-cubes lattice-edge vertices and polygon centroids).
struct Assembly {
  std::vector<Vec3> positions;  //!< world space
  std::vector<std::array<Index, 3>> triangles;
  //! Per triangle, where it comes from: a cell key (a kept piece of M or a patch polygon in that cell),
  //! kFaceSource | face (a triangle of M re-fanned because an edge of it was split), or kIntact.
  std::vector<std::uint64_t> tri_source;
  static constexpr std::uint64_t kFaceSource = std::uint64_t(1) << 63, kIntact = ~std::uint64_t(0);
  std::vector<Index> kept_old;
  std::vector<PointKey> derived;
  std::size_t n_patch = 0;
  std::vector<Index> deleted_old;  //!< live vertices of M removed, by handle
  std::size_t faces_kept = 0;      //!< triangles of M kept intact
  std::size_t live_faces = 0;
  std::size_t n_kept() const { return kept_old.size(); }
  std::size_t n_derived() const { return derived.size(); }
};

//! Build the replaced surface for the complex cells `region` (sorted keys). Returns false with a reason
//! when the stitching meets an inconsistency (the caller grows the region and retries).
bool assemble(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
              const std::vector<std::uint64_t>& region, const openvdb::FloatGrid& theta, Assembly& out,
              std::string& why);

//! Pieces of M smaller than this (index space, voxels squared) are not kept next to a complex cell.
inline constexpr double kMinKeptPieceArea = 1e-6;

//! Add to `region` (sorted keys, kept sorted) every cell holding a piece smaller than kMinKeptPieceArea of a
//! face that reaches the region, until there is none: such a piece, where a mesh edge passes close to a
//! lattice line, would be kept as a sliver; replacing its cell too costs a few patch triangles. Returns the
//! number of cells added.
std::size_t absorb_sliver_pieces(const SurfaceMesh& mesh, const LatticeCut& cut, std::vector<std::uint64_t>& region);

//! Index-space area (voxels squared) below which a triangle of the replacement is a sliver.
inline constexpr double kMinTriangleArea = 2e-6;

//! Add to `region` (sorted keys, kept sorted) the cells whose triangles in `A` (built for `region`) are
//! slivers, smaller than kMinTriangleArea: the cell of a kept piece or of a patch polygon, every cell of a
//! re-fanned triangle of M. Where an edge or a face of M passes within a hair of a lattice line or node, the
//! corners of the pieces there nearly meet, and no triangulation of them avoids a sliver; replacing those
//! cells too (Wojtan et al. 2009 snap such near-coincident points instead) moves the patch boundary away.
//! Returns the number of cells added.
std::size_t absorb_sliver_triangles(const LatticeCut& cut, const Assembly& A,
                                    const openvdb::math::Transform& xform, std::vector<std::uint64_t>& region);

//! `region` grown by one layer of cells (26-neighbourhood).
std::vector<std::uint64_t> grow_region(const std::vector<std::uint64_t>& region);

}  // namespace topotrack::topology
