#pragma once
//! What `topotrack align` adds to the library's defaults for a pair far apart (our additions; the tracker,
//! between consecutive frames, keeps the defaults): the full graph's misplaced nodes follow their intrinsic
//! places (CoarseParams::intrinsic_full_graph) after one low-density pass guided by the pass's own misplaced
//! nodes (kLargeMotionIntrinsicPasses) on a graph less coarse where the misfit is small (kLargeMotionNearPassDensity),
//! the full graph's levels run from alpha_reg 10 down to 0.01 with or without
//! the pass (kLargeMotionAlphaRegStartAfterPass, kLargeMotionAlphaRegStartWithoutPass, kLargeMotionAlphaRegMin,
//! kLargeMotionFitTolerance and kLargeMotionCheckFitFirstTolerance), a pair within the normal rays' reach ends on a
//! denser graph (kLargeMotionDenseSpacingFactor), a mesh of few vertices gets a graph of enough nodes
//! (kLargeMotionMinNodes), the full graph also fits sampled vertices (kLargeMotionVertexFitWeight) and, where every node
//! would get backward matches, makes them at those vertices (kLargeMotionBackwardVertexWeight), and the fine stage takes
//! further rounds (kLargeMotionFineRounds). The rigid pre-alignment, the low-density pass and the backward matches are
//! library defaults already, gated by the measured misfit. One place for the tool, the tests and the bench.
#include "kernels/registration/coarse.hpp"
#include "kernels/registration/fine.hpp"

namespace topotrack {

inline void use_large_motion_alignment(CoarseParams& coarse, FineParams& fine) {
  coarse.intrinsic_full_graph = true;
  coarse.intrinsic_passes = kLargeMotionIntrinsicPasses;
  coarse.near_pass_density = kLargeMotionNearPassDensity;
  coarse.alpha_reg_start_after_pass = kLargeMotionAlphaRegStartAfterPass;
  coarse.alpha_reg_start_without_pass = kLargeMotionAlphaRegStartWithoutPass;
  coarse.alpha_reg_min = kLargeMotionAlphaRegMin;
  coarse.fit_tolerance = kLargeMotionFitTolerance;
  coarse.check_fit_first_tolerance = kLargeMotionCheckFitFirstTolerance;
  coarse.dense_spacing_factor = kLargeMotionDenseSpacingFactor;
  coarse.min_nodes = kLargeMotionMinNodes;
  coarse.vertex_fit_weight = kLargeMotionVertexFitWeight;
  coarse.vertex_fit_spacing = kLargeMotionVertexFitSpacing;
  coarse.vertex_fit_max_disagreement = kLargeMotionVertexFitMaxDisagreement;
  coarse.backward_vertex_weight = kLargeMotionBackwardVertexWeight;
  fine.max_rounds = kLargeMotionFineRounds;
  fine.relax.iterations = kLargeMotionRelaxIterations;
}

}  // namespace topotrack
