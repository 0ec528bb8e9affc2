#pragma once
//! Components too small for the lattice (engine/tracker.cpp, after line 11 of Algorithm 1).
//!
//! ConstrainTopology (§4.3) sees the input only through φ_S at the lattice nodes: a droplet or a crumb thinner
//! than a voxel may change the sign of no node, and then M never gets it (the paper: such features are lost at
//! the grid's resolution). Resurfaced captures and fluid spray are full of them, and an output that drops them
//! is farther from its input than a voxel (a 2.5-voxel needle missing from a resurfaced pcow frame is a
//! Hausdorff distance of 1.85 % of the diagonal). This step makes M follow the input at the component level:
//! after ConstrainTopology(M, φ_S), every small component of S that no part of M comes near is copied into M (a
//! PatchCreate event, its new vertices' material from the closest point of M; one that a part of M comes near
//! only where its copy, or the copy moved up to twice `radius` away from M, touches no part of M and is not
//! inside it), and every small component of M that comes near no part of S is removed (a PatchDelete event).
//! Components of either larger than `max_extent` (bounding-box diagonal) are the lattice's business and are not
//! looked at. A copied component at most 2√2 L
//! across (L the target edge length) becomes an octahedron on its principal axes, the best-shaped mesh at that
//! resolution (ImproveMesh would collapse its triangles to a tetrahedron, often a flat one).
#include <cstddef>

#include "io/event_list.hpp"
#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

struct SmallComponentReport {
  std::size_t added = 0;    //!< components of S copied into M
  std::size_t removed = 0;  //!< components of M removed
};

//! `target` is the scene of S_n. `radius`: a component counts as present in the other surface when one of its
//! vertices lies within this distance of it (the tracker passes half a voxel).
//! M keeps its vertex order and ids; it is rebuilt only when something changes. Deterministic.
SmallComponentReport match_small_components(SurfaceMesh& mesh, const TargetSurface& target, double radius,
                                            double max_extent, double edge_length, EventList* events);

}  // namespace topotrack
