#pragma once
//! Coarse non-linear alignment (§4.2, adapting Li et al. 2009): an embedded deformation graph whose
//! nodes carry affine transforms (A_j, b_j), skinned to the vertices; correspondences from each node
//! along its normal onto the target, pruned by normal angle and closest-point ratio; the energy
//!   alpha_fit (alpha_point |x - c|^2 + alpha_plane <n, x - c>^2) + alpha_reg (E_rigid + 0.1 E_smooth)
//! minimised by Gauss–Newton with a sparse Cholesky whose symbolic analysis is reused, alternating
//! with the correspondence search; alpha_reg starts at 1000 and is divided by 10 whenever converged.
//! Lengths are measured relative to the scene's bounding-box diagonal (the paper assumes a diagonal of 1).
//! For large motion (our addition, gated by the measured misfit so that close frames keep the paper's
//! scheme): a global rigid pre-alignment (rigid_icp.hpp), a first pass on a lower-density graph,
//! backward (target -> node) matches added to the fitting term, and (when asked for, as `topotrack align`
//! does) intrinsic matches for the nodes laid on the wrong part (intrinsic_matches.hpp).
#include <functional>
#include <span>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"
#include "kernels/registration/correspondences.hpp"
#include "kernels/registration/intrinsic_matches.hpp"
#include "kernels/registration/rigid_icp.hpp"
#include "kernels/registration/sparse_cholesky.hpp"

