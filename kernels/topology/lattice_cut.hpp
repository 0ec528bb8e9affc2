#pragma once
//! The tracked mesh M cut into pieces by the cells of a voxel lattice (§4.3, after Wojtan et al. 2009):
//! every triangle is clipped by the lattice planes x = i, y = j, z = k (index space) into convex
//! polygons, one per cell it passes through. ConstrainTopology classifies each cell from its pieces and
//! keeps the pieces of the cells that are not topologically complex.
//!
//! Robustness without tolerances: each point of the subdivision is named by what it is made of (a mesh
//! vertex; a mesh edge crossing a plane; a mesh face crossing a lattice line), so the triangles sharing
//! it agree on it exactly. Planes are applied in a fixed order (all x, then all y, then all z), and the
//! side of a point is decided once, from one canonical position, by `coordinate >= plane`. The cut works
//! on a copy of M translated by kShift (index space, about 1e-4 voxel, different per axis): meshes made
//! by marching cubes on the same lattice (vertices on lattice lines, edges in lattice planes) and
//! symmetric meshes (edges through lattice lines) are then in general position. Cut points are mapped
//! back by the same translation, so they lie exactly on M's edges and faces.
#include <array>
#include <cstdint>
#include <openvdb/openvdb.h>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/topology/huge_pages.hpp"

