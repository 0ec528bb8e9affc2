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

//! `region` grown by one layer of cells (26-neighbourhood).
std::vector<std::uint64_t> grow_region(const std::vector<std::uint64_t>& region);

}  // namespace topotrack::topology