namespace topotrack {

//! How each Gauss–Newton system is solved. Direct: sparse Cholesky of the full 12N x 12N matrix.
//! SeparablePCG: conjugate gradients on the same system to `pcg_tolerance`, preconditioned by a
//! sparse Cholesky of its 4N x 4N per-coordinate part (smoothness, point-to-point, coordinate-averaged
//! rigidity and point-to-plane: exact but for the within-node coupling of x, y, z), factored once per
//! alpha_reg level by BlockCholesky (4 x 4 node blocks, one triangular solve for x, y and z): 27x fewer
//! factorisation flops, same solution to the tolerance. The coupling within a node is handled by a
//! symmetric multiplicative two-level preconditioner (node-block Jacobi around the per-coordinate
//! Cholesky correction); the 12N matrix is applied node by node without storing its off-diagonal blocks.
enum class CoarseLinearSolver { Direct, SeparablePCG };

//! Where align_coarse is when CoarseParams::observer is called.
enum class CoarseStage {
  Prealigned,       //!< after the rigid pre-alignment (only when it ran)
  LowDensityLevel,  //!< after an alpha_reg level of the low-density pass
  Level,            //!< after an alpha_reg level of the full graph
  DenseLevel,       //!< after the level of the denser graph (CoarseParams::dense_spacing_factor)
};

//! A snapshot for diagnostics: the mesh's vertex positions (by handle index) at the end of a stage.
struct CoarseSnapshot {
  CoarseStage stage = CoarseStage::Level;
  double alpha_reg = 0;  //!< the level's (0 for Prealigned)
  int rounds = 0;        //!< rounds of the level
  double fit_distance = 0;  //!< mean node-to-correspondence distance after the level, in mean edge lengths
  std::span<const Vec3> positions;
};

//! What CoarseParams::match_override is told of a round.
struct CoarseMatchRound {
  CoarseStage stage = CoarseStage::Level;  //!< LowDensityLevel or Level
  int level = 1;                           //!< alpha_reg level of the stage, from 1
  std::span<const Vertex> nodes;           //!< the mesh vertex of each node
};

struct CoarseParams {
  double node_spacing_factor = 4;  //!< node spacing in mean edge lengths of the mesh (§4.2)
  //! A graph of at least `min_nodes` nodes at full density (our addition; 0: the paper's spacing whatever the mesh's
  //! size, the library's and the tracker's default): on a mesh of few vertices four mean edge lengths give too few
  //! nodes for the shape's parts, so the spacing shrinks (the low-density pass's with it) to
  //! node_spacing_factor * sqrt(nodes / min_nodes) mean edge lengths, never below `min_node_spacing_factor`.
  //! `topotrack align` takes kLargeMotionMinNodes. CoarseReport::node_spacing reports the spacing used.
  int min_nodes = 0;
  double min_node_spacing_factor = 2.5;
  int k = 4;                       //!< nodes per vertex (§4.2)
  double alpha_point = 0.1;        //!< point-to-point weight (§4.2)
  double alpha_plane = 1;          //!< point-to-plane weight (§4.2)
  double alpha_fit = 0.1;          //!< fitting weight (§4.2)
  double alpha_reg_start = 1000;   //!< initial regularisation weight (§4.2)
  double alpha_reg_min = 0.1;      //!< stop once alpha_reg would drop below this (the paper leaves it open)
  double smooth_weight = 0.1;      //!< E_smooth relative to E_rigid (§4.2)
  double max_normal_angle_deg = 60;  //!< correspondence pruning (§4.2)
  double max_closest_ratio = 3;      //!< correspondence pruning (§4.2)
  int max_iterations = 40;           //!< cap on correspondence + Gauss–Newton rounds in total
  //! Cap on rounds at one alpha_reg. The paper alternates "until convergence": large motion gains from
  //! more (pcow 1 -> 16: 16.5% ground-truth error with 8, 9.0% with 30 and max_iterations 100), but
  //! consecutive blobs frames then crawl for 24 rounds at alpha_reg 1000 (measured), so 8 stays.
  int max_iterations_per_level = 8;
  //! A level has converged (alpha_reg is relaxed) when a round lowers the energy by less than this
  //! fraction, or moves no node by more than `step_tolerance` mean edge lengths (our addition: the
  //! paper leaves "convergence" open; an absolute test keeps near-aligned frames from spending
  //! rounds on noise-level relative decreases).
  double convergence_tolerance = 2e-3;
  //! Node motion of a round (|db_j| + spacing |dA_j|_F) below which it has converged, in mean edge lengths.
  //! With retract_rotations the rounds converge geometrically (motion / 3 per round) instead of
  //! crawling, and the last ones set the tangential accuracy: blobs tracker (100 frames, default
  //! resolution) final drift 0.075% of the diagonal with 0.01, 0.035% with 0.003, 0.019% with 0.001
  //! (0.026% before the retraction, with 0.01); samba, pcow, elephant 1 -> 16 unchanged.
  double step_tolerance = 0.001;
  //! A level has also converged when the largest node motion of a round is below this fraction of the
  //! mean node-to-correspondence distance after it (our addition): the regularisation holds the nodes
  //! back and further rounds at this alpha_reg only crawl (consecutive blobs frames: 8 rounds at
  //! alpha_reg 100, each moving 0.5 of 3 edge lengths). Measured with 0.25: samba, pcow, elephant 1 -> 16
  //! unchanged (pcow 19 rounds instead of 25); blobs tracker 20 frames 15.9 rounds/frame instead of 19.4,
  //! new vertices 0.65 vs 0.68 %/frame, but final drift 0.042 vs 0.032 % of the diagonal: off by default.
  double stall_ratio = 0;
  //! Stop relaxing alpha_reg once a level has converged with the mean node-to-correspondence distance
  //! below this many mean edge lengths (our addition): with the fit residual (hence its gradient) at
  //! zero a lower alpha_reg has nothing left to fit. 0 always runs down to alpha_reg_min.
  double fit_tolerance = 0.05;
  //! Before completing the graph (the k-nearest-node search, the system's pattern and ordering), find
  //! the correspondences of its nodes once: when their mean distance is already below
  //! `fit_tolerance`, the stage has converged before its first step and ends with no round (our
  //! addition: the same test that ends the schedule after a round). This is the common case of the
  //! full-density graph after the low-density pass between consecutive frames, whose one round at
  //! alpha_reg 1000 then moved the nodes by 0.002 mean edge lengths (blobs at 100k vertices).
  bool check_fit_first = true;
  //! The mean distance, in mean edge lengths, below which check_fit_first finds the nodes fitted (0: fit_tolerance).
  //! `topotrack align` ends its schedule at a lower fit_tolerance (kLargeMotionFitTolerance) but keeps 0.05 here:
  //! with 0.02 samba's consecutive frames 1 -> 2 took 25 rounds instead of none, for 0.0562 % ground-truth error
  //! instead of 0.0549 %.
  double check_fit_first_tolerance = 0;
  //! Node density relative to the paper's (1, 0.5, 0.25: the paper's fast preview); spacing / sqrt(density).
  double graph_density = 1;
  //! Levenberg–Marquardt damping of the step (relative units): keeps the system positive definite
  //! where a component has no correspondence at all.
  double damping = 1e-6;
  CholeskyBackend solver = kDefaultCholeskyBackend;  //!< Direct only (SeparablePCG: BlockCholesky)
  CoarseLinearSolver linear_solver = CoarseLinearSolver::SeparablePCG;  //!< measured faster (bench)
  //! Relative residual of the Gauss–Newton system (SeparablePCG): an inexact Newton step, 1e-3 gives
  //! the same alignment as 1e-4 with a third fewer PCG iterations (measured on samba and pcow).
  double pcg_tolerance = 1e-3;
  //! Cap on PCG iterations per round: an inexact Newton step. Only the first rounds at alpha_reg 1000
  //! and 100 need more (30-47); the correspondence rounds that follow make up for it. Measured against
  //! 100 (bench/registration, blobs tracker): 24% less coarse time per blobs frame with drift 0.302% vs
  //! 0.320% of the diagonal; large motion 3x faster on elephant, same or lower ground-truth error.
  int max_pcg_iterations = 15;
  //! The PCG preconditioner's coarse correction by the per-coordinate Cholesky factor (SeparablePCG); off: block
  //! Jacobi alone, no factorisation (the denser graph's, below).
  bool pcg_coarse_correction = true;
  //! Take the rotational part of each node's Gauss–Newton step along a rotation (a retraction: the
  //! step is the same to first order) rather than along the straight line A + t dA, whose departure
  //! from orthogonality the rigidity term penalises quadratically (our addition; the energy, weights and
  //! schedule are the paper's). Without it consecutive blobs frames (a 3.6 degree turn) crawl at
  //! alpha_reg 1000, the step halved to 1/16 in every round.
  bool retract_rotations = true;
  bool refactor_each_round = false;  //!< SeparablePCG: refresh the preconditioner every round, not per level
  //! Large motion (our addition, see rigid_icp.hpp): when the trimmed mean closest-point distance of
  //! the mesh to the target exceeds this fraction of the target's bounding-box diagonal, the mesh is
  //! first moved by a global trimmed rigid ICP; 0 disables it. Measured misfit (frame 1 -> 16,
  //! resampled target): pcow 5.1%, elephant 0.57%, samba 0.1%; consecutive blobs frames in the
  //! tracker 2.0%. Pre-aligned, pcow's ground-truth error drops from 15.3% to 9.1% of the diagonal,
  //! elephant's from 5.07% to 5.03% (not worth its 30% more coarse time); the blobs tracker with a
  //! threshold of 2 edge lengths (so pre-aligned every frame) needed 2.4 instead of 19.4 rounds per
  //! frame but drifted 0.104% instead of 0.032% of the diagonal (rigid ICP slides tangentially on
  //! smooth shapes), hence a threshold well above consecutive-frame motion.
  double prealign_misfit = 0.035;
  RigidIcpParams prealign;
  //! Large motion (our addition): the first this many alpha_reg levels match each node to its closest
  //! point on the target (normal test kept) instead of casting along its normal; only when the
  //! misfit exceeds `prealign_misfit` (consecutive frames keep the paper's normal rays). Measured
  //! with 2 after the pre-alignment: pcow 9.04% -> 8.95%, elephant (pre-aligned) 5.01% -> 5.25%
  //! (5 levels: 5.60%): off by default.
  int closest_point_levels = 0;
  //! Large motion (our addition, §4.2's coarse-to-fine in spirit): when the misfit (see
  //! prealign_misfit) exceeds `coarse_pass_misfit`, a first pass of the whole alpha_reg schedule runs
  //! on a graph of `coarse_pass_density` times the node density, down to `coarse_pass_alpha_reg_min`,
  //! and the full graph then starts from its result (its rest state: the deformed mesh) with at most
  //! `max_iterations_per_level_after_pass` rounds per level. 0 disables it. Measured (frame 1 -> 16):
  //! elephant 5.09% -> 4.15% of the diagonal (3.97% with 8 rounds per level after the pass), pcow
  //! (pre-aligned) 9.04% -> 9.25% (8.70% with 8); the blobs tracker (misfit 2%, so every frame) drifts
  //! 0.012% instead of 0.032% with half the coarse time per frame; bench/registration gap 15 at 47k:
  //! 0.93x the time, at 98k: 1.30x. Samba 1 -> 16 (misfit 0.18%) and consecutive captures unchanged.
  double coarse_pass_misfit = 0.004;
  double coarse_pass_density = 0.25;
  double coarse_pass_alpha_reg_min = 0.1;
  //! The low-density pass's density where the misfit is below `near_pass_misfit` (our addition; 0: coarse_pass_density
  //! at any misfit, the library's and the tracker's default). A pair that needs the pass but not every node's backward
  //! matches (backward_all_misfit's 3 %) has moved within a few of its node spacings: a quarter-density graph is coarser
  //! than its motion needs, and what it leaves misplaced the full graph's rays do not bring back. `topotrack align`
  //! takes kLargeMotionNearPassDensity. The pass's nodes stay at least `near_pass_min_spacing` (a fraction of the target's
  //! bounding-box diagonal) apart, never sparser than coarse_pass_density: on a finer mesh of the same shape the pass
  //! then has about as many nodes (their cost grows with their number, and the motion to fit is the same).
  double near_pass_density = 0;
  double near_pass_misfit = 0.03;
  double near_pass_min_spacing = 0.025;
  //! ... and at most this many rounds per alpha_reg level (max_iterations_per_level's 8 otherwise): more nodes, fewer
  //! rounds for about the quarter's time.
  int near_pass_max_iterations_per_level = 6;
  //! Cap on rounds per alpha_reg level of the full graph after the low-density pass ran (see above).
  //! 8 instead of 3 (measured 2026-11-23): frame k -> k+15 from k = 1, 3, 5, 7, 9
  //! (tests/kernels/registration/real_data_test.cpp), summed error pcow 15.75% -> 14.77%, elephant 18.84% ->
  //! 18.55%, samba 1.616% -> 1.606%, but bench/registration gap 15 at 47k 1.42 -> 2.20 s, at 98k 3.19 -> 4.58 s
  //! (issue 4's 2 s / 4 s); resurfaced pcow tracked 40 frames: drift 2.61% -> 2.19% (default profile, coarse
  //! median 1.20 -> 1.36 s/frame), 2.013% -> 1.901% (profiles/capture.json, which sets 8). Where the full
  //! graph finds the nodes fitted (blobs) or the pass does not run (samba) nothing changes.
  int max_iterations_per_level_after_pass = 3;
  //! The full graph's first alpha_reg after the low-density pass ran (our addition; 0: alpha_reg_start, the
  //! paper's 1000). The pass has fitted the coarse motion down to its alpha_reg of 0.1, so the full graph's levels
  //! at 1000 and 100 (3 rounds each) moved little: the elephant frame 1 -> 16 2.21 -> 2.19 % of the diagonal
  //! over both. `topotrack align` starts at kLargeMotionAlphaRegStartAfterPass; the tracker keeps 1000.
  double alpha_reg_start_after_pass = 0;
  //! The full graph's first alpha_reg where the misfit was measured and called for no low-density pass (our addition;
  //! 0: alpha_reg_start). The motion is then within the normal rays' reach, and the levels at 1000 and 100 spend their
  //! rounds holding the graph near rigid. `topotrack align` starts at kLargeMotionAlphaRegStartWithoutPass; the
  //! tracker keeps 1000.
  double alpha_reg_start_without_pass = 0;
  //! Large motion (our addition, the target -> source half of a symmetric fit): when the misfit (see
  //! prealign_misfit) exceeds `backward_misfit`, each round also matches the target to the nodes
  //! (find_backward_correspondences, about `backward_samples_per_node` target samples per node) and
  //! adds a backward fitting term, weighted `backward_weight` relative to the forward one, at each node
  //! whose forward match is pruned, or at every node when the misfit exceeds `backward_all_misfit`;
  //! also in the low-density pass (a threshold of 0: always). A part of the target that no node's
  //! normal ray reaches (a limb that swung away, whose forward matches are pruned or land on the wrong
  //! part) then pulls the nearest compatible nodes. Measured (frames 1, 5, 7, 9 -> +15, ground-truth
  //! error in % of the diagonal, before -> after): samba (misfit 0.18-0.34%) 0.15, 0.31, 2.13, 0.70 ->
  //! 0.15, 0.31, 0.41, 0.56; pcow (misfit 5%, every node) 9.13, 8.85, 16.0, 8.79 -> 3.25, 3.52, 3.46,
  //! 2.87 (pruned nodes only: 4.32, 3.83, 4.01, 3.04); elephant (0.57%) 4.27, 3.62, 3.12, 3.33 -> 3.41,
  //! 3.14, 3.43, 4.63. Weight 10 against 3 and 30: pcow 4.59 and 2.93 at frame 1, elephant 9 -> 24 (all
  //! nodes) 2.30 with 10, 4.54 with 30. The blobs tracker (100 frames, misfit about 2% per frame) is
  //! bit-identical with the pruned nodes only (every node keeps its forward match), but drifts 0.84%
  //! instead of 0.019% with every node (the node means of the target samples slide the nodes
  //! tangentially, frame after frame), hence `backward_all_misfit` above consecutive-frame motion.
  double backward_weight = 10;
  //! Where every node gets backward matches (the misfit above `backward_all_misfit`) and the vertices are fitted
  //! (vertex_fit_weight), the full graph matches the target's samples to the nearest fitted vertices instead of the
  //! nodes, each vertex's backward term weighted this much relative to its forward one (our addition; 0: at the nodes,
  //! the default and the tracker's). A node's backward match is the mean of the samples nearest to it, a patch about
  //! a node spacing across; a fitted vertex's patch is half that. `topotrack align` takes kLargeMotionBackwardVertexWeight.
  double backward_vertex_weight = 0;
  double backward_misfit = 0.003;
  double backward_all_misfit = 0.03;
  int backward_samples_per_node = 16;
  //! Large motion (our addition, kernels/registration/intrinsic_matches.hpp): after the low-density pass,
  //! nodes are placed on the target by their geodesic distances to consistently matched anchors; a node
  //! more than `intrinsic.misplaced_spacings` (low-density) node spacings from its place lies on another
  //! part (a limb laid where another one is) and follows its place instead of its ray. With
  //! `intrinsic_full_graph` the full graph's misplaced nodes do so in every round; `intrinsic_passes` first
  //! runs the low-density pass again, up to that many times while any of its nodes are misplaced, with
  //! theirs (more accurate, and dearer). Off by default and in the tracker; `topotrack align` sets
  //! intrinsic_full_graph and one guided pass (use_large_motion_alignment). Measured in docs/results.md
  //! (2026-12-01, 2026-12-02).
  bool intrinsic_full_graph = false;
  int intrinsic_passes = 0;
  //! Cap on rounds per alpha_reg level of a guided pass (from alpha_reg 10; our addition). A guided pass runs on
  //! the first pass's graph, the mesh as the first pass left it its rest state. Measured (elephant frame 1 -> 16,
  //! one guided pass, median over five re-samplings of the target): 1.11 % of the diagonal (1.06-1.14) with 3,
  //! 1.07 % (1.06-1.59) with 8 at about twice the pass's rounds; two guided passes with 3: 1.11 %.
  int intrinsic_pass_max_iterations_per_level = 3;
  IntrinsicParams intrinsic;
  //! A denser graph after the schedule (our addition, the finer end of the low-density pass's coarse-to-fine;
  //! 0: none, the default and the tracker's). Where the low-density pass did not run (the motion within the
  //! normal rays' reach) and the full graph took at least one round, a graph with nodes every
  //! `dense_spacing_factor` mean edge lengths, sampled on the mesh as the schedule left it, runs one level at
  //! `dense_alpha_reg` (at most max_iterations_per_level rounds): its rays fit more of the surface than the full
  //! graph's nodes can. `topotrack align` takes kLargeMotionDenseSpacingFactor.
  double dense_spacing_factor = 0;
  double dense_alpha_reg = 0.01;
  //! The denser graph's rounds refine a converged fit locally: their PCG runs with block Jacobi alone
  //! (pcg_coarse_correction off) and at most this many iterations. Measured (docs/results.md 2026-12-03): samba ten-run
  //! sum 1.6641 -> 1.6621 (15 iterations with the coarse correction -> 3 without); the bench's samba re-meshed to 98k,
  //! frame 1 -> 16 (TOPOTRACK_TEST_SOURCE_REFINE=0.24) 0.0797 -> 0.0798 %, its denser graph 2.2 -> ~0.9 s.
  int dense_max_pcg_iterations = 3;
  //! A fitting term at the mesh's vertices too (our addition; 0: the paper's, at the nodes only, the default and the
  //! tracker's): vertices sampled `vertex_fit_spacing` node spacings apart (0: every vertex) are matched along their
  //! normals (their nodes' A^-T blended, applied to the rest normal) like the nodes (same pruning), each term weighted vertex_fit_weight * nodes / vertices relative to
  //! a node's, so that the data, not the regularisation alone, sets each node's A_j (its rotation and shape): with the
  //! nodes' matches alone the linear blend of a few nodes cannot follow a limb's bend between them. A vertex's match is
  //! pruned where its displacement differs by more than `vertex_fit_max_disagreement` node spacings (0: no test) from
  //! the skinning-weighted mean of its nodes' (or none of them has a match): a ray from a part still far from its place
  //! may hit another part, and the vertices outnumber the nodes. A vertex skinned by a guided node (the intrinsic
  //! stage's) is left to the node's match. The full graph and the denser graph fit their vertices; the low-density
  //! passes do not. match_override is called for the vertices too (CoarseMatchRound::nodes: the vertices).
  //! `topotrack align` takes kLargeMotionVertexFit*; measured there.
  double vertex_fit_weight = 0;
  double vertex_fit_spacing = 0;
  double vertex_fit_max_disagreement = 0;
  //! Diagnostics: when set, called after the pre-alignment and after every alpha_reg level (then
  //! costs one skinning of the mesh per level); the result does not depend on it.
  std::function<void(const CoarseSnapshot&)> observer;
  //! Diagnostics (the registration tests' ground-truth experiments): when set, called in every round
  //! with the round's node correspondences, which it may replace; unset, nothing changes.
  std::function<void(const CoarseMatchRound&, std::vector<Correspondence>&)> match_override;
};


//! Guided low-density passes `topotrack align` runs (use_large_motion_alignment): the elephant frame 1 -> 16,
//! median over five re-samplings of the target, 1.44 % of the diagonal without, 1.11 % with one (docs/results.md).
inline constexpr int kLargeMotionIntrinsicPasses = 1;

//! What else `topotrack align` sets (use_large_motion_alignment): the full graph after the low-density pass
//! from alpha_reg 10 (CoarseParams::alpha_reg_start_after_pass), down to 0.01 (alpha_reg_min) unless the nodes
//! lie within 0.02 mean edge lengths of their matches (fit_tolerance; samba stopped at 0.05; a pair found fitted
//! before the first round still is at 0.05: kLargeMotionCheckFitFirstTolerance). Measured together
//! (frame 1 -> 16, median over five re-samplings of the target, % of the diagonal; docs/results.md 2026-12-02):
//! samba 0.152 -> 0.138, pcow 3.49 -> 3.46, elephant 1.11 -> 1.08, and bench/registration gap 15 (medians of five
//! alternating runs) 47k 1.90 -> 1.56 s, 98k 3.81 -> 3.09 s: two levels fewer on the full graph, one more lower.
inline constexpr double kLargeMotionAlphaRegStartAfterPass = 10;
inline constexpr double kLargeMotionAlphaRegMin = 0.01;
inline constexpr double kLargeMotionFitTolerance = 0.02;
inline constexpr double kLargeMotionCheckFitFirstTolerance = 0.05;  // the library's fit_tolerance (see there)
//! CoarseParams::dense_spacing_factor for `topotrack align` (at dense_alpha_reg 0.01, the end of its schedule). Measured
//! (frame k -> k+15, % of the diagonal; docs/results.md 2026-12-02): samba frame 1 median over five re-samplings of the
//! target 0.138 -> 0.119 (2 or 4 rounds instead of 8: 0.127 / 0.123), k = 3, 5, 7 (one re-sampling) 0.165 / 0.270 /
//! 0.358 -> 0.139 / 0.224 / 0.296 (k = 9 runs the pass: 0.501); spacing 2 0.114. Where the low-density pass runs it does
//! not: after the pass the elephant 1.08 -> 1.05 and pcow 3.46 -> 3.36 for 0.6 s more at 42k vertices (over issue 4's
//! time at 98k). Cost: bench/registration size 4 (samba re-meshed to 98k) 2.72 -> 4.0-4.5 s (the level 1.2-1.3 s).
inline constexpr double kLargeMotionDenseSpacingFactor = 2.5;
//! CoarseParams::min_nodes for `topotrack align`. Measured (docs/results.md 2026-12-02, % of the diagonal): pcow (2,904
//! vertices, 137 nodes at the paper's spacing, 284 now) frame 1 -> 16 median over five re-samplings 3.46 -> 2.46 (250:
//! 2.57, 350: 2.41), summed over frames k = 1, 3, 5, 7, 9 -> k+15 at two re-samplings 33.92 -> 27.59 (250: 27.26, 350:
//! 28.35), distance to the target 0.052-0.103 -> 0.041-0.049; coarse 0.19 -> 0.25 s. Samba (415 nodes) and the
//! elephant (2,003) are untouched.
inline constexpr int kLargeMotionMinNodes = 300;
//! CoarseParams::near_pass_density for `topotrack align`: the pass's nodes 1.5 times the full graph's spacing apart instead
//! of twice, 6 rounds per level. Measured (docs/results.md 2026-12-02, % of the diagonal): the elephant (misfit 0.5-0.9 %)
//! frame 1 -> 16 median over five re-samplings of the target 1.08 -> 0.90, frame k -> k+15 summed over k = 1, 3, 5, 7, 9
//! at two re-samplings 9.81 -> 8.67 (8 rounds per level: 8.82, 5: 8.74; density 0.36 / 0.5 / 0.5625 with 8: 8.81 / 8.86 /
//! 9.35); samba k = 9 (misfit 0.49 %, the one samba pair of these that runs the pass) 0.538 / 0.551 -> 0.431 / 0.457. pcow
//! (misfit 3.9-6.6 %, above near_pass_misfit) is worse with it, 27.59 -> 32.36 at 4/9, and keeps the quarter.
//! near_pass_min_spacing's 2.5 % of the diagonal leaves these elephant pairs (42k vertices; frame 1: 870 pass nodes instead
//! of 500) at 4/9 (2.65 % thins the pass of some: 9.75) and the bench's 98k re-meshing near the quarter (1,131 nodes; 1,692
//! at 4/9 took its pass from 1.2 to 2.5 s, the pair over issue 4's 4 s). bench/registration gap 15, two runs alternating:
//! 47k 1.74 / 1.85 -> 2.02 / 1.91 s, 98k 3.38 / 3.17 -> 3.62 / 3.62 s.
inline constexpr double kLargeMotionNearPassDensity = 4.0 / 9.0;
//! CoarseParams::alpha_reg_start_without_pass for `topotrack align`. Measured (samba frame k -> k+15 without the pass, % of
//! the diagonal; docs/results.md 2026-12-02): frame 1 median over five re-samplings 0.1191 either way in 19 rounds
//! instead of 32, k = 3 / 5 / 7 0.1387 / 0.2239 / 0.2956 -> 0.1387 / 0.2250 / 0.2884 in 26 / 26 / 32 rounds instead of
//! 40; bench/registration size 4 (samba re-meshed to 98k, with the denser graph) 4.40-4.53 -> 3.47-3.67 s. Where the pass
//! runs (pcow, the elephant) nothing changes.
inline constexpr double kLargeMotionAlphaRegStartWithoutPass = 10;
//! CoarseParams::vertex_fit_weight, vertex_fit_spacing, vertex_fit_max_disagreement for `topotrack align`. Measured (frame
//! k -> k+15 summed over k = 1, 3, 5, 7, 9 at two re-samplings of the target, 0.79 and 0.81, % of the diagonal;
//! docs/results.md 2026-12-03): samba 2.429 -> 1.664, elephant 8.667 -> 8.145, pcow 27.59 -> 26.48. Weight 3 / 30
//! (spacing 0.5, no disagreement test): elephant 8.12 / 8.33, pcow 26.87 / 26.21; spacing 0.35 / 0.25: elephant 8.20 /
//! 8.20 for more time; every vertex (weight 1): elephant frame 1 0.918 -> 0.848, twice the coarse time. Without the
//! disagreement test samba frame 5 -> 20 lost a limb to another part with weight 1 and 10 (1.0-1.2 % instead of 0.23 %),
//! and also when the vertices waited for alpha_reg 1 or 0.1; a test at 0.25 / 0.5 spacings: elephant 8.36 / 8.16, pcow
//! 27.45 / 27.00. In the low-density passes too (0.5): samba 1.616, elephant 9.56, pcow 26.62.
//! CoarseParams::backward_vertex_weight for `topotrack align`. Measured (ten-run sums as above; "other pairs": pcow
//! k = 2, 4, ..., 20 and the elephant k = 2, 4, 6, 8 at 0.8; docs/results.md 2026-12-04): pcow 26.351 -> 25.726, other
//! pairs 28.773 -> 27.803, k = 21, 25, ..., 57 171.36 -> 170.92; frame 1 -> 16 median 2.28 -> 2.40 %. Weight 2 / 3 / 5
//! with the guided nodes' vertices keeping their backward matches: 24.84 / 24.79 / 24.85, other pairs 28.34 / 28.01 /
//! 28.90. Samba and the elephant (backward matches at the pruned nodes only) are unchanged, bit for bit.
inline constexpr double kLargeMotionBackwardVertexWeight = 3;
inline constexpr double kLargeMotionVertexFitWeight = 10;
inline constexpr double kLargeMotionVertexFitSpacing = 0.5;
inline constexpr double kLargeMotionVertexFitMaxDisagreement = 1;

//! One correspondence + Gauss–Newton round.
struct CoarseRound {
  double alpha_reg = 0;
  double energy_before = 0; //!< total energy before the round's step (with its correspondences)
  double energy = 0;        //!< total energy after the round's step
  double motion = 0;        //!< largest node motion of the step, in mean edge lengths
  double fit_distance = 0;  //!< mean node-to-correspondence distance after the step, in mean edge lengths
  double step = 0;          //!< fraction of the Gauss–Newton step taken (halved while it raised the energy; 0: none)
  int pcg_iterations = 0;
  std::size_t correspondences = 0;
};

//! What one graph's rounds cost, by phase (CoarseReport::low_density: the low-density passes').
struct CoarsePhases {
  int nodes = 0;           //!< of the (last) graph
  int rounds = 0;
  int pcg_iterations = 0;
  int factorisations = 0;
  double seconds_graph = 0, seconds_correspondences = 0, seconds_assembly = 0, seconds_factorisation = 0,
         seconds_solve = 0, seconds_total = 0;
};

struct CoarseReport {
  int iterations = 0;         //!< correspondence + Gauss–Newton rounds
  int levels = 0;             //!< alpha_reg levels visited
  int nodes = 0;
  int graph_edges = 0;
  int fitted_vertices = 0;    //!< vertices with a fitting term of their own (CoarseParams::vertex_fit_weight)
  int factorisations = 0;
  std::size_t factor_nonzeros = 0;  //!< entries of the Cholesky factor L (the last factorisation)
  int pcg_iterations = 0;     //!< summed over rounds (SeparablePCG)
  double node_spacing = 0;
  double alpha_reg_end = 0;   //!< the last alpha_reg used
  std::size_t correspondences = 0;  //!< valid node correspondences in the last round
  std::size_t pruned_no_hit = 0, pruned_normal = 0, pruned_distance = 0;  //!< in the last round
  double energy_start = 0, energy_end = 0;  //!< total energy before the first and after the last step
  double fit_start = 0, fit_end = 0;        //!< E_fit (unweighted, relative units) likewise
  double mean_fit_distance = 0;  //!< mean |x_j - c_j| over the valid node correspondences after the last step
  bool fitted_at_start = false;  //!< check_fit_first found the nodes fitted: no round ran (levels 0)
  std::vector<double> energy_history;       //!< total energy after each round (alpha_reg of that round)
  std::vector<CoarseRound> rounds;          //!< per round, in order
  bool prealigned = false;          //!< the rigid pre-alignment ran and was applied
  bool backward = false;            //!< the misfit called for the backward correspondences (pruned nodes)
  bool backward_all = false;        //!< ... at every node
  bool backward_at_vertices = false;  //!< ... made at the fitted vertices instead (backward_vertex_weight)
  int coarse_pass_iterations = 0;   //!< rounds of the low-density pass, guided ones included (0: it did not run)
  int intrinsic_passes = 0;         //!< low-density passes run again with intrinsic matches
  std::size_t intrinsic_misplaced = 0;  //!< the pass's nodes found misplaced after it (intrinsic_passes > 0)
  std::size_t intrinsic_full_graph_misplaced = 0;  //!< the full graph's nodes that followed their places
  double seconds_intrinsic = 0;     //!< the intrinsic matches (within seconds_prealign)
  //! The low-density pass and the guided passes summed (within seconds_prealign; zero when none ran).
  CoarsePhases low_density;
  //! The denser graph's level (CoarseParams::dense_spacing_factor; within seconds_total only; zero when it did not run).
  CoarsePhases dense;
  double misfit_start = 0;          //!< trimmed mean closest-point distance before anything / target diagonal
  RigidIcpReport prealign;
  //! The misfit test, the rigid pre-alignment, the low-density passes and the intrinsic matches
  //! together (the phase seconds below are the full graph's only; seconds_total covers everything).
  double seconds_prealign = 0;
  double seconds_graph = 0, seconds_correspondences = 0, seconds_assembly = 0, seconds_factorisation = 0,
         seconds_solve = 0, seconds_total = 0;
};

//! Deform `mesh` toward `target` (§4.2, coarse stage). Moves vertex positions only (connectivity and
//! ids untouched); vertices of a component without any correspondence move rigidly with their nodes.
//! Deterministic for any thread count.
//! \pre mesh has no isolated live vertex.  \throw InvalidInput on bad parameters or an empty mesh,
//! SolverError if the factorisation fails.
CoarseReport align_coarse(SurfaceMesh& mesh, const TargetSurface& target, const CoarseParams& params = {});

}  // namespace topotrack
