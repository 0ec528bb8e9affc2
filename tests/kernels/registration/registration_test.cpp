// Deformation graph, correspondence pruning, coarse and fine alignment, projection baseline (§4.2).
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>

#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/registration/coarse.hpp"
#include "kernels/registration/large_motion.hpp"
#include "kernels/registration/correspondences.hpp"
#include "kernels/registration/deformation_graph.hpp"
#include "kernels/registration/fine.hpp"
#include "kernels/registration/projection.hpp"
#include "tests/kernels/registration/blob.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

using test::blob;
using test::mean_error;

Eigen::Matrix3d rotation(double deg, const Vec3& axis) {
  return Eigen::AngleAxisd(deg * std::numbers::pi / 180, axis.normalized()).toRotationMatrix();
}

// The paper's scheme alone (§4.2): the large-motion stages (rigid pre-alignment, low-density pass)
// off, for the tests of the Gauss–Newton rounds themselves.
CoarseParams paper_scheme() {
  CoarseParams p;
  p.prealign_misfit = 0;
  p.coarse_pass_misfit = 0;
  return p;
}

// Source mesh, ground-truth positions and a target with different connectivity (coarser icosphere
// mapped by the same transform).
struct Case {
  SurfaceMesh source;
  std::vector<Vec3> truth;
  TargetSurface target;
};

template <class F>
Case make_case(F&& transform) {
  test::Soup src = blob(4);
  test::Soup tgt = blob(5);
  std::vector<Vec3> truth;
  for (const Vec3& p : src.positions) truth.push_back(transform(p));
  for (Vec3& p : tgt.positions) p = transform(p);
  return Case{src.mesh(), truth, TargetSurface(tgt.positions, tgt.triangles)};
}

// --- deformation graph ---------------------------------------------------------------------------

TEST(DeformationGraph, NodesWeightsAndEdges) {
  SurfaceMesh mesh = blob(4).mesh();
  const double spacing = 4 * mean_edge_length(mesh);
  const DeformationGraph g = build_deformation_graph(mesh, spacing, 4);
  EXPECT_GT(g.n_nodes(), 20u);
  EXPECT_LT(g.n_nodes(), mesh.n_vertices() / 5);
  // Nodes at least `spacing` apart (Euclidean is a lower bound of the geodesic distance).
  for (std::size_t a = 0; a < g.n_nodes(); ++a)
    for (std::size_t b = a + 1; b < g.n_nodes(); ++b)
      EXPECT_GT((g.node_position[a] - g.node_position[b]).norm(), 0.5 * spacing);
  for (std::size_t v = 0; v < mesh.vertices_size(); ++v) {
    double sum = 0;
    for (int s = 0; s < 4; ++s) {
      EXPECT_NE(g.influence_node[v * 4 + s], kInvalidIndex);
      sum += g.influence_weight[v * 4 + s];
    }
    EXPECT_NEAR(sum, 1.0, 1e-12);
    // The first influence is the nearest node: within the covering radius.
    EXPECT_LT((mesh.positions()[v] - g.node_position[g.influence_node[v * 4]]).norm(), spacing * 1.0001);
  }
  EXPECT_GT(g.edges.size(), g.n_nodes());
  for (const auto& [i, j] : g.edges) EXPECT_LT(i, j);
  EXPECT_THROW(build_deformation_graph(mesh, 0.0, 4), InvalidInput);
  EXPECT_THROW(build_deformation_graph(mesh, spacing, 0), InvalidInput);
}

TEST(DeformationGraph, ComponentsNeverShareNodes) {
  // Two spheres 1% apart: close in space, infinitely far along the surface.
  const test::Soup a = test::icosphere(3, 1.0, Vec3(0, 0, 0));
  const test::Soup b = test::icosphere(3, 1.0, Vec3(2.02, 0, 0));
  SurfaceMesh mesh = test::merge(a, b).mesh();
  const DeformationGraph g = build_deformation_graph(mesh, 8 * mean_edge_length(mesh), 4);
  const std::size_t na = a.positions.size();
  auto side = [&](Index node) { return g.node_vertex[node].idx < na; };
  for (std::size_t v = 0; v < mesh.vertices_size(); ++v)
    for (int s = 0; s < 4; ++s) {
      const Index j = g.influence_node[v * 4 + s];
      if (j != kInvalidIndex) {
        EXPECT_EQ(side(j), v < na);
      }
    }
  for (const auto& [i, j] : g.edges) EXPECT_EQ(side(i), side(j));
}

// The k + 1 nearest nodes of every vertex against a brute force (a full Dijkstra from every node), on
// a blob and a small sphere whose vertices have fewer than k + 1 nodes within the first search radius
// (the second search) or at all (d_max is then the search radius, 2.5 spacings).
TEST(DeformationGraph, NearestNodesAreExact) {
  SurfaceMesh mesh = test::merge(blob(4), test::icosphere(2, 0.12, Vec3(3, 0, 0))).mesh();
  const double spacing = 4 * mean_edge_length(blob(4).mesh()), radius = 2.5 * spacing;
  const std::vector<Vertex> nodes = sample_graph_nodes(mesh, spacing);
  const DeformationGraph g = build_deformation_graph(mesh, nodes, spacing, 4);
  ASSERT_EQ(g.node_vertex, nodes);
  const DeformationGraph same = build_deformation_graph(mesh, spacing, 4);
  EXPECT_EQ(same.influence_node, g.influence_node);
  EXPECT_EQ(same.influence_weight, g.influence_weight);
  const std::size_t nv = mesh.vertices_size();
  std::vector<std::vector<std::pair<double, Index>>> cand(nv);
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    std::vector<double> d(nv, std::numeric_limits<double>::infinity());
    using Item = std::pair<double, Index>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> q;
    d[nodes[j].idx] = 0;
    q.push({0.0, nodes[j].idx});
    std::vector<Halfedge> ring;
    while (!q.empty()) {
      const auto [du, u] = q.top();
      q.pop();
      if (du > d[u]) continue;
      mesh.outgoing(Vertex(u), ring);
      for (Halfedge h : ring) {
        const Index w = mesh.to_vertex(h).idx;
        const double nd = du + (mesh.positions()[w] - mesh.positions()[u]).norm();
        if (nd < d[w]) {
          d[w] = nd;
          q.push({nd, w});
        }
      }
    }
    for (std::size_t v = 0; v < nv; ++v)
      if (d[v] <= radius) cand[v].push_back({d[v], Index(j)});
  }
  std::size_t small_sphere = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    std::sort(cand[v].begin(), cand[v].end());
    ASSERT_FALSE(cand[v].empty());
    small_sphere += cand[v].size() < 5;
    const double dmax = cand[v].size() > 4 ? cand[v][4].first : radius;
    double sum = 0;
    for (std::size_t s = 0; s < 4 && s < cand[v].size(); ++s) sum += std::pow(1 - cand[v][s].first / dmax, 2);
    for (std::size_t s = 0; s < 4; ++s) {
      if (s >= cand[v].size()) {
        EXPECT_EQ(g.influence_node[v * 4 + s], kInvalidIndex);
        continue;
      }
      EXPECT_EQ(g.influence_node[v * 4 + s], cand[v][s].second) << "vertex " << v << " slot " << s;
      EXPECT_NEAR(g.influence_weight[v * 4 + s], std::pow(1 - cand[v][s].first / dmax, 2) / sum, 1e-9);
    }
  }
  EXPECT_EQ(small_sphere, test::icosphere(2, 0.12).positions.size());  // every vertex of the small sphere
  const std::vector<Vertex> outside{Vertex{Index(nv)}};
  EXPECT_THROW(build_deformation_graph(mesh, outside, spacing, 4), InvalidInput);
  EXPECT_THROW(sample_graph_nodes(mesh, -1.0), InvalidInput);
}

