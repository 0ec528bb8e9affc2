// Intrinsic matches (kernels/registration/intrinsic_matches.hpp) and the edge graph's distances
// (kernels/mesh/edge_graph.hpp) on small closed shapes.
#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <queue>
#include <random>
#include <vector>

#include "kernels/mesh/edge_graph.hpp"
#include "kernels/registration/intrinsic_matches.hpp"
#include "tests/kernels/registration/blob.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

TEST(EdgeGraph, DistancesAlongTheSurface) {
  const test::Soup s = test::icosphere(4, 1.0);
  const EdgeGraph g = edge_graph(s.positions, s.triangles);
  EXPECT_EQ(g.n_vertices(), s.positions.size());
  // Each triangle edge appears once per direction, neighbours ascending.
  std::size_t entries = 0;
  for (Index v = 0; v < g.n_vertices(); ++v) {
    for (Index i = g.offset[v] + 1; i < g.offset[v + 1]; ++i) EXPECT_LT(g.target[i - 1], g.target[i]);
    entries += g.offset[v + 1] - g.offset[v];
  }
  EXPECT_EQ(entries, 3 * s.triangles.size());  // closed: E = 3F/2 edges, both ways
  EXPECT_EQ(edge_graph(s.mesh()).offset.back(), g.offset.back());
  // From the north pole to the south pole: half the great circle, pi, overestimated by Dijkstra over edges
  // by a few percent, never under.
  Index north = 0, south = 0;
  for (Index v = 0; v < s.positions.size(); ++v) {
    if (s.positions[v].z() > s.positions[north].z()) north = v;
    if (s.positions[v].z() < s.positions[south].z()) south = v;
  }
  std::vector<float> d = geodesic_distances(g, std::vector<Index>{north})[0];
  EXPECT_EQ(d[north], 0.0f);
  EXPECT_GT(d[south], 0.99 * std::numbers::pi);
  EXPECT_LT(d[south], 1.10 * std::numbers::pi);
  // Another component is unreached.
  test::Soup two = test::merge(s, test::icosphere(1, 0.2, Vec3(5, 0, 0)));
  d = geodesic_distances(edge_graph(two.positions, two.triangles), std::vector<Index>{north})[0];
  EXPECT_TRUE(std::isinf(d.back()));
  // Poisson-disk samples: no two closer than the spacing, every vertex within it of one.
  const double spacing = 0.5;
  const std::vector<Index> samples = poisson_disk_samples(g, spacing);
  std::vector<float> nearest(g.n_vertices(), std::numeric_limits<float>::infinity());
  const std::vector<std::vector<float>> from_samples = geodesic_distances(g, samples);
  ASSERT_EQ(from_samples.size(), samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const Index a = samples[i];
    d = from_samples[i];
    for (const Index b : samples) {
      if (b == a) continue;
      EXPECT_GE(d[b], spacing * (1 - 1e-6));
    }
    for (Index v = 0; v < g.n_vertices(); ++v) nearest[v] = std::min(nearest[v], d[v]);
  }
  for (const float x : nearest) EXPECT_LT(x, spacing);
}

