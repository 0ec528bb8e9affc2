#pragma once
//! Filling the enclosed voids of a closed, embedded triangle mesh (a level set's zero set): every component
//! that lies inside another component is removed, so what is left bounds the solid seen from the outer
//! exterior (the region connected to infinity) and nothing of it is hollow.
//!
//! Why (our choice, not the paper's): resurfacing a self-intersecting capture (pcow of /work/shared/data)
//! can seal thin gaps between crossing sheets into inner cavities (every 10th frame at 128 voxels across:
//! frames 61, 71 and 81 had 1, 1 and 2); a captured body has none, and the tracker would carry each as a
//! separate inside-out component. (A plain cavity far from other surfaces never gets here: OpenVDB's
//! meshToVolume already signs what the exterior cannot reach as inside.) A cavity's wall is
//! the component seen inside out (negative signed volume); a speck floating in a cavity is inside one too.
#include "io/mesh_data.hpp"

namespace topotrack {

struct FillVoidsReport {
  std::size_t components = 0;          //!< of the input
  std::size_t voids_filled = 0;        //!< removed components oriented inside out (cavity walls)
  std::size_t islands_removed = 0;     //!< removed components oriented outward (bodies inside a cavity)
  std::size_t vertices_removed = 0, triangles_removed = 0;
};

//! The mesh without its enclosed components (the remaining vertices in their order, the remaining
//! triangles in their order, ids and attributes kept). Components are the sets of triangles connected
//! through shared vertices; component A is enclosed by B when the generalized winding number of B at a
//! vertex of A has magnitude above 1/2. Deterministic, parallel over the enclosing components.
//! \pre `mesh` is closed and its components do not intersect each other (marching cubes output is).
//! \throw InvalidInput on an index out of range or a non-finite coordinate.
MeshData fill_voids(const MeshData& mesh, FillVoidsReport* report = nullptr);

}  // namespace topotrack
