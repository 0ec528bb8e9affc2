#pragma once
//! Relaxation on the target (our addition to §4.2's fine stage, for large motion). Once the surface fits the
//! target, its rays no longer move the material along it: where the coarse stage laid a part slid or turned on
//! the target (a foot turned about its length, a body slid by a fraction of a node spacing), the fine stage's
//! normal rays keep it there. This stage slides the mesh along the target towards the source's shape: it
//! lowers the as-rigid-as-possible energy against the source (Sorkine & Alexa 2007: cotangent weights, one
//! rotation per vertex, local/global iterations) while a point-to-plane term keeps every vertex on the target's
//! tangent plane at its closest point, so that the vertices move along the surface, not off it:
//!   sum_ij w_ij |(x_i - x_j) - (R_i + R_j) / 2 (p_i - p_j)|^2 + lambda sum_i (<n_i, x_i - c_i>^2 + beta |x_i - c_i|^2)
//! (p: the source, x: the mesh, c_i, n_i: x_i's closest point on the target and its normal). A few iterations:
//! the motion it undoes is the slide the correspondences left, and converging to the least strained layout on
//! the target would also undo the stretch an elastic motion really has (pcow: docs/results.md). Each global step
//! is a few iterations of conjugate gradients, warm-started from x, with a two-level preconditioner: 3 x 3 block
//! Jacobi, and a coarse correction along the surface on the deformation graph of the rest shape (relax.cpp).
#include <span>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

struct RelaxParams {
  int iterations = 0;           //!< local/global iterations (0: no relaxation, the paper's and the tracker's)
  double plane_weight = 10;     //!< lambda, per vertex, relative to the mean edge weight
  double point_weight = 1e-3;   //!< beta: the point-to-point share of the fit (keeps the system definite)
  int cg_iterations = 5;        //!< conjugate-gradient iterations per global step
  //! A vertex farther than this from the target (a fraction of its bounding-box diagonal) has no fit term (align_fine
  //! passes its sigma, §4.2's 0.1).
  double max_distance = 0.1;
};

//! RelaxParams::iterations for `topotrack align` (use_large_motion_alignment). Measured (docs/results.md, 2026-12-07):
//! sums of the ground-truth error over frames k = 1, 3, 5, 7, 9 -> k + 15 at two re-samplings of the target, % of the
//! diagonal, without -> 10 iterations: elephant 8.147 -> 6.728, pcow 24.990 -> 20.967, samba 1.662 -> 1.243 (20: 6.432,
//! 21.088, 1.223, for twice the stage's time: 0.8-0.9 s at 47k vertices, 2.2 s at 98k on the 2-core bench host).
//! Point-to-plane weight 3 / 30 instead of 10: 6.618 / 7.008, 22.014 / 20.993, 1.344 / 1.232. With the vertices
//! numbered breadth-first (2026-12-08): 6.730, 20.957, 1.2433 and 0.80-0.92 s at 47k, 1.69-1.77 s at 98k.
inline constexpr int kLargeMotionRelaxIterations = 10;

struct RelaxReport {
  int iterations = 0;
  int cg_iterations = 0;           //!< summed over the global steps
  double energy_start = 0, energy_end = 0;  //!< the energy above at the first and the last step's correspondences
  std::size_t fitted = 0;          //!< vertices with a fit term in the last iteration
  double mean_distance = 0;        //!< their mean distance to the target before the last step / diagonal
  int coarse_nodes = 0;            //!< nodes of the preconditioner's coarse level
  double seconds_setup = 0, seconds_closest = 0, seconds_rotations = 0, seconds_solve = 0, seconds_total = 0;
};

//! Slide `mesh` along `target` towards the shape `rest` (positions by vertex handle index, the same connectivity:
//! the mesh before the alignment). Moves positions only. Deterministic for any thread count.
//! \throw InvalidInput on bad parameters or when rest does not match the mesh; SolverError if the factorisation fails.
RelaxReport relax_on_target(SurfaceMesh& mesh, std::span<const Vec3> rest, const TargetSurface& target,
                            const RelaxParams& params);

}  // namespace topotrack