// The source is the bumpy blob, the target the same shape meshed finer. Where the nodes are now: on the
// target at their own places, but for a cap around the +x tip, turned by 90 degrees about z onto the
// blob's +y side (a limb laid where another part is). The cap's nodes, and only they, are found misplaced
// and placed near where they belong; with every node in place nothing is.
TEST(IntrinsicMatches, FindAndPlaceACapLaidOnAnotherPart) {
  const test::Soup src = test::blob(4), tgt = test::blob(5);
  const EdgeGraph source = edge_graph(src.positions, src.triangles);
  const TargetSurface target(tgt.positions, tgt.triangles);
  const EdgeGraph target_graph = edge_graph(tgt.positions, tgt.triangles);
  const double spacing = 0.25;
  const std::vector<Index> nodes = poisson_disk_samples(source, spacing);
  const Vec3 tip(1.2, 0, 0);  // the blob's +x end (semi-axis 1, bumps to 1.25)
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(std::numbers::pi / 2, Vec3::UnitZ()).toRotationMatrix();
  std::vector<Vec3> truth(nodes.size()), now(nodes.size());
  std::vector<char> in_cap(nodes.size());
  std::size_t cap = 0;
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    truth[j] = src.positions[nodes[j]];
    in_cap[j] = (truth[j] - tip).norm() < 0.45;
    cap += in_cap[j];
    now[j] = in_cap[j] ? target.closest_point(turn * truth[j]).point : truth[j];
  }
  ASSERT_GE(cap, 5u);
  ASSERT_LE(cap, nodes.size() / 5);
  const IntrinsicAnchors anchors = intrinsic_anchors(source, nodes, truth);
  std::vector<Vec3> anchor_now;
  for (const Index a : anchors.anchor)
    for (std::size_t j = 0; j < nodes.size(); ++j)
      if (nodes[j] == a) anchor_now.push_back(now[j]);
  ASSERT_EQ(anchor_now.size(), anchors.anchor.size());

  const IntrinsicMatches im = intrinsic_matches(anchors, anchor_now, nodes, now, target, target_graph, spacing);
  EXPECT_LT(im.kept, im.anchors);  // the cap's anchors dropped
  EXPECT_NEAR(im.scale, 1.0, 0.1);
  std::size_t found = 0;
  for (std::size_t j = 0; j < nodes.size(); ++j) {
    if (!im.match[j].valid()) continue;
    EXPECT_TRUE(in_cap[j]) << "node " << j << " at " << truth[j].transpose();
    found += in_cap[j];
    EXPECT_LT((im.match[j].point - truth[j]).norm(), 1.5 * spacing) << "node " << j;
  }
  EXPECT_EQ(found, im.misplaced);
  EXPECT_GE(found, cap * 3 / 4) << "of " << cap;  // measured: all 5 of 5, 3 of 32 anchors dropped

  std::vector<Vec3> anchor_truth;
  for (const Index a : anchors.anchor) anchor_truth.push_back(src.positions[a]);
  const IntrinsicMatches none = intrinsic_matches(anchors, anchor_truth, nodes, truth, target, target_graph, spacing);
  EXPECT_EQ(none.misplaced, 0u);
  EXPECT_EQ(none.kept, none.anchors);

  // A cache shared by both matchings (the second reuses the fields of the anchors whose matches did not move)
  // changes nothing.
  IntrinsicTargetCache cache;
  const auto same = [](const IntrinsicMatches& a, const IntrinsicMatches& b) {
    ASSERT_EQ(a.match.size(), b.match.size());
    EXPECT_EQ(a.kept, b.kept);
    EXPECT_EQ(a.misplaced, b.misplaced);
    EXPECT_EQ(a.scale, b.scale);
    for (std::size_t j = 0; j < a.match.size(); ++j) {
      EXPECT_EQ(a.match[j].status, b.match[j].status);
      EXPECT_EQ(a.match[j].point, b.match[j].point);
    }
  };
  same(intrinsic_matches(anchors, anchor_now, nodes, now, target, target_graph, spacing, {}, &cache), im);
  const std::size_t fields = cache.source.size();
  EXPECT_EQ(fields, anchors.anchor.size());
  same(intrinsic_matches(anchors, anchor_truth, nodes, truth, target, target_graph, spacing, {}, &cache), none);
  EXPECT_GT(cache.source.size(), fields);                        // the cap's anchors moved: new fields
  EXPECT_LT(cache.source.size(), 2 * anchors.anchor.size());     // the others' were reused
}

// A textbook Dijkstra in float arithmetic (binary heap of (distance, vertex), the mesh's own numbering):
// what geodesic_distances must reproduce exactly, whatever its queue, layout or thread count.
std::vector<float> reference_distances(const EdgeGraph& g, Index source) {
  std::vector<float> dist(g.n_vertices(), std::numeric_limits<float>::infinity());
  std::priority_queue<std::pair<float, Index>, std::vector<std::pair<float, Index>>, std::greater<>> queue;
  dist[source] = 0;
  queue.push({0.0f, source});
  while (!queue.empty()) {
    const auto [d, u] = queue.top();
    queue.pop();
    if (d > dist[u]) continue;
    for (Index i = g.offset[u]; i < g.offset[u + 1]; ++i)
      if (const float nd = d + float(g.length[i]); nd < dist[g.target[i]]) {
        dist[g.target[i]] = nd;
        queue.push({nd, g.target[i]});
      }
  }
  return dist;
}

