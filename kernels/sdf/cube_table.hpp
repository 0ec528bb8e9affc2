#pragma once
//! Marching-cubes cell conventions and the polygon table (§4.3; Wojtan et al. 2009 classify and
//! re-mesh cell by cell with it).
//!
//! Corners: corner c sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1) from the cell's minimum corner.
//! Edges:   edge e = 4 * axis + k runs along `axis` (0 = x, 1 = y, 2 = z); with (u, v) the two other
//!          axes in increasing order, k = bit_u + 2 * bit_v gives the edge's offsets along u and v.
//!          Endpoint 0 has the axis bit 0, endpoint 1 the axis bit 1:
//!            0: 0-1   1: 2-3   2: 4-5   3: 6-7     (x edges)
//!            4: 0-2   5: 1-3   6: 4-6   7: 5-7     (y edges)
//!            8: 0-4   9: 1-5  10: 2-6  11: 3-7     (z edges)
//! Faces:   face f = 2 * axis + side is the face where the corners' `axis` bit equals `side`:
//!          0: x=0  1: x=1  2: y=0  3: y=1  4: z=0  5: z=1.
//!
//! Polygons: the surface inside a cell is a set of disjoint cycles through the crossed edges (edges whose
//! two corners have different signs). They are built face by face: on each face the crossed edges are
//! joined by segments, and on an ambiguous face (two diagonal corners inside, two outside) each inside
//! corner is cut off on its own ("inside separated"). The rule reads only the four signs of that face, so
//! the two cells sharing a face always make the same segments there, and every crossed lattice edge is
//! used by exactly one polygon of each of its four cells: the union over cells is a closed 2-manifold.
//! Cycles are oriented counter-clockwise seen from outside, i.e. their normal points towards increasing
//! values (out of the inside region).
#include <array>
#include <cstdint>
#include <span>

namespace topotrack::cube {

inline constexpr int kCorners = 8, kEdges = 12, kFaces = 6;

//! Offset of corner c along axis a (0 or 1).
constexpr int corner_bit(int c, int a) { return (c >> a) & 1; }
//! The axis an edge runs along.
constexpr int edge_axis(int e) { return e >> 2; }
//! Endpoint i (0 = lower along the axis, 1 = upper) of edge e.
int edge_corner(int e, int i);
//! The two faces that contain edge e.
std::array<int, 2> edge_faces(int e);
//! The four corners of face f in cyclic order (counter-clockwise seen from outside the cell).
std::array<int, 4> face_corners(int f);
//! The four edges of face f in cyclic order: edge i joins face_corners(f)[i] and [i + 1].
std::array<int, 4> face_edges(int f);
//! The face across which the neighbouring cell lies: the opposite face index in that cell.
constexpr int opposite_face(int f) { return f ^ 1; }
//! Whether two distinct edges lie on a common face.
bool edges_share_face(int e0, int e1);

//! The polygons of one sign configuration.
struct CubePolygons {
  std::uint8_t count = 0;                 //!< number of polygons (0..4)
  std::array<std::uint8_t, 5> offset{};   //!< polygon p is edges[offset[p] .. offset[p+1])
  std::array<std::uint8_t, 12> edges{};   //!< cube-edge indices of the polygons' corners, in cycle order
  //! Bit p set: for the quad p, the diagonal between its corners 0 and 2 joins two edges without a common
  //! face (so it can never duplicate an edge of another cell); bit p + 4: the same for corners 1 and 3.
  std::uint8_t quad_diagonals = 0;

  std::span<const std::uint8_t> polygon(int p) const {
    return {edges.data() + offset[p], std::size_t(offset[p + 1] - offset[p])};
  }
  int size(int p) const { return offset[p + 1] - offset[p]; }
};

//! The polygons for `inside_mask` (bit c set = corner c inside, value < iso). A pure function of the
//! mask; the table is generated from the face rule above at first use.
const CubePolygons& cube_polygons(std::uint8_t inside_mask);

//! The segments of face f for this mask as directed pairs of edge indices (from, to), in the
//! polygons' cycle direction: 0, 1 or 2 segments. The cell on the other side of the face has the same
//! segments in the opposite direction.
int face_segments(std::uint8_t inside_mask, int f, std::array<std::array<int, 2>, 2>& out);

}  // namespace topotrack::cube
