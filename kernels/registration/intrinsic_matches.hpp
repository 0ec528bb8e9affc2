#pragma once
//! Intrinsic matches for large motion (our addition to §4.2, after Huang et al. 2008, "Non-rigid
//! registration under isometric deformations"). Normal rays and closest points match a node to the part
//! of the target that is near it; where a limb swung far (a galloping elephant's hind leg, 20 % of the
//! diagonal in 30 frames), they lay it on the part that is there, and no regularisation undoes that.
//! Distances along the surface tell where it belongs: a motion that bends but does not tear keeps them,
//! to within its stretch (4 % median on the elephant, docs/results.md), far finer than such a misplacement.
//!
//! From the nodes' current matches (the target vertex nearest to where each node is now), anchors are
//! chosen by geodesic farthest-point sampling; an anchor whose geodesic distances to its nearest anchors
//! disagree with the target's between their matches is dropped, the worst first, until every anchor left
//! agrees with most of its neighbours. Each node is then placed on the target where its geodesic distances
//! to its nearest kept anchors are best reproduced (scaled by the median ratio of target to source
//! distances between kept anchors); a node whose place lies far from where it is now is misplaced, and
//! that place becomes its match. Distances are Dijkstra's over the edges of either mesh.
#include <span>
#include <vector>

#include "kernels/mesh/edge_graph.hpp"
#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"
#include "kernels/registration/correspondences.hpp"

namespace topotrack {

struct IntrinsicParams {
  int anchors = 32;  //!< farthest-point anchors among the nodes (intrinsic_anchors)
  //! An anchor pair agrees when the target's distance between their matches is within this fraction of the
  //! scaled source distance, plus `slack` node spacings.
  double tolerance = 0.1;
  double slack = 0.25;
  int agreement_neighbours = 10;  //!< the nearest kept anchors that judge an anchor ...
  double min_agreement = 0.75;    //!< ... of which it must agree with this fraction
  int signature_anchors = 12;     //!< the nearest kept anchors that place a node
  //! A node is misplaced when its place lies more than this many node spacings from where it is. Measured on
  //! the elephant (frame 1 -> 16, after the coarse stage, five re-samplings of the target): at 2 every node so
  //! found was more than 5 % of the diagonal from its ground truth (17-20 % on average; placed: 3.6-4.5 %).
  double misplaced_spacings = 2;
};

//! The source's side, once for a set of nodes: anchors chosen among them by farthest-point sampling of
//! their positions, and the anchors' geodesic distances to every node.
struct IntrinsicAnchors {
  std::vector<Index> anchor;                  //!< vertices of the source's edge graph
  std::vector<std::vector<float>> distance;   //!< [a][v]: from anchor a to vertex v (infinity: unreached)
};

//! `source`: the source's edge graph at its rest positions; `candidates`: vertices to choose the anchors
//! among, at `position` (any pose: it only spreads them). \throw InvalidInput on a vertex out of range or
//! mismatched sizes.
IntrinsicAnchors intrinsic_anchors(const EdgeGraph& source, std::span<const Index> candidates,
                                   std::span<const Vec3> position, int anchors = 32);

struct IntrinsicMatches {
  std::vector<Correspondence> match;  //!< per node: its place (status Ok) where misplaced, else NoHit
  std::size_t anchors = 0, kept = 0, misplaced = 0;
  double scale = 1;  //!< target / source distance, median over pairs of kept anchors
};

//! What intrinsic_matches computes on the target and can reuse in a later call on the same target graph: the
//! distance fields from the anchors' matches (a field depends on its source vertex alone) and the candidate
//! places at a spacing. The results are the same with or without it.
struct IntrinsicTargetCache {
  std::vector<Index> source;                  //!< target vertex of each field
  std::vector<std::vector<float>> distance;   //!< [f][t]
  double candidate_spacing = 0;
  std::vector<Index> candidates;
};

//! `nodes`: source vertices, `node_x`: where they are now (and `anchor_x`: where the anchors are now);
//! `target_graph`: edge_graph(target.positions(), target.triangles()); `spacing`: the nodes' spacing (a
//! length); `cache` (optional): reused and extended (only for one target graph).
//! Deterministic for any thread count. \throw InvalidInput on mismatched sizes or bad parameters.
IntrinsicMatches intrinsic_matches(const IntrinsicAnchors& anchors, std::span<const Vec3> anchor_x,
                                   std::span<const Index> nodes, std::span<const Vec3> node_x,
                                   const TargetSurface& target, const EdgeGraph& target_graph, double spacing,
                                   const IntrinsicParams& params = {}, IntrinsicTargetCache* cache = nullptr);

}  // namespace topotrack