// --- correspondences -----------------------------------------------------------------------------

TEST(Correspondences, PruningRules) {
  const test::Soup s = test::icosphere(5);
  const TargetSurface target(s.positions, s.triangles);
  // Along the normal onto the sphere: accepted.
  Correspondence c = find_correspondence(target, Vec3(0, 1.1, 0), Vec3(0, 1, 0));
  EXPECT_EQ(c.status, CorrespondenceStatus::Ok);
  EXPECT_NEAR(c.distance, 0.1, 2e-3);
  // Undirected: a point inside the sphere finds the wall behind it.
  c = find_correspondence(target, Vec3(0, 0.9, 0), Vec3(0, -1, 0));
  EXPECT_EQ(c.status, CorrespondenceStatus::NormalAngle);  // the wall faces the other way
  // Grazing ray: normals 64 degrees apart.
  c = find_correspondence(target, Vec3(0, 0.9, 0), Vec3(1, 0, 0));
  EXPECT_EQ(c.status, CorrespondenceStatus::NormalAngle);
  // Same ray without the angle test: 0.436 away while the closest point is 0.1 away (> 3x).
  CorrespondenceParams no_angle;
  no_angle.max_normal_angle_deg = 180;
  c = find_correspondence(target, Vec3(0, 0.9, 0), Vec3(1, 0, 0), no_angle);
  EXPECT_EQ(c.status, CorrespondenceStatus::TooFar);
  no_angle.max_closest_ratio = 5;
  EXPECT_EQ(find_correspondence(target, Vec3(0, 0.9, 0), Vec3(1, 0, 0), no_angle).status, CorrespondenceStatus::Ok);
  // Misses and a zero normal.
  EXPECT_EQ(find_correspondence(target, Vec3(5, 5, 5), Vec3(1, 0, 0)).status, CorrespondenceStatus::NoHit);
  EXPECT_EQ(find_correspondence(target, Vec3(0, 1.1, 0), Vec3::Zero()).status, CorrespondenceStatus::NoHit);
  // A length limit (the fine stage's sigma).
  CorrespondenceParams short_ray;
  short_ray.max_distance = 0.05;
  EXPECT_EQ(find_correspondence(target, Vec3(0, 1.1, 0), Vec3(0, 1, 0), short_ray).status,
            CorrespondenceStatus::NoHit);
}

TEST(Correspondences, ClosestPointMode) {
  const test::Soup s = test::icosphere(5);
  const TargetSurface target(s.positions, s.triangles);
  CorrespondenceParams closest;
  closest.closest_point = true;
  // The grazing ray that the ratio test prunes: the closest point is straight above, normals agree.
  Correspondence c = find_correspondence(target, Vec3(0, 0.9, 0), Vec3(0.2, 1, 0), closest);
  EXPECT_EQ(c.status, CorrespondenceStatus::Ok);
  EXPECT_NEAR(c.distance, 0.1, 2e-3);
  EXPECT_NEAR(c.point.y(), 1.0, 2e-3);
  // The normal test still applies.
  EXPECT_EQ(find_correspondence(target, Vec3(0, 0.9, 0), Vec3(1, 0, 0), closest).status,
            CorrespondenceStatus::NormalAngle);
  EXPECT_EQ(find_correspondence(target, Vec3(0, 0.9, 0), Vec3(0, -1, 0), closest).status,
            CorrespondenceStatus::NormalAngle);
  // Farther than max_distance: no match.
  closest.max_distance = 0.05;
  EXPECT_EQ(find_correspondence(target, Vec3(0, 0.9, 0), Vec3(0, 1, 0), closest).status, CorrespondenceStatus::NoHit);
}

// The target -> node matches of large motion: each target sample goes to its nearest node with a
// compatible normal; a node's match is the area-weighted mean of its samples.
TEST(Correspondences, BackwardMatches) {
  const test::Soup s = test::icosphere(5);
  const TargetSurface target(s.positions, s.triangles);
  const TargetSamples all = sample_target(target);
  EXPECT_EQ(all.point.size(), target.n_triangles());
  double area = 0;
  for (double a : all.area) area += a;
  EXPECT_NEAR(area, 4 * std::numbers::pi, 0.02);
  EXPECT_LE(sample_target(target, 1000).point.size(), 1000u);
  EXPECT_GE(sample_target(target, 1000).point.size(), 900u);
  // Two nodes above the poles, both facing up: the north one takes the cap within 60 degrees of its
  // normal (y >= 0.5: mean y 0.75 on the unit sphere, area-uniform in y); the south one no sample (its
  // nearest samples face down, and so do all within reach of its normal).
  const std::vector<Vec3> x{Vec3(0, 1.2, 0), Vec3(0, -1.2, 0)};
  std::vector<Vec3> n{Vec3(0, 1, 0), Vec3(0, 2, 0)};
  std::vector<Correspondence> c = find_backward_correspondences(all, x, n, 60);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].status, CorrespondenceStatus::Ok);
  EXPECT_NEAR(c[0].point.y(), 0.75, 0.01);
  EXPECT_NEAR(c[0].point.x(), 0, 0.01);
  EXPECT_NEAR(c[0].normal.y(), 1, 1e-9);
  EXPECT_NEAR(c[0].distance, 0.45, 0.01);
  EXPECT_EQ(c[1].status, CorrespondenceStatus::NoHit);
  // Facing down, the south node takes the south cap.
  n[1] = Vec3(0, -1, 0);
  c = find_backward_correspondences(all, x, n, 60);
  EXPECT_EQ(c[1].status, CorrespondenceStatus::Ok);
  EXPECT_NEAR(c[1].point.y(), -0.75, 0.01);
  // Without the normal test every sample goes to its nearest node: the hemispheres, mean |y| 0.5.
  c = find_backward_correspondences(all, x, std::vector<Vec3>{Vec3(0, 1, 0), Vec3(0, 1, 0)}, 180);
  EXPECT_NEAR(c[0].point.y(), 0.5, 0.01);
  EXPECT_NEAR(c[1].point.y(), -0.5, 0.01);
  EXPECT_THROW(find_backward_correspondences(all, x, std::vector<Vec3>{Vec3(0, 1, 0)}, 60), InvalidInput);
  EXPECT_THROW(find_backward_correspondences(all, x, n, 60, 0), InvalidInput);
}

// --- coarse + fine -------------------------------------------------------------------------------

TEST(Alignment, RigidRotationIsRecovered) {
  const Eigen::Matrix3d R = rotation(25, Vec3(0.3, 1, 0.2));
  const Vec3 t(0.05, -0.03, 0.02);
  Case c = make_case([&](const Vec3& p) { return Vec3(R * p + t); });
  const double diag = c.target.bbox_diagonal();
  const double before = mean_error(c.source, c.truth);
  Case with_pass = make_case([&](const Vec3& p) { return Vec3(R * p + t); });
  const CoarseReport cr = align_coarse(c.source, c.target, paper_scheme());
  EXPECT_GT(cr.iterations, 1);
  EXPECT_LT(cr.fit_end, 0.05 * cr.fit_start);
  const double after_coarse = mean_error(c.source, c.truth);
  const FineReport fr = align_fine(c.source, c.target);
  EXPECT_LT(fr.energy_end, fr.energy_start);
  const double after = mean_error(c.source, c.truth);
  EXPECT_LT(after_coarse, 0.2 * before);
  EXPECT_LT(after, 0.005 * diag) << "before " << before / diag << " coarse " << after_coarse / diag;
  c.source.validate();
  // The defaults: the misfit calls for the low-density pass first; the result is as good.
  const CoarseReport dp = align_coarse(with_pass.source, with_pass.target);
  EXPECT_GT(dp.coarse_pass_iterations, 1);
  EXPECT_FALSE(dp.prealigned);
  // The pass's own split: its rounds, a sparser graph, and phases within the time before the full graph.
  EXPECT_EQ(dp.low_density.rounds, dp.coarse_pass_iterations);
  EXPECT_GT(dp.low_density.nodes, 0);
  EXPECT_LT(dp.low_density.nodes, dp.nodes);
  EXPECT_GT(dp.low_density.pcg_iterations, 0);
  EXPECT_GT(dp.low_density.factorisations, 0);
  const CoarsePhases& ld = dp.low_density;
  EXPECT_GT(ld.seconds_total, 0);
  EXPECT_LE(ld.seconds_graph + ld.seconds_correspondences + ld.seconds_assembly + ld.seconds_factorisation +
                ld.seconds_solve,
            ld.seconds_total);
  EXPECT_LE(ld.seconds_total, dp.seconds_prealign);
  // The paper's scheme alone runs no pass and reports none.
  EXPECT_EQ(cr.low_density.rounds, 0);
  EXPECT_EQ(cr.low_density.nodes, 0);
  EXPECT_EQ(cr.low_density.seconds_total, 0);
  align_fine(with_pass.source, with_pass.target);
  EXPECT_LT(mean_error(with_pass.source, with_pass.truth), 0.005 * diag);
}

