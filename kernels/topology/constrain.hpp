#pragma once
//! ConstrainTopology(M, Θ) of §4.3: make the tracked mesh M take the topology of a voxelized implicit
//! surface Θ, after Wojtan et al. 2009 ("Deforming meshes that split and merge") as the paper generalises
//! it to any Θ. Called as ConstrainTopology(M, φ_M) (self-intersections become merges) and as
//! ConstrainTopology(M, φ_S) (M takes the target's topology: splits, merges, components appearing and
//! vanishing) in Algorithm 1, lines 9 and 11.
//!
//! Method.
//!  1. Cells are the cubes between Θ's voxel centres (the marching-cubes cells of kernels/sdf). M is cut
//!     exactly along the lattice planes into one convex piece per cell and triangle (lattice_cut.hpp).
//!  2. Each cell is classified in parallel (classify.hpp): it is complex unless M ∩ cell is a set of disks
//!     whose boundary loops run through the cube-edge crossings exactly like the marching-cubes polygons
//!     of Θ's corner signs.
//!  3. Replacement with exact cutting (our choice of stitching, instead of the subdivision stitching of
//!     Wojtan et al. 2010): the pieces of M in complex cells are removed, the pieces in the other cells kept.
//!     The cut boundary of the kept part lies on faces between a complex and a simple cell, and on each
//!     such face it is, by the simple cell's classification, a set of curves joining the same cube-edge
//!     crossings as the marching-cubes face segments of Θ. Each marching-cubes polygon of a complex cell
//!     uses M's own crossing point as its vertex on every lattice edge that touches a simple cell, and
//!     along a face shared with a simple cell it follows M's cut curve instead of the straight segment;
//!     polygons that picked up curve points are fanned from a new centroid vertex. The result is a
//!     closed, oriented 2-manifold by construction; it is checked (SurfaceMesh::from_triangles with
//!     require_closed, whose checks amount to validate(true)), and should a check ever fail the complex region is grown by one cell layer and the
//!     replacement redone, up to `max_region_growth` times. No slivers where avoidable: M's vertices are
//!     pushed kSnap voxels off the lattice planes before cutting, patch vertices stay kSnap off the lattice
//!     nodes, kept pieces are fanned from their widest corner, the cells of tiny kept pieces join the
//!     region (absorb_sliver_pieces), and so do the cells of any triangle of the result below
//!     kMinTriangleArea (absorb_sliver_triangles, up to three rounds; the last valid result is kept).
//!     Lattice nodes within kSignTolerance of Θ's zero set take the sign M's crossings imply (classify.hpp),
//!     so that the kSnap push never makes a well-represented cell complex, unless that would change Θ's
//!     topology (ConstrainParams::flips_keep_topology).
//!  4. Events (§4.4), in this order: the points where the cut subdivides kept triangles (edge splits and
//!     triangle subdivisions with exact interpolation weights); one PatchDelete per connected patch of
//!     removed vertices (backward rules by breadth-first march from the kept vertices around it, each
//!     vertex averaging its already-visited neighbours); one PatchCreate per connected patch of new
//!     vertices (forward rules by the same march from the kept vertices around it). A patch with no
//!     vertex around it (a component vanishing or appearing) gets its vertex sets and no rule.
//!
//! The mesh is rebuilt: it comes out compacted, vertex handles change, persistent ids of kept vertices
//! are kept and new vertices get fresh ids. Vertex properties of arithmetic type (float, double, integer)
//! are carried over with the same weights as the events; properties of other types are dropped. When no
//! cell is complex the mesh is not touched at all and no event is recorded.
#include <cstddef>
#include <openvdb/openvdb.h>

#include "io/event_list.hpp"
#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/topology/classify.hpp"