namespace topotrack::topology {

//! The translation of the working copy, in voxels.
inline constexpr double kShift[3] = {1.0e-4, 1.37e-4, 1.71e-4};
//! Vertices of the working copy closer than 2 kSnap (in voxels) to a lattice plane are pushed away from it,
//! on their own side, by the map d -> kSnap + d / 2 of their distance d: the cut then never leaves a piece
//! thinner than kSnap next to a vertex (Wojtan et al. 2009 push nearly-zero lattice values off zero for the
//! same reason). The map is increasing along each axis, so no two vertices meet, and no vertex changes side:
//! which mesh edges cross which planes does not change. The moved positions are used for the output only
//! where the cut re-triangulates (the kept pieces around complex cells): a move of at most kSnap voxels.
inline constexpr double kSnap = 1.0e-2;

//! A point of the subdivision. Ordered, so it can be sorted and searched.
struct PointKey {
  std::uint64_t a = 0, b = 0;
  auto operator<=>(const PointKey&) const = default;
};
enum class PointKind : std::uint8_t { Vertex = 0, EdgePoint = 1, FacePoint = 2, Other = 3 };

PointKey vertex_key(Index v);
//! Mesh edge `edge` crossing the plane `axis` = `plane`.
PointKey edge_point_key(Index edge, int axis, int plane);
//! Mesh face `face` crossing the lattice line along `line_axis` at planes (u, v) of the two other axes
//! (in increasing axis order).
PointKey face_point_key(Index face, int line_axis, int plane_u, int plane_v);
//! Keys of kind Other: the caller's own points (centroids, lattice-edge vertices).
PointKey other_key(std::uint64_t a, std::uint64_t b);

inline PointKind kind(const PointKey& k) { return PointKind(k.a >> 62); }
inline Index key_element(const PointKey& k) { return Index(k.a & 0xffffffffu); }  //!< vertex, edge or face
inline int key_axis(const PointKey& k) { return int((k.a >> 60) & 3u); }           //!< plane / line axis
inline int key_plane(const PointKey& k) { return int(std::int64_t(k.b) - (std::int64_t(1) << 31)); }
inline int key_plane_u(const PointKey& k) { return int(std::int64_t(k.b >> 32) - (std::int64_t(1) << 31)); }
inline int key_plane_v(const PointKey& k) { return int(std::int64_t(k.b & 0xffffffffu) - (std::int64_t(1) << 31)); }

struct PointKeyHash {
  std::size_t operator()(const PointKey& k) const {
    std::uint64_t h = k.a * 0x9E3779B97F4A7C15ull ^ (k.b + 0x632BE59BD9B4E019ull + (k.a << 6) + (k.a >> 2));
    h ^= h >> 31;
    h *= 0xBF58476D1CE4E5B9ull;
    return std::size_t(h ^ (h >> 29));
  }
};

//! Cells packed in 63 bits (21 bits per coordinate, range [-2^20, 2^20)); key order is x, y, z.
std::uint64_t cell_key(const openvdb::Coord& c);
openvdb::Coord cell_from_key(std::uint64_t key);
inline constexpr int kCellRange = 1 << 20;

inline constexpr std::uint8_t kOnMeshEdge = 0xff;

//! One convex piece: the part of mesh face `face` inside cell `cell`.
struct Piece {
  std::uint64_t cell = 0;
  Index face = 0;
  std::uint32_t begin = 0;  //!< its corners are keys[begin, begin + size), counter-clockwise like the face
  std::uint8_t size = 0;
};

//! M cut by the lattice.
struct LatticeCut {
  std::vector<Vec3> P;             //!< index-space vertex positions plus kShift, snapped (per vertex handle)
  std::vector<std::uint8_t> snapped;  //!< per vertex handle: P was moved off a plane (see kSnap)
  HugeVector<Piece> pieces;        //!< in face order; the pieces of a face are contiguous
  std::vector<std::uint32_t> face_pieces;  //!< face f has pieces [face_pieces[f], face_pieces[f+1])
  std::vector<std::array<Index, 3>> face_vertices;  //!< per live face: SurfaceMesh::vertices, as indices
  //! Corners of the pieces (piece p's are keys[p.begin, p.begin + p.size)); between the corners of consecutive
  //! chunks of faces there may be unused entries.
  HugeVector<PointKey> keys;
  //! Per piece edge (corner i to i+1): the cube face of the piece's cell it lies on (2 * axis + side),
  //! or kOnMeshEdge when it is part of a mesh edge. Indexed like keys.
  HugeVector<std::uint8_t> tags;
  //! Faces whose clipping met a configuration that rounding made inconsistent (never seen in practice;
  //! kept as a fallback): they have no pieces, and every cell of their bounding box is complex.
  std::vector<Index> bad_faces;
  std::vector<std::array<openvdb::Coord, 2>> bad_boxes;  //!< min and max cell of each bad face
};

//! Cut the live faces of `mesh` by the lattice of `xform` (index space: voxel centres at integers,
//! cells between them). Deterministic and parallel over fixed chunks of faces. With `only`, a face is cut
//! only when the box of cells it spans holds an active voxel of `only` (a cell, keyed by its minimum corner,
//! like Θ's voxels): the others get no pieces, as if whole (a local ConstrainTopology, constrain.hpp).
//! \throw InvalidInput on a non-finite coordinate or a mesh beyond the cell key range.
LatticeCut cut_by_lattice(const SurfaceMesh& mesh, const openvdb::math::Transform& xform,
                          const openvdb::MaskGrid* only = nullptr);

//! Whether the box of cells [lo, hi] (inclusive) holds an active voxel or tile of `cells`: by leaf node, so
//! a box far from every active voxel costs a few lookups.
bool box_touches(const openvdb::MaskTree& cells, const openvdb::Coord& lo, const openvdb::Coord& hi);

//! The canonical position (index space plus kShift, like LatticeCut::P) of a subdivision point (kinds Vertex, EdgePoint, FacePoint), and
//! its weights over mesh vertices: one vertex; the two edge ends (vertex(e,0), vertex(e,1)); the three
//! face corners (in SurfaceMesh::vertices order).
struct PointWeights {
  int n = 0;
  std::array<Vertex, 3> v;
  std::array<double, 3> w{};
};
Vec3 point_position(const SurfaceMesh& mesh, const std::vector<Vec3>& P, const PointKey& key,
                    PointWeights* weights = nullptr);
//! The same, with the corners of a FacePoint's face taken from cut.face_vertices instead of the mesh: the
//! same arithmetic (bit-identical), fewer scattered reads.
Vec3 point_position(const SurfaceMesh& mesh, const LatticeCut& cut, const PointKey& key);
//! World position of a point given in the cut's frame (index space plus kShift).
Vec3 cut_to_world(const openvdb::math::Transform& xform, const Vec3& p);

}  // namespace topotrack::topology