// The diagnostics hook sees every round of both stages and may replace the matches: a hook that
// changes nothing leaves the result bit for bit; matches taken from the ground truth are followed
// where the paper's rounds alone (here without the rotation retraction) stay far off: the
// ground-truth experiments of real_data_test.
TEST(Alignment, MatchOverrideSeesEveryRoundAndIsFollowed) {
  const Eigen::Matrix3d R = rotation(70, Vec3(0.2, 1, 0.4));
  const Vec3 t(0.6, -0.3, 0.2);
  auto transform = [&](const Vec3& p) { return Vec3(R * p + t); };
  Case plain = make_case(transform), hooked = make_case(transform), truth = make_case(transform);
  align_coarse(plain.source, plain.target);
  CoarseParams p;
  int rounds = 0, pass_rounds = 0;
  p.match_override = [&](const CoarseMatchRound& round, std::vector<Correspondence>& corr) {
    EXPECT_EQ(round.nodes.size(), corr.size());
    EXPECT_GE(round.level, 1);
    ++(round.stage == CoarseStage::LowDensityLevel ? pass_rounds : rounds);
  };
  const CoarseReport hr = align_coarse(hooked.source, hooked.target, p);
  EXPECT_EQ(plain.source.positions(), hooked.source.positions());
  EXPECT_EQ(pass_rounds, hr.coarse_pass_iterations);
  EXPECT_EQ(rounds + pass_rounds, hr.iterations + hr.coarse_pass_iterations);

  CoarseParams q = paper_scheme();
  q.retract_rotations = false;
  q.match_override = [&](const CoarseMatchRound& round, std::vector<Correspondence>& corr) {
    for (std::size_t j = 0; j < corr.size(); ++j) {
      const TargetSurface::Hit hit = truth.target.closest_point(truth.truth[round.nodes[j].idx]);
      corr[j] = Correspondence{CorrespondenceStatus::Ok, hit.point, hit.normal, 0};
    }
  };
  const double diag = truth.target.bbox_diagonal();
  Case alone = make_case(transform);
  CoarseParams r = paper_scheme();
  r.retract_rotations = false;
  align_coarse(alone.source, alone.target, r);
  align_coarse(truth.source, truth.target, q);
  EXPECT_LT(mean_error(truth.source, truth.truth), 0.01 * diag);  // measured 0.47%
  EXPECT_GT(mean_error(alone.source, alone.truth), 0.02 * diag);  // measured 3.1%
}

// Far beyond the capture range of normal rays (a third of the shape's size and 70 degrees): the rigid
// pre-alignment runs first, and without it (nor the rotation retraction of the Gauss–Newton steps) the
// coarse stage stays far off. The retraction alone recovers it too.
TEST(Alignment, LargeMotionIsPreAligned) {
  const Eigen::Matrix3d R = rotation(70, Vec3(0.2, 1, 0.4));
  const Vec3 t(0.6, -0.3, 0.2);
  auto transform = [&](const Vec3& p) { return Vec3(R * p + t); };
  Case with = make_case(transform), without = make_case(transform), retracted = make_case(transform);
  const double diag = with.target.bbox_diagonal();
  const double before = mean_error(with.source, with.truth);
  const CoarseReport cr = align_coarse(with.source, with.target);
  EXPECT_GT(cr.misfit_start, CoarseParams{}.prealign_misfit);
  EXPECT_TRUE(cr.prealigned);
  EXPECT_TRUE(cr.backward_all);  // the misfit also calls for the backward matches at every node
  EXPECT_LT(cr.prealign.distance_end, 0.1 * cr.prealign.distance_start);
  align_fine(with.source, with.target);
  CoarseParams off;
  off.prealign_misfit = 0;
  const CoarseReport cr2 = align_coarse(retracted.source, retracted.target, off);
  EXPECT_FALSE(cr2.prealigned);
  align_fine(retracted.source, retracted.target);
  off.retract_rotations = false;
  const CoarseReport co = align_coarse(without.source, without.target, off);
  EXPECT_FALSE(co.prealigned);
  align_fine(without.source, without.target);
  const double after = mean_error(with.source, with.truth), after_off = mean_error(without.source, without.truth);
  EXPECT_LT(after, 0.01 * diag) << "before " << before / diag;
  EXPECT_GT(after_off, 5 * after);
  EXPECT_LT(mean_error(retracted.source, retracted.truth), 0.01 * diag);
  with.source.validate();
}

// Small motion stays with the paper's scheme: the misfit is measured, nothing is pre-aligned.
TEST(Alignment, SmallMotionIsNotPreAligned) {
  Case c = make_case([](const Vec3& p) { return Vec3(rotation(5, Vec3(0, 0, 1)) * p + Vec3(0.03, 0, 0)); });
  const CoarseReport cr = align_coarse(c.source, c.target);
  EXPECT_GT(cr.misfit_start, 0);
  EXPECT_LT(cr.misfit_start, CoarseParams{}.prealign_misfit);
  EXPECT_FALSE(cr.prealigned);
  EXPECT_FALSE(cr.backward_all);
  EXPECT_EQ(cr.prealign.iterations, 0);
}

TEST(Alignment, AffineStretchIsRecovered) {
  // With the paper's weights in relative units the rigidity term dominates down to alpha_reg_min, so a
  // stretch is recovered onto the surface but only partly along it (measured: ground-truth error
  // 0.057 -> 0.034 at alpha_reg_min 0.1).
  Case c = make_case([](const Vec3& p) { return Vec3(1.1 * p.x(), p.y(), p.z() + 0.05 * p.x()); });
  const double diag = c.target.bbox_diagonal();
  const double before = mean_error(c.source, c.truth);
  align_coarse(c.source, c.target);
  align_fine(c.source, c.target);
  const double after = mean_error(c.source, c.truth);
  EXPECT_LT(after, 0.7 * before);
  double distance = 0;
  for (const Vec3& p : c.source.positions()) distance += c.target.closest_point(p).distance;
  EXPECT_LT(distance / double(c.source.n_vertices()), 0.001 * diag);
}

TEST(Alignment, EnergiesDecrease) {
  Case c = make_case([](const Vec3& p) { return Vec3(p + Vec3(0.1, 0, 0)); });
  const CoarseReport cr = align_coarse(c.source, c.target, paper_scheme());
  ASSERT_FALSE(cr.energy_history.empty());
  EXPECT_LE(cr.energy_history.front(), cr.energy_start);
  EXPECT_LT(cr.fit_end, cr.fit_start);
  const FineReport fr = align_fine(c.source, c.target);
  EXPECT_LE(fr.energy_end, fr.energy_start);
  EXPECT_LT(fr.residual, 1e-6);
}