namespace topotrack {

struct ConstrainParams {
  // The cells are Θ's voxels: the voxel size (tied to the tracked mesh's target edge length) is chosen when
  // Θ is computed with signed_distance (kernels/sdf).
  bool record_events = true;   //!< append §4.4 events when an EventList is given
  int max_region_growth = 4;   //!< layers the complex region may grow by when a replacement check fails
  //! Fill ConstrainReport::components_before/after: a pass over the whole mesh each (about 4 ms at 100k
  //! vertices); the tracker does not need them.
  bool count_components = true;
  //! Lattice nodes within kSignTolerance of Θ's zero set take the sign M's crossings imply only where that
  //! keeps Θ's topology (classify.hpp): M then always comes out with the topology of Θ's marching-cubes
  //! surface. Off, they take it wherever the crossings agree, and across a gap or a sheet of Θ that close
  //! to a node M keeps its own topology.
  bool flips_keep_topology = true;
  //! When the cut of all of M would be large (its faces' boxes of cells hold more than this many cells), the
  //! complex cells are found in slabs, each cutting only the faces that reach it, and the replacement cuts
  //! only the faces around the complex region: far less memory (on the tracker's lattice of an eighth of an
  //! edge the cut of all of M was most of it). The cells are those of one pass, up to the signs that nodes
  //! near Θ's zero set take from M (classify.hpp), decided in sequence: on resurfaced pcow at L/4 the result
  //! differed from one pass in 9 of 40 frames (docs/results.md). 0: always one pass (the default).
  double max_cut_cells = 0;
};

struct ConstrainReport {
  std::size_t complex_cells = 0;     //!< cells replaced (after any growth)
  //! The examined cells by the verdict of the per-cell test (classify.hpp), before any growth: why M was
  //! resampled where it was (index: int(topology::CellVerdict); names: topology::verdict_name).
  topology::VerdictCounts cells_by_verdict{};
  std::size_t faces_removed = 0;     //!< triangles of M not kept intact
  std::size_t faces_added = 0;       //!< triangles of the result that are not triangles of M
  std::size_t vertices_removed = 0;  //!< vertices of M removed
  std::size_t vertices_added = 0;    //!< new vertices (cut points, patch vertices, centroids)
  std::size_t patches_created = 0, patches_deleted = 0;
  std::size_t bad_faces = 0;         //!< faces whose clipping fell back to whole-box replacement
  int region_growth = 0;             //!< layers the region grew by
  int components_before = 0, components_after = 0;  //!< 0 unless ConstrainParams::count_components
  int slabs = 0;            //!< slabs the complex cells were found in (0: one pass over all of M)
  int examined_growth = 0;  //!< times the replacement after slabs reached beyond the cells cut for it
  double seconds_cut = 0;       //!< cutting M by the lattice
  double seconds_index = 0;     //!< grouping the pieces by cell, Θ's sign-change cells (within seconds_classify)
  double seconds_classify = 0;  //!< cutting and classification
  double seconds_replace = 0;   //!< removal, marching-cubes patch, stitching, rebuild, sliver rounds:
  double seconds_assemble = 0;  //!<   assemble() over all attempts and sliver rounds
  double seconds_rebuild = 0;   //!<   SurfaceMesh::from_triangles (closed) over all attempts
  double seconds_slivers = 0;   //!<   absorb_sliver_pieces / absorb_sliver_triangles / grow_region
  int assemblies = 0;           //!<   replacements built (first, growths, sliver rounds)
  double seconds_components = 0;  //!< connected components before and after
  double seconds_events = 0;    //!< event and property propagation
  double seconds_total = 0;
};

//! ConstrainTopology(M, Θ) of §4.3; Θ is a narrow-band level set (negative inside), its voxel lattice the
//! cells. \pre mesh is a closed, consistently oriented 2-manifold (outward normals); Θ's transform is
//! linear (any voxel size) and every lattice edge along which it changes sign has an active end (true of a
//! distance whose band is wider than the cell diagonal, √3 voxels, on each side; the values need not be distances).
//! \throw InvalidInput on a non-finite or out-of-range coordinate or a non-linear transform;
//! TopologyError when the replacement still fails after max_region_growth growths.
ConstrainReport constrain_topology(SurfaceMesh& mesh, const openvdb::FloatGrid& theta, const ConstrainParams& params = {},
                                   EventList* events = nullptr);

}  // namespace topotrack
