#pragma once
//! Marching cubes over an OpenVDB level set whose output is always a closed, consistently oriented
//! 2-manifold without duplicate edges or degenerate (repeated-vertex) faces (§4.3: the topology change
//! of Wojtan et al. 2009 replaces mesh triangles with these, cell by cell).
//!
//! Cells are the cubes whose 8 corners are voxel centres; cell (i, j, k) has its minimum corner at voxel
//! (i, j, k). Cube conventions and the polygon table: kernels/sdf/cube_table.hpp. A voxel is inside when
//! its value is < iso. Inactive voxels and tiles take part with their (background) value, so the sign
//! outside the band is the side the background says and cells at the band border leave no holes.
//!
//! Vertices: one per crossed lattice edge, by linear interpolation of the two voxel values (the
//! parameter clamped to [1e-3, 1 - 1e-3] so that no two vertices coincide), plus one centroid vertex
//! per polygon with five or more corners. Triangulation, and why it creates no duplicate edge:
//!  - an edge between two lattice-edge vertices on a common cube face is only ever a face segment;
//!    the two cells sharing that face make the same segment (the table's face rule reads the face's
//!    four signs only), so each segment is used by exactly two triangles;
//!  - a quad is split along a diagonal whose two lattice edges share no cube face: such a pair of
//!    lattice edges belongs to exactly one cell and, in that cell, to this one polygon, so the diagonal
//!    cannot appear anywhere else (the shorter admissible diagonal is taken; a quad without one is
//!    treated like a larger polygon);
//!  - larger polygons are fanned from a new centroid vertex, whose edges are new.
//! Every crossed lattice edge lies in four cells and is a corner of exactly one polygon in each, and those
//! four polygons close up around it: the output is a closed 2-manifold.
//!
//! Output order is deterministic (bit-identical for any thread count): lattice-edge vertices sorted by
//! lattice edge (x, then y, then z, then axis), then centroids cell by cell; triangles cell by cell in
//! the order the cells are visited (VDB leaf order, then voxel order within a leaf).
#include <cstdint>
#include <openvdb/openvdb.h>
#include <span>
#include <vector>

#include "io/mesh_data.hpp"
#include "kernels/sdf/cube_table.hpp"

namespace topotrack {

//! A lattice edge: from voxel `origin` one step along `axis` (0 = x, 1 = y, 2 = z).
struct LatticeEdge {
  openvdb::Coord origin;
  int axis = 0;
  bool operator==(const LatticeEdge&) const = default;
};
//! Lattice edges packed into 62 bits (coordinates in [-2^19, 2^19), 20 bits each, then the axis).
//! Key order is x, y, z, axis. \throw InvalidInput when a coordinate is out of that range.
std::uint64_t lattice_edge_key(const LatticeEdge& e);
LatticeEdge lattice_edge_from_key(std::uint64_t key);
//! The lattice edge of cube edge `cube_edge` of the cell with minimum corner `cell`.
LatticeEdge cell_edge(const openvdb::Coord& cell, int cube_edge);

//! The 8 corner values of a cell (corner c at cell + (c & 1, (c >> 1) & 1, (c >> 2) & 1)).
std::array<float, 8> cell_values(const openvdb::FloatGrid& grid, const openvdb::Coord& cell);
//! Bit c set when values[c] < iso.
std::uint8_t inside_mask(const std::array<float, 8>& values, double iso = 0);
//! The surface point on a crossed lattice edge in index space: origin + t * e_axis with
//! t = (iso - v0) / (v1 - v0) clamped to [1e-3, 1 - 1e-3] (v0, v1 the values at origin and origin + e_axis).
openvdb::Vec3d edge_point_index(const LatticeEdge& e, double v0, double v1, double iso);

//! The whole zero (iso) surface of `grid`: every cell with at least one active corner voxel
//! (active tiles are ignored, as in any narrow-band level set). World-space positions, no ids.
//! \throw InvalidInput on a non-finite voxel value in a visited cell or coordinates out of the key range.
MeshData marching_cubes(const openvdb::FloatGrid& grid, double iso = 0);

//! Marching cubes restricted to some cells (e.g. the topologically complex cells of §4.3). The result has
//! boundaries where the cell set ends; along them it joins exactly the triangles marching_cubes makes in
//! the neighbouring cells (same lattice-edge vertices, same face segments).
struct CellMesh {
  MeshData mesh;
  //! Per output vertex: lattice_edge_key of its lattice edge, or kCentroidVertex for a polygon centroid.
  std::vector<std::uint64_t> vertex_keys;
  //! Per output triangle: the index into `cells` of the cell it came from.
  std::vector<std::uint32_t> triangle_cells;
  static constexpr std::uint64_t kCentroidVertex = ~std::uint64_t(0);
};
//! \pre the cells are distinct (a repeated cell repeats its triangles). \throw InvalidInput as above.
CellMesh marching_cubes_cells(const openvdb::FloatGrid& grid, std::span<const openvdb::Coord> cells, double iso = 0);

}  // namespace topotrack