// The per-round report: one entry per round, alpha_reg relaxed by 10 between levels, each accepted step
// lowering the energy of its correspondences, and the PCG cap (an inexact Newton step) respected.
TEST(Alignment, RoundsAreReported) {
  Case c = make_case([](const Vec3& p) { return Vec3(rotation(20, Vec3(0, 0, 1)) * p + Vec3(0.05, 0, 0)); });
  CoarseParams p = paper_scheme();
  p.max_pcg_iterations = 4;
  const double edge = mean_edge_length(c.source);  // the unit of motion and fit_distance
  const CoarseReport r = align_coarse(c.source, c.target, p);
  ASSERT_EQ(int(r.rounds.size()), r.iterations);
  ASSERT_GT(r.iterations, 1);
  int pcg = 0;
  for (std::size_t i = 0; i < r.rounds.size(); ++i) {
    const CoarseRound& k = r.rounds[i];
    EXPECT_LE(k.energy, k.energy_before) << "round " << i;
    EXPECT_EQ(k.energy, r.energy_history[i]);
    EXPECT_GE(k.pcg_iterations, 0);
    EXPECT_LE(k.pcg_iterations, p.max_pcg_iterations);
    EXPECT_GE(k.motion, 0);
    EXPECT_GT(k.correspondences, 0u);
    pcg += k.pcg_iterations;
    if (i > 0) {
      const double ratio = r.rounds[i - 1].alpha_reg / k.alpha_reg;
      EXPECT_TRUE(ratio == 1 || std::abs(ratio - 10) < 1e-9) << "round " << i;
    }
  }
  EXPECT_EQ(pcg, r.pcg_iterations);
  EXPECT_EQ(r.rounds.front().alpha_reg, p.alpha_reg_start);
  EXPECT_EQ(r.rounds.back().alpha_reg, r.alpha_reg_end);
  EXPECT_NEAR(r.rounds.back().fit_distance * edge, r.mean_fit_distance, 1e-12);
  // Even with 4 PCG iterations per round the rotation is recovered.
  EXPECT_LT(mean_error(c.source, c.truth), 0.01 * c.target.bbox_diagonal());
}

// A turn of a few degrees, the tracker's consecutive frames: along the straight line A + t dA the
// rigidity term makes the line search cut the Gauss–Newton step at alpha_reg 1000 and the rounds crawl;
// retracted onto rotations the full steps are taken and the schedule ends sooner, as accurate.
TEST(Alignment, RotationStepsAreRetracted) {
  auto turn = [](const Vec3& p) { return Vec3(rotation(8, Vec3(0.2, 0.1, 1)) * p); };
  Case a = make_case(turn), b = make_case(turn);
  CoarseParams p = paper_scheme();
  const CoarseReport with = align_coarse(a.source, a.target, p);
  p.retract_rotations = false;
  const CoarseReport without = align_coarse(b.source, b.target, p);
  ASSERT_FALSE(with.rounds.empty());
  ASSERT_FALSE(without.rounds.empty());
  // Measured: first steps 1/4 vs 1/16, 23 rounds vs 40 (the cap), error 1.8e-5 vs 5.8e-5 of the diagonal.
  EXPECT_GE(with.rounds.front().step, 2 * without.rounds.front().step);
  EXPECT_LT(with.iterations, without.iterations);
  const double diag = a.target.bbox_diagonal();
  EXPECT_LT(mean_error(a.source, a.truth), 1e-4 * diag);
  EXPECT_LE(mean_error(a.source, a.truth), mean_error(b.source, b.truth));
  for (const CoarseRound& r : with.rounds) EXPECT_LE(r.energy, r.energy_before);
}

TEST(Alignment, FinePrunesBeyondSigma) {
  // Sphere plus a far-away sphere that has no counterpart: the far one must not move.
  test::FarSphereCase c = test::far_sphere_case();
  const std::vector<Vec3> before = c.mesh.positions();
  const FineReport fr = align_fine(c.mesh, c.target);
  EXPECT_EQ(fr.correspondences, c.near_vertices);
  test::expect_far_sphere_kept(c, before, fr.pruned);
}

// Further fine rounds while the matched vertices stay far from their hits: a unit sphere onto one with a
// spike (a Gaussian bump half its radius high), whose tip the smoothness term keeps the first round from
// reaching. Up to kLargeMotionFineRounds come closer to the target than the paper's one (the default); a
// target the sphere already lies on takes one round.
TEST(Alignment, FineRoundsContinueWhileFarFromTheMatches) {
  const test::Soup sphere = test::icosphere(4, 1.0);
  test::Soup spiky = test::icosphere(5, 1.0);
  for (Vec3& p : spiky.positions) p *= 1 + 0.5 * std::exp(-20 * (p - Vec3(0, 0, 1)).squaredNorm());
  const TargetSurface target(spiky.positions, spiky.triangles);
  auto distance = [&](const SurfaceMesh& m) {
    double d = 0;
    for (const Vec3& p : m.positions()) d += target.closest_point(p).distance;
    return d / double(m.positions().size()) / target.bbox_diagonal();
  };
  SurfaceMesh one = sphere.mesh(), more = sphere.mesh();
  FineParams large;
  large.max_rounds = kLargeMotionFineRounds;
  const FineReport r1 = align_fine(one, target);
  const FineReport rn = align_fine(more, target, large);
  EXPECT_EQ(r1.rounds, 1);
  EXPECT_GT(r1.mean_residual, FineParams{}.more_rounds_residual);
  EXPECT_GT(rn.rounds, 1);
  EXPECT_LE(rn.rounds, kLargeMotionFineRounds);
  EXPECT_LT(rn.mean_residual, r1.mean_residual);
  EXPECT_LT(distance(more), 0.7 * distance(one)) << distance(more) << " vs " << distance(one);

  SurfaceMesh on = sphere.mesh();
  const test::Soup same = test::icosphere(5, 1.0);
  const FineReport r0 = align_fine(on, TargetSurface(same.positions, same.triangles), large);
  EXPECT_EQ(r0.rounds, 1);
  EXPECT_LE(r0.mean_residual, FineParams{}.more_rounds_residual);
}

TEST(Alignment, ComponentsWithoutCounterpartStayFinite) {
  // The target has one component, the mesh two: no NaN, no throw, the matched sphere aligns.
  const test::Soup a = test::icosphere(3, 1.0);
  const test::Soup b = test::icosphere(3, 0.3, Vec3(3, 0, 0));
  SurfaceMesh mesh = test::merge(a, b).mesh();
  const test::Soup t = test::icosphere(4, 1.0, Vec3(0.1, 0, 0));
  const TargetSurface target(t.positions, t.triangles);
  EXPECT_NO_THROW(align_coarse(mesh, target));
  EXPECT_NO_THROW(align_fine(mesh, target));
  for (const Vec3& p : mesh.positions()) EXPECT_TRUE(p.allFinite());
  mesh.validate();
}