TEST(EdgeGraph, DistanceFieldsAreExactlyDijkstrasOnAnyThreadCount) {
  // Two components (one unreached from the other), the vertices numbered at random (as a resampled
  // mesh's are), edges of many lengths (a stretched, jittered sphere), and a repeated source.
  test::Soup s = test::merge(test::icosphere(4, 1.0), test::icosphere(2, 0.3, Vec3(3, 0, 0)));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  for (Vec3& p : s.positions) p = Vec3(2.0 * p.x(), p.y(), 0.5 * p.z()) + Vec3(jitter(rng), jitter(rng), jitter(rng));
  std::vector<Index> perm(s.positions.size());
  std::iota(perm.begin(), perm.end(), Index(0));
  std::shuffle(perm.begin(), perm.end(), rng);
  std::vector<Vec3> shuffled(s.positions.size());
  for (std::size_t v = 0; v < perm.size(); ++v) shuffled[perm[v]] = s.positions[v];
  for (auto& t : s.triangles)
    for (Index& v : t) v = perm[v];
  s.positions = shuffled;
  const EdgeGraph g = edge_graph(s.positions, s.triangles);
  const std::vector<Index> sources = {0, 17, Index(g.n_vertices() - 1), 17, Index(g.n_vertices() / 2)};
  std::vector<std::vector<float>> by_threads[2];
  for (int threads = 1; threads <= 2; ++threads) {
    const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, std::size_t(threads));
    by_threads[threads - 1] = geodesic_distances(g, sources);
  }
  ASSERT_EQ(by_threads[0].size(), sources.size());
  std::size_t unreached = 0;
  for (std::size_t a = 0; a < sources.size(); ++a) {
    const std::vector<float> ref = reference_distances(g, sources[a]);
    ASSERT_EQ(by_threads[0][a].size(), ref.size());
    for (std::size_t v = 0; v < ref.size(); ++v) {
      ASSERT_EQ(std::bit_cast<std::uint32_t>(by_threads[0][a][v]), std::bit_cast<std::uint32_t>(ref[v])) << a << " " << v;
      ASSERT_EQ(std::bit_cast<std::uint32_t>(by_threads[1][a][v]), std::bit_cast<std::uint32_t>(ref[v])) << a << " " << v;
      unreached += std::isinf(ref[v]);
    }
  }
  EXPECT_GT(unreached, 0u);  // the other component
  EXPECT_TRUE(geodesic_distances(g, std::vector<Index>{}).empty());
  EXPECT_THROW(geodesic_distances(g, std::vector<Index>{Index(g.n_vertices())}), InvalidInput);
}

TEST(IntrinsicMatches, BadInputThrows) {
  const test::Soup s = test::icosphere(2, 1.0);
  const EdgeGraph g = edge_graph(s.positions, s.triangles);
  const TargetSurface target(s.positions, s.triangles);
  const std::vector<Index> nodes = {0, 1, 2};
  const std::vector<Vec3> x = {s.positions[0], s.positions[1], s.positions[2]};
  EXPECT_THROW(intrinsic_anchors(g, nodes, std::vector<Vec3>{s.positions[0]}), InvalidInput);
  EXPECT_THROW(intrinsic_anchors(g, std::vector<Index>{Index(s.positions.size())}, std::vector<Vec3>{Vec3::Zero()}),
               InvalidInput);
  EXPECT_THROW(intrinsic_anchors(g, nodes, x, 1), InvalidInput);
  const IntrinsicAnchors a = intrinsic_anchors(g, nodes, x);
  std::vector<Vec3> ax;
  for (const Index v : a.anchor) ax.push_back(s.positions[v]);
  EXPECT_THROW(intrinsic_matches(a, ax, nodes, std::vector<Vec3>{}, target, g, 0.3), InvalidInput);
  EXPECT_THROW(intrinsic_matches(a, ax, nodes, x, target, g, 0), InvalidInput);
  const test::Soup other = test::icosphere(1, 1.0);
  EXPECT_THROW(intrinsic_matches(a, ax, nodes, x, target, edge_graph(other.positions, other.triangles), 0.3),
               InvalidInput);
}

}  // namespace
}  // namespace topotrack
