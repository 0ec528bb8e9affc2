#pragma once
//! The naive baseline of the paper's Fig. 9: move every vertex to its closest point on the target.
//! Severe tangential drift, kept for comparisons.
#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

//! Move each live vertex of `mesh` to its closest point on `target` (in parallel, deterministic).
void project_to_closest(SurfaceMesh& mesh, const TargetSurface& target);

}  // namespace topotrack