TEST(Alignment, AlignedInputStopsAfterTheFirstLevel) {
  // Source and target the same surface (different sampling): nothing to fit, so the schedule ends
  // once the first level has converged; with fit_tolerance 0 it runs down to alpha_reg_min. By
  // default the nodes are found fitted before the first step: no round at all, nothing moves.
  Case c = make_case([](const Vec3& p) { return p; });
  SurfaceMesh full = c.source.clone(), checked = c.source.clone();
  const std::vector<Vec3> before = c.source.positions();
  const CoarseReport none = align_coarse(checked, c.target);
  EXPECT_TRUE(none.fitted_at_start);
  EXPECT_EQ(none.levels, 0);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_GT(none.nodes, 20);
  EXPECT_GT(none.correspondences, 0u);
  EXPECT_LT(none.mean_fit_distance, 0.05 * mean_edge_length(c.source));
  EXPECT_EQ(checked.positions(), before);
  CoarseParams p;
  p.check_fit_first = false;
  const CoarseReport early = align_coarse(c.source, c.target, p);
  EXPECT_FALSE(early.fitted_at_start);
  EXPECT_EQ(early.levels, 1);
  EXPECT_GE(early.iterations, 1);
  EXPECT_LE(early.iterations, 3);
  EXPECT_LT(early.mean_fit_distance, 0.05 * mean_edge_length(c.source));
  EXPECT_EQ(early.nodes, none.nodes);
  p = CoarseParams{};
  p.fit_tolerance = 0;
  const CoarseReport all = align_coarse(full, c.target, p);
  EXPECT_EQ(all.levels, 5);
  EXPECT_DOUBLE_EQ(all.alpha_reg_end, 0.1);
  EXPECT_LT(mean_error(c.source, c.truth), 0.002 * c.target.bbox_diagonal());
}

// check_fit_first_tolerance: the test before the first step has its own threshold when set (align keeps 0.05
// there while its schedule runs down to a fit of 0.02 mean edge lengths).
TEST(Alignment, FittedFirstHasItsOwnTolerance) {
  const double edge = mean_edge_length(make_case([](const Vec3& p) { return p; }).source);
  const double shift = 0.02 * edge;  // the nodes lie within about this of the target
  auto run = [&](double fit_tolerance, double first_tolerance) {
    Case c = make_case([&](const Vec3& p) { return Vec3(p + Vec3(shift, 0, 0)); });
    CoarseParams p;
    p.fit_tolerance = fit_tolerance;
    p.check_fit_first_tolerance = first_tolerance;
    return align_coarse(c.source, c.target, p);
  };
  EXPECT_TRUE(run(0.05, 0).fitted_at_start);       // the default: fit_tolerance decides
  EXPECT_FALSE(run(0.001, 0).fitted_at_start);
  EXPECT_TRUE(run(0.001, 0.05).fitted_at_start);   // its own threshold
  const CoarseReport stepped = run(0.05, 0.001);
  EXPECT_FALSE(stepped.fitted_at_start);
  EXPECT_GE(stepped.iterations, 1);
}

TEST(Alignment, GraphDensityPreview) {
  Case c = make_case([](const Vec3& p) { return Vec3(p + Vec3(0.05, 0.02, 0)); });
  SurfaceMesh quarter = c.source.clone();
  CoarseParams p;
  const CoarseReport full = align_coarse(c.source, c.target, p);
  p.graph_density = 0.25;
  const CoarseReport q = align_coarse(quarter, c.target, p);
  EXPECT_LT(q.nodes, full.nodes / 2);
  EXPECT_LT(mean_error(quarter, c.truth), 0.5 * mean_error(c.source, c.truth) + 0.01 * c.target.bbox_diagonal());
}

TEST(Alignment, BadParametersThrow) {
  Case c = make_case([](const Vec3& p) { return p; });
  using FineSetting = void (*)(FineParams&);
  for (FineSetting bad : {+[](FineParams& q) { q.sigma = -1; }, +[](FineParams& q) { q.max_rounds = 0; },
                          +[](FineParams& q) { q.more_rounds_residual = std::nan(""); }}) {
    FineParams f;
    bad(f);
    EXPECT_THROW(align_fine(c.source, c.target, f), InvalidInput);
  }
  using CoarseSetting = void (*)(CoarseParams&);
  for (CoarseSetting bad : {
           +[](CoarseParams& q) { q.graph_density = 0; }, +[](CoarseParams& q) { q.step_tolerance = -1; },
           +[](CoarseParams& q) { q.intrinsic_pass_max_iterations_per_level = 0; },
           +[](CoarseParams& q) { q.check_fit_first_tolerance = std::nan(""); },
           +[](CoarseParams& q) { q.fit_tolerance = std::nan(""); }, +[](CoarseParams& q) { q.stall_ratio = -0.5; },
           +[](CoarseParams& q) { q.prealign_misfit = -1; },
           // checked even when the misfit does not call for the pre-alignment
           +[](CoarseParams& q) { q.prealign.trim_fraction = 0; },
           +[](CoarseParams& q) { q.closest_point_levels = -1; }, +[](CoarseParams& q) { q.backward_weight = -1; },
           +[](CoarseParams& q) { q.backward_misfit = -1; }, +[](CoarseParams& q) { q.backward_all_misfit = -1; },
           +[](CoarseParams& q) { q.backward_samples_per_node = 0; },
           +[](CoarseParams& q) { q.alpha_reg_start_after_pass = -1; },
           +[](CoarseParams& q) { q.alpha_reg_start_without_pass = std::nan(""); },
           +[](CoarseParams& q) { q.dense_spacing_factor = -1; }, +[](CoarseParams& q) { q.dense_alpha_reg = 0; },
           +[](CoarseParams& q) { q.min_nodes = -1; }, +[](CoarseParams& q) { q.min_node_spacing_factor = 0; },
           +[](CoarseParams& q) { q.near_pass_density = 1.5; }, +[](CoarseParams& q) { q.near_pass_density = std::nan(""); },
           +[](CoarseParams& q) { q.near_pass_misfit = -1; }, +[](CoarseParams& q) { q.near_pass_min_spacing = -1; },
           +[](CoarseParams& q) { q.near_pass_max_iterations_per_level = 0; },
           +[](CoarseParams& q) { q.vertex_fit_weight = -1; }, +[](CoarseParams& q) { q.vertex_fit_spacing = std::nan(""); },
           +[](CoarseParams& q) { q.vertex_fit_max_disagreement = -1; }}) {
    CoarseParams p;
    bad(p);
    EXPECT_THROW(align_coarse(c.source, c.target, p), InvalidInput);
  }
  SurfaceMesh empty;
  EXPECT_THROW(align_coarse(empty, c.target), InvalidInput);
}

TEST(Alignment, CholeskyBackendsAgree) {
  Case c1 = make_case([](const Vec3& p) { return Vec3(rotation(10, Vec3(0, 0, 1)) * p); });
  Case c2 = make_case([](const Vec3& p) { return Vec3(rotation(10, Vec3(0, 0, 1)) * p); });
  CoarseParams p;
  p.linear_solver = CoarseLinearSolver::Direct;  // the backend serves the direct solve only
  p.solver = CholeskyBackend::EigenLDLT;
  const CoarseReport a = align_coarse(c1.source, c1.target, p);
  p.solver = CholeskyBackend::Cholmod;
  const CoarseReport b = align_coarse(c2.source, c2.target, p);
  EXPECT_EQ(a.iterations, b.iterations);
  for (std::size_t i = 0; i < c1.source.vertices_size(); ++i)
    EXPECT_LT((c1.source.positions()[i] - c2.source.positions()[i]).norm(), 1e-6);
}

TEST(Alignment, SeparablePcgMatchesDirectSolve) {
  Case c1 = make_case([](const Vec3& p) { return Vec3(rotation(10, Vec3(0, 1, 1)) * p + Vec3(0.02, 0, 0)); });
  Case c2 = make_case([](const Vec3& p) { return Vec3(rotation(10, Vec3(0, 1, 1)) * p + Vec3(0.02, 0, 0)); });
  CoarseParams p = paper_scheme();
  p.linear_solver = CoarseLinearSolver::Direct;
  const CoarseReport a = align_coarse(c1.source, c1.target, p);
  p.linear_solver = CoarseLinearSolver::SeparablePCG;
  p.pcg_tolerance = 1e-10;
  p.max_pcg_iterations = 1000;
  const CoarseReport b = align_coarse(c2.source, c2.target, p);
  EXPECT_GT(b.pcg_iterations, 0);
  EXPECT_LT(b.factorisations, a.factorisations);
  const double diag = c1.target.bbox_diagonal();
  for (std::size_t i = 0; i < c1.source.vertices_size(); ++i)
    EXPECT_LT((c1.source.positions()[i] - c2.source.positions()[i]).norm(), 1e-4 * diag);
}

