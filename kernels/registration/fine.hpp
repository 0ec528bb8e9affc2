#pragma once
//! Fine linear alignment (§4.2): for each vertex an undirected ray along its normal onto the target
//! (nearest hit either way), pruned beyond sigma times the scene's bounding-box diagonal; per-vertex
//! displacements d minimise  sum_i |x_i + d_i - c_i|^2 + sum_edges |d_i - d_j|^2, solved by conjugate
//! gradients (Jacobi preconditioner, warm start from the raw correspondence displacements). Optionally
//! (FineParams::normal_displacement) the displacements are scalars along the vertex normals.
#include <cstddef>

#include <span>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"
#include "kernels/registration/relax.hpp"

namespace topotrack {

struct FineParams {
  double sigma = 0.1;                  //!< pruning distance, fraction of the scene's bbox diagonal (§4.2)
  double max_normal_angle_deg = 180;   //!< optional normal pruning (the paper prunes by sigma only: off)
  double fit_weight = 1;               //!< weight of E_fit (§4.2: 1)
  double smooth_weight = 1;            //!< weight of E_reg (§4.2: 1)
  int max_cg_iterations = 500;
  double tolerance = 1e-8;             //!< relative residual |r| / |rhs| at which CG stops
  int rounds = 1;                      //!< ray casting + solve rounds (the paper: one)
  //! Further rounds (our addition, for large motion): after `rounds`, another round (up to `max_rounds` in all)
  //! while the mean distance of the matched vertices from their correspondences after a round's step exceeds
  //! `more_rounds_residual` times the scene's bounding-box diagonal: where the smoothness term held them back
  //! from targets far apart, the next rays, cast from nearer, ask for less. No extra work when it does not.
  //! 1 (the paper's single round) by default; `topotrack align` takes kLargeMotionFineRounds.
  int max_rounds = 1;
  double more_rounds_residual = 5e-4;
  //! CG tolerance of those further rounds: an inexact step that the next rays correct (1e-8 as in the first
  //! round: the same distances to the target, twice the solve time).
  double more_rounds_tolerance = 1e-2;
  //! Scalar displacements along the vertex normals, d_i = t_i n_i, with E_reg = sum_edges (t_i - t_j)^2
  //! (the paper writes E_reg with |d_i - d_j|; off: vector d_i, the default). Every c_i lies on x_i's normal
  //! ray, so E_fit asks for no tangential motion; with vector d_i the smoothness term averages neighbours'
  //! differently oriented displacements and slides vertices along the surface, which the scalar form cannot.
  //! Measured, two runs each: `gen blobs` (100 frames) drift 0.019 / 0.021 -> 0.013 / 0.016 %; resurfaced
  //! samba and pcow (40 frames) unchanged within run-to-run noise; same speed (108k vertices).
  bool normal_displacement = false;
  //! After the rounds, the relaxation on the target (relax.hpp) towards the rest shape given to align_fine; off
  //! (0 iterations) by default and in the tracker; `topotrack align` takes kLargeMotionRelaxIterations.
  RelaxParams relax;
};

//! FineParams::max_rounds for large motion (`topotrack align`, unless --no-large-motion). Measured, frame 1 -> 16,
//! the run of median ground-truth error over five re-samplings of the target (docs/results.md, 2026-12-01; before
//! the intrinsic matches, with which the elephant takes 4-6 rounds),
//! distance to the target in % of the diagonal, one round -> up to 8: pcow 0.29 -> 0.045 (8 rounds; 0.045-0.079
//! over the five), elephant 0.13 -> 0.036 (6; 0.036-0.060), samba 0.021 (one round: its residual is 0.025 %); the
//! ground-truth error pcow 3.50 -> 3.47, elephant 3.40 -> 3.42; bench/registration gap 15 (the elephant at 47k and
//! 98k vertices): 1.35 -> 1.63 s and 3.38 -> 3.73 s. Not in the tracker: between consecutive frames the first
//! round leaves 0.003-0.15 %, and the further rounds, where they ran, took resurfaced pcow's final drift (capture
//! profile) from 1.89 to 2.01 % and gave a metaballs frame 1.15 % Hausdorff distance and a triangle below 2°.
inline constexpr int kLargeMotionFineRounds = 8;

struct FineReport {
  int cg_iterations = 0;               //!< summed over rounds (the coordinates are solved together)
  int rounds = 0;                      //!< rounds run
  double mean_residual = 0;            //!< mean |x_i - c_i| over the matched after the last step / scene diagonal
  std::size_t correspondences = 0, pruned = 0;  //!< in the last round
  double residual = 0;                 //!< final relative CG residual (largest over the coordinates)
  double energy_start = 0, energy_end = 0;      //!< E_tot at d = 0 and at the solution, last round
  double seconds_raycast = 0, seconds_assembly = 0, seconds_solve = 0, seconds_total = 0;
  RelaxReport relax;  //!< FineParams::relax (within seconds_total)
};

//! Displace the vertices of `mesh` onto `target` (§4.2, fine stage). Moves positions only; a vertex
//! without a correspondence follows its neighbours; a component without any correspondence stays.
//! Deterministic for any thread count. `rest`: the mesh's shape before the alignment (positions by vertex handle
//! index), which FineParams::relax slides it towards; without it (empty) there is no relaxation.
//! \throw InvalidInput on bad parameters.
FineReport align_fine(SurfaceMesh& mesh, const TargetSurface& target, const FineParams& params = {},
                      std::span<const Vec3> rest = {});

}  // namespace topotrack