// CoarseParams::vertex_fit_weight: the vertices' fitting blocks (assembled for the direct solve, applied through the
// vertices in the PCG's matrix-free product) are the same system, and the data then sets the nodes' A_j: a bend, whose
// curvature between the nodes their matches alone leave to the regularisation, is fitted closer.
TEST(Alignment, VertexFitIsOneSystemForBothSolversAndFitsABendCloser) {
  const auto bend = [](const Vec3& p) { return Vec3(p.x() + 0.5 * p.z() * p.z(), p.y(), p.z()); };
  Case c0 = make_case(bend), c1 = make_case(bend), c2 = make_case(bend);
  CoarseParams p = paper_scheme();
  p.alpha_reg_min = 0.01;
  const auto to_target = [](const Case& c) {
    double d = 0;
    for (const Vec3& x : c.source.positions()) d += c.target.closest_point(x).distance;
    return d / double(c.source.n_vertices());
  };
  align_coarse(c0.source, c0.target, p);
  p.vertex_fit_weight = 10;
  p.vertex_fit_spacing = 0.5;
  p.linear_solver = CoarseLinearSolver::Direct;
  const CoarseReport a = align_coarse(c1.source, c1.target, p);
  p.linear_solver = CoarseLinearSolver::SeparablePCG;
  p.pcg_tolerance = 1e-10;
  p.max_pcg_iterations = 1000;
  const CoarseReport b = align_coarse(c2.source, c2.target, p);
  EXPECT_EQ(a.iterations, b.iterations);
  const double diag = c1.target.bbox_diagonal();
  for (std::size_t i = 0; i < c1.source.vertices_size(); ++i)
    ASSERT_LT((c1.source.positions()[i] - c2.source.positions()[i]).norm(), 1e-4 * diag) << "vertex " << i;
  std::printf("bend: ground-truth error %.5f nodes only, %.5f with the vertices; to the target %.6f / %.6f\n",
              mean_error(c0.source, c0.truth), mean_error(c2.source, c2.truth), to_target(c0), to_target(c2));
  EXPECT_LT(to_target(c2), 0.85 * to_target(c0));  // measured 0.00120 vs 0.00153 (ground truth 0.0330 vs 0.0331)
  EXPECT_LT(mean_error(c2.source, c2.truth), mean_error(c0.source, c0.truth));
  for (const CoarseRound& r : b.rounds) EXPECT_LE(r.energy, r.energy_before);
}

// CoarseParams::vertex_fit_max_disagreement: vertex matches that would move their vertices two node spacings off their
// nodes' motion are all pruned (the result is the nodes' fit alone, bit for bit); without the test they are followed.
TEST(Alignment, VertexMatchesThatDisagreeWithTheirNodesArePruned) {
  const Eigen::Matrix3d R = rotation(10, Vec3(0, 1, 1));
  const auto run = [&](double weight, double disagreement) {
    Case c = make_case([&](const Vec3& p) { return Vec3(R * p); });
    CoarseParams p = paper_scheme();
    p.vertex_fit_weight = weight;
    p.vertex_fit_max_disagreement = disagreement;  // every vertex (spacing 0): its rounds are told by their size
    const std::size_t nv = c.source.n_vertices();
    int vertex_rounds = 0;
    p.match_override = [&](const CoarseMatchRound& round, std::vector<Correspondence>& corr) {
      if (round.nodes.size() != nv) return;
      ++vertex_rounds;
      for (Correspondence& m : corr)
        if (m.valid()) m.point += 2 * 4 * mean_edge_length(c.source) * m.normal;  // two node spacings off
    };
    align_coarse(c.source, c.target, p);
    EXPECT_EQ(vertex_rounds > 0, weight > 0);
    return c.source.positions();
  };
  const std::vector<Vec3> nodes_only = run(0, 1), pruned = run(10, 1), followed = run(10, 0);
  ASSERT_EQ(nodes_only.size(), pruned.size());
  for (std::size_t i = 0; i < nodes_only.size(); ++i) ASSERT_EQ(nodes_only[i], pruned[i]) << "vertex " << i;
  double moved = 0;
  for (std::size_t i = 0; i < nodes_only.size(); ++i) moved = std::max(moved, (nodes_only[i] - followed[i]).norm());
  EXPECT_GT(moved, mean_edge_length(make_case([](const Vec3& p) { return p; }).source));
}

// CoarseParams::alpha_reg_start_after_pass: the full graph's first round after the low-density pass, and only then;
// alpha_reg_start_without_pass: where the misfit called for no pass, and only then.
TEST(Alignment, FullGraphStartsAtTheAlphaRegOfWhetherThePassRan) {
  const Eigen::Matrix3d R = rotation(15, Vec3(1, 1, 0));
  enum Pass { Runs, BelowItsMisfit, Off };
  auto first_alpha = [&](double start_after_pass, double start_without_pass, Pass pass) {
    Case c = make_case([&](const Vec3& p) { return Vec3(R * p * 1.1); });
    CoarseParams q;
    q.check_fit_first = false;
    q.alpha_reg_start_after_pass = start_after_pass;
    q.alpha_reg_start_without_pass = start_without_pass;
    if (pass == BelowItsMisfit) q.coarse_pass_misfit = 1e9;
    if (pass == Off) q.coarse_pass_misfit = 0;
    const CoarseReport r = align_coarse(c.source, c.target, q);
    EXPECT_EQ(r.coarse_pass_iterations > 0, pass == Runs);
    EXPECT_FALSE(r.rounds.empty());
    return r.rounds.empty() ? 0.0 : r.rounds.front().alpha_reg;
  };
  EXPECT_EQ(first_alpha(0, 0, Runs), 1000);  // the paper's start
  EXPECT_EQ(first_alpha(10, 0, Runs), 10);
  EXPECT_EQ(first_alpha(10, 0, Off), 1000);  // no pass: the paper's schedule
  EXPECT_EQ(first_alpha(10, 0, BelowItsMisfit), 1000);
  EXPECT_EQ(first_alpha(10, 30, BelowItsMisfit), 30);
  EXPECT_EQ(first_alpha(10, 30, Runs), 10);
  EXPECT_EQ(first_alpha(0, 30, Off), 1000);  // the pass switched off: no misfit called for none
  // `align` sets it, with the lower end of the schedule.
  CoarseParams q;
  FineParams f;
  use_large_motion_alignment(q, f);
  EXPECT_EQ(q.alpha_reg_start_after_pass, kLargeMotionAlphaRegStartAfterPass);
  EXPECT_EQ(q.alpha_reg_start_without_pass, kLargeMotionAlphaRegStartWithoutPass);
  EXPECT_EQ(CoarseParams{}.alpha_reg_start_without_pass, 0);  // the library's (and the tracker's): the paper's 1000
  EXPECT_EQ(q.alpha_reg_min, kLargeMotionAlphaRegMin);
  EXPECT_EQ(q.fit_tolerance, kLargeMotionFitTolerance);
  EXPECT_EQ(q.check_fit_first_tolerance, kLargeMotionCheckFitFirstTolerance);
}

// CoarseParams::near_pass_density: the low-density pass's graph where the misfit is below near_pass_misfit, and only there.
TEST(Alignment, NearPassDensityWhereTheMisfitIsSmall) {
  const Eigen::Matrix3d R = rotation(15, Vec3(1, 1, 0));
  int quarter_nodes = 1 << 30;
  auto pass_nodes = [&](double near_density, double near_misfit, double min_spacing = 0) {
    Case c = make_case([&](const Vec3& p) { return Vec3(R * p * 1.1); });
    CoarseParams q;
    q.check_fit_first = false;
    q.near_pass_density = near_density;
    q.near_pass_misfit = near_misfit;
    q.near_pass_min_spacing = min_spacing;
    const CoarseReport r = align_coarse(c.source, c.target, q);
    EXPECT_GT(r.coarse_pass_iterations, 0);
    EXPECT_GT(r.misfit_start, 0.004);
    EXPECT_LT(r.misfit_start, 0.5);
    // near_pass_max_iterations_per_level on the near pass's five levels (1000 to 0.1), max_iterations_per_level's 8 otherwise
    if (r.low_density.nodes > quarter_nodes) {
      EXPECT_LE(r.low_density.rounds, 5 * q.near_pass_max_iterations_per_level);
    }
    return r.low_density.nodes;
  };
  const int quarter = quarter_nodes = pass_nodes(0, 0.5);  // the library's default: a quarter at any misfit
  const int near = pass_nodes(kLargeMotionNearPassDensity, 0.5);
  EXPECT_GT(quarter, 0);
  // 4/9 of the full graph's density instead of 1/4: about 1.8 times the nodes
  EXPECT_GT(near, 1.4 * quarter);
  EXPECT_LT(near, 2.4 * quarter);
  EXPECT_EQ(pass_nodes(kLargeMotionNearPassDensity, 0.004), quarter);  // the misfit above near_pass_misfit
  EXPECT_EQ(pass_nodes(kLargeMotionNearPassDensity, 0.5, 1.0), quarter);  // a spacing floor never sparser than the quarter
  // A floor between the near pass's spacing (1.5 full-graph spacings) and the quarter's (2): a density between theirs.
  Case c = make_case([&](const Vec3& p) { return Vec3(R * p * 1.1); });
  const double full_spacing = align_coarse(c.source, c.target, CoarseParams{}).node_spacing / c.target.bbox_diagonal();
  const int between = pass_nodes(kLargeMotionNearPassDensity, 0.5, 1.75 * full_spacing);
  EXPECT_LT(between, near);
  EXPECT_GT(between, quarter);
  CoarseParams q;
  FineParams f;
  use_large_motion_alignment(q, f);
  EXPECT_EQ(q.near_pass_density, kLargeMotionNearPassDensity);
  EXPECT_EQ(CoarseParams{}.near_pass_density, 0);
}

// CoarseParams::dense_spacing_factor: one level on a denser graph where the low-density pass did not run, and only there.
TEST(Alignment, DenseGraphEndsAPairWithoutThePass) {
  const Eigen::Matrix3d R = rotation(8, Vec3(1, 1, 0));
  auto transform = [&](const Vec3& p) { return Vec3(R * Vec3(1.1 * p.x(), p.y(), 0.95 * p.z())); };
  auto run = [&](double dense_spacing, bool pass, std::vector<CoarseStage>* stages = nullptr) {
    Case c = make_case(transform);
    CoarseParams q;
    q.check_fit_first = false;
    q.dense_spacing_factor = dense_spacing;
    if (!pass) q.coarse_pass_misfit = 0;
    if (stages) q.observer = [&](const CoarseSnapshot& s) { stages->push_back(s.stage); };
    const CoarseReport r = align_coarse(c.source, c.target, q);
    EXPECT_EQ(r.coarse_pass_iterations > 0, pass);
    return std::pair{r, mean_error(c.source, c.truth)};
  };
  std::vector<CoarseStage> stages;
  const auto [dense, dense_error] = run(2.5, false, &stages);
  const auto [plain, plain_error] = run(0, false);
  EXPECT_EQ(plain.dense.rounds, 0);
  EXPECT_GT(dense.dense.rounds, 0);
  EXPECT_LE(dense.dense.rounds, CoarseParams{}.max_iterations_per_level);  // one level
  EXPECT_GT(dense.dense.nodes, 2 * dense.nodes);                           // (4 / 2.5)^2 = 2.56 times the nodes
  EXPECT_EQ(dense.nodes, plain.nodes);
  EXPECT_EQ(dense.iterations, plain.iterations);  // the schedule before it unchanged
  ASSERT_FALSE(stages.empty());
  EXPECT_EQ(stages.back(), CoarseStage::DenseLevel);
  EXPECT_EQ(std::count(stages.begin(), stages.end(), CoarseStage::DenseLevel), 1);
  EXPECT_LT(dense_error, plain_error);
  EXPECT_GE(dense.seconds_total, dense.dense.seconds_total);
  // Where the low-density pass ran, none.
  const Eigen::Matrix3d R2 = rotation(15, Vec3(1, 1, 0));
  Case c = make_case([&](const Vec3& p) { return Vec3(R2 * p * 1.1); });
  CoarseParams q;
  q.check_fit_first = false;
  q.dense_spacing_factor = 2.5;
  const CoarseReport with_pass = align_coarse(c.source, c.target, q);
  EXPECT_GT(with_pass.coarse_pass_iterations, 0);
  EXPECT_EQ(with_pass.dense.rounds, 0);
  // Nor where the nodes were found fitted before the first round.
  Case fitted = make_case([](const Vec3& p) { return p; });
  q = CoarseParams{};
  q.dense_spacing_factor = 2.5;
  const CoarseReport none = align_coarse(fitted.source, fitted.target, q);
  EXPECT_TRUE(none.fitted_at_start);
  EXPECT_EQ(none.dense.rounds, 0);
  // `align` sets it.
  FineParams f;
  q = CoarseParams{};
  use_large_motion_alignment(q, f);
  EXPECT_EQ(q.dense_spacing_factor, kLargeMotionDenseSpacingFactor);
  EXPECT_EQ(CoarseParams{}.dense_spacing_factor, 0);  // the library's (and the tracker's) default: none
}

// CoarseParams::min_nodes: a mesh whose paper spacing gives too few nodes gets a denser graph; others are untouched.
TEST(Alignment, MinNodesGivesASmallMeshEnoughNodes) {
  const Eigen::Matrix3d R = rotation(8, Vec3(1, 1, 0));
  auto transform = [&](const Vec3& p) { return Vec3(R * Vec3(1.1 * p.x(), p.y(), 0.95 * p.z())); };
  auto run = [&](int min_nodes, double floor = 2.5) {
    Case c = make_case(transform);
    const double edge = mean_edge_length(c.source);
    CoarseParams q;
    q.check_fit_first = false;
    q.min_nodes = min_nodes;
    q.min_node_spacing_factor = floor;
    const CoarseReport r = align_coarse(c.source, c.target, q);
    return std::tuple{r, r.node_spacing / edge, c.source.positions()};
  };
  const auto [paper, paper_factor, paper_out] = run(0);
  EXPECT_NEAR(paper_factor, 4, 1e-9);
  // The nodes the paper's spacing gives on the mesh as it comes (the full graph's, sampled after the low-density
  // pass, may differ).
  const SurfaceMesh rest = make_case(transform).source;
  const int n = int(sample_graph_nodes(rest, 4 * mean_edge_length(rest)).size());
  // No more than those: nothing changes, bit for bit.
  const auto [same, same_factor, same_out] = run(n);
  EXPECT_EQ(same.nodes, paper.nodes);
  EXPECT_EQ(same.iterations, paper.iterations);
  EXPECT_EQ(same_out, paper_out);
  // Twice those: the spacing shrinks by sqrt(2), the graph grows.
  const auto [denser, denser_factor, denser_out] = run(2 * n, 1);
  EXPECT_NEAR(denser_factor, 4 / std::sqrt(2.0), 1e-9);
  EXPECT_GT(denser.nodes, 3 * paper.nodes / 2);
  // Never below the floor.
  const auto [floored, floored_factor, floored_out] = run(100 * n);
  EXPECT_NEAR(floored_factor, 2.5, 1e-9);
  // A graph as dense as the denser graph's: that level does not run.
  Case c = make_case(transform);
  CoarseParams q;
  q.check_fit_first = false;
  q.coarse_pass_misfit = 0;
  q.dense_spacing_factor = 2.5;
  EXPECT_GT(align_coarse(c.source, c.target, q).dense.rounds, 0);
  c = make_case(transform);
  q.min_nodes = 100 * n;
  EXPECT_EQ(align_coarse(c.source, c.target, q).dense.rounds, 0);
  // `align` sets it; the library (and the tracker) do not.
  q = CoarseParams{};
  FineParams f;
  use_large_motion_alignment(q, f);
  EXPECT_EQ(q.min_nodes, kLargeMotionMinNodes);
  EXPECT_EQ(CoarseParams{}.min_nodes, 0);
}

// CoarseParams::backward_vertex_weight: where every node would get backward matches, `align` makes them at the fitted
// vertices instead; nowhere else, and not in the library's defaults.
TEST(Alignment, BackwardMatchesAtTheFittedVerticesWhereEveryNodeGetsThem) {
  const Eigen::Matrix3d R = rotation(70, Vec3(0.2, 1, 0.4));
  auto transform = [&](const Vec3& p) { return Vec3(R * p + Vec3(0.6, -0.3, 0.2)); };
  auto run = [&](double weight, double vertex_fit, CoarseReport* report) {
    Case c = make_case(transform);
    CoarseParams q;
    FineParams f;
    use_large_motion_alignment(q, f);
    q.backward_vertex_weight = weight;
    q.vertex_fit_weight = vertex_fit;
    q.check_fit_first = false;  // the full graph runs its rounds (else the pass may leave it fitted at the start)
    *report = align_coarse(c.source, c.target, q);
    double error = 0;
    for (std::size_t i = 0; i < c.truth.size(); ++i) error += (c.source.positions()[i] - c.truth[i]).norm();
    return std::make_pair(c.source.positions(), error / double(c.truth.size()) / c.target.bbox_diagonal());
  };
  CoarseReport at_nodes, at_vertices, unfitted;
  const auto [x_nodes, e_nodes] = run(0, kLargeMotionVertexFitWeight, &at_nodes);
  const auto [x_vertices, e_vertices] = run(kLargeMotionBackwardVertexWeight, kLargeMotionVertexFitWeight, &at_vertices);
  run(kLargeMotionBackwardVertexWeight, 0, &unfitted);
  EXPECT_TRUE(at_nodes.backward_all);
  EXPECT_FALSE(at_nodes.backward_at_vertices);
  EXPECT_TRUE(at_vertices.backward_at_vertices);
  EXPECT_FALSE(unfitted.backward_at_vertices);  // no fitted vertices: at the nodes
  EXPECT_NE(x_nodes, x_vertices);
  EXPECT_LT(e_vertices, 0.01);
  EXPECT_LT(e_nodes, 0.01);
  // Below the every-node misfit the pruned nodes keep theirs: nothing changes.
  const Eigen::Matrix3d R2 = rotation(8, Vec3(1, 1, 0));
  for (const double weight : {0.0, kLargeMotionBackwardVertexWeight}) {
    Case c = make_case([&](const Vec3& p) { return Vec3(R2 * p); });
    CoarseParams q;
    FineParams f;
    use_large_motion_alignment(q, f);
    q.backward_vertex_weight = weight;
    EXPECT_FALSE(align_coarse(c.source, c.target, q).backward_at_vertices);
  }
  CoarseParams q;
  FineParams f;
  use_large_motion_alignment(q, f);
  EXPECT_EQ(q.backward_vertex_weight, kLargeMotionBackwardVertexWeight);
  EXPECT_EQ(CoarseParams{}.backward_vertex_weight, 0);
}

TEST(Alignment, OneAndTwoThreadsGiveIdenticalResults) {
  auto run = [](int threads) {
    tbb::task_arena arena(threads);
    std::vector<Vec3> out;
    arena.execute([&] {
      const Eigen::Matrix3d R = rotation(15, Vec3(1, 1, 0));
      Case c = make_case([&](const Vec3& p) { return Vec3(R * p * 1.1); });
      EXPECT_GT(align_coarse(c.source, c.target).coarse_pass_iterations, 0);
      align_fine(c.source, c.target);
      out = c.source.positions();
      // Large motion: rigid pre-alignment, low-density pass, full graph.
      const Eigen::Matrix3d R2 = rotation(70, Vec3(0.2, 1, 0.4));
      Case d = make_case([&](const Vec3& p) { return Vec3(R2 * p + Vec3(0.6, -0.3, 0.2)); });
      EXPECT_TRUE(align_coarse(d.source, d.target).prealigned);
      out.insert(out.end(), d.source.positions().begin(), d.source.positions().end());
      // `align`'s configuration, every node off its intrinsic place counted misplaced: a guided pass runs on
      // the first pass's graph.
      Case e = make_case([&](const Vec3& p) { return Vec3(R2 * p + Vec3(0.6, -0.3, 0.2)); });
      CoarseParams q;
      FineParams f;
      use_large_motion_alignment(q, f);
      q.intrinsic.misplaced_spacings = 0;
      q.check_fit_first = false;  // the first pass runs its rounds (else it may find itself fitted, with no graph)
      const double e_edge = mean_edge_length(e.source);
      const std::vector<Vec3> e_rest = e.source.positions();
      const CoarseReport er = align_coarse(e.source, e.target, q);
      EXPECT_TRUE(er.backward_at_vertices);  // the misfit gives every node backward matches: at the vertices
      EXPECT_LT(er.node_spacing, 3 * e_edge);  // min_nodes: the blob's few vertices
      EXPECT_EQ(er.intrinsic_passes, 1);
      EXPECT_EQ(er.low_density.rounds, er.coarse_pass_iterations);
      EXPECT_GT(er.low_density.factorisations, 1);  // the first pass's and the guided pass's
      const FineReport fr = align_fine(e.source, e.target, f, e_rest);  // with the relaxation on the target
      EXPECT_EQ(fr.relax.iterations, kLargeMotionRelaxIterations);
      out.insert(out.end(), e.source.positions().begin(), e.source.positions().end());
      // `align`'s configuration where the pass does not run: the denser graph's level.
      const Eigen::Matrix3d R3 = rotation(8, Vec3(1, 1, 0));
      Case g = make_case([&](const Vec3& p) { return Vec3(R3 * p); });
      q.coarse_pass_misfit = 0;
      q.min_nodes = 0;  // else the blob's graph is as dense as the denser graph's, which then does not run
      EXPECT_GT(align_coarse(g.source, g.target, q).dense.rounds, 0);
      out.insert(out.end(), g.source.positions().begin(), g.source.positions().end());
    });
    return out;
  };
  const std::vector<Vec3> a = run(1), b = run(2);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) ASSERT_EQ(a[i], b[i]) << "vertex " << i;
}

TEST(Projection, MovesVerticesOntoTarget) {
  SurfaceMesh mesh = test::icosphere(3, 1.2).mesh();
  const test::Soup t = test::icosphere(5, 1.0);
  const TargetSurface target(t.positions, t.triangles);
  project_to_closest(mesh, target);
  for (const Vec3& p : mesh.positions()) EXPECT_NEAR(p.norm(), 1.0, 1e-3);
}

}  // namespace
}  // namespace topotrack
