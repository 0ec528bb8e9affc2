#include "kernels/registration/intrinsic_matches.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace topotrack {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// The target vertex nearest to where `x` is closest to the target.
Index nearest_target_vertex(const TargetSurface& target, const Vec3& x) {
  const TargetSurface::Hit hit = target.closest_point(x);
  const auto& tri = target.triangles()[hit.face];
  const auto& P = target.positions();
  Index best = tri[0];
  for (int c = 1; c < 3; ++c)
    if ((P[tri[c]] - hit.point).squaredNorm() < (P[best] - hit.point).squaredNorm()) best = tri[c];
  return best;
}

double median(std::vector<double> v) {
  if (v.empty()) return 1;
  const auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

IntrinsicAnchors intrinsic_anchors(const EdgeGraph& source, std::span<const Index> candidates,
                                   std::span<const Vec3> position, int anchors) {
  for (const Index v : candidates)
    if (v >= source.n_vertices()) TT_THROW(InvalidInput, "intrinsic_anchors: vertex " << v << " out of range");
  if (position.size() != candidates.size())
    TT_THROW(InvalidInput, "intrinsic_anchors: " << candidates.size() << " vertices but " << position.size() << " positions");
  if (anchors < 2) TT_THROW(InvalidInput, "intrinsic_anchors: fewer than two anchors asked for");
  IntrinsicAnchors out;
  // Farthest-point sampling in space (cheap, and the geodesic distances below then run in parallel).
  const std::size_t nc = candidates.size(), na = std::min<std::size_t>(std::size_t(anchors), nc);
  std::vector<double> nearest(nc, kInf);
  std::size_t next = 0;
  while (out.anchor.size() < na) {
    out.anchor.push_back(candidates[next]);
    for (std::size_t j = 0; j < nc; ++j) nearest[j] = std::min(nearest[j], (position[j] - position[next]).squaredNorm());
    next = std::size_t(std::max_element(nearest.begin(), nearest.end()) - nearest.begin());
    if (!(nearest[next] > 0)) break;  // every candidate is an anchor
  }
  out.distance = geodesic_distances(source, out.anchor);
  return out;
}

IntrinsicMatches intrinsic_matches(const IntrinsicAnchors& anchors, std::span<const Vec3> anchor_x,
                                   std::span<const Index> nodes, std::span<const Vec3> node_x,
                                   const TargetSurface& target, const EdgeGraph& target_graph, double spacing,
                                   const IntrinsicParams& params, IntrinsicTargetCache* cache) {
  if (nodes.size() != node_x.size() || anchors.anchor.size() != anchor_x.size())
    TT_THROW(InvalidInput, "intrinsic_matches: positions do not match the nodes or the anchors");
  if (target_graph.n_vertices() != target.n_vertices())
    TT_THROW(InvalidInput, "intrinsic_matches: the target graph is not the target's");
  if (!(spacing > 0) || params.signature_anchors < 1 || params.agreement_neighbours < 1 ||
      !(params.tolerance >= 0) || !(params.slack >= 0) || !(params.min_agreement >= 0) ||
      !(params.misplaced_spacings >= 0))
    TT_THROW(InvalidInput, "intrinsic_matches: invalid parameters");
  const std::size_t nn = nodes.size(), A = anchors.anchor.size();
  IntrinsicMatches out;
  out.match.assign(nn, Correspondence{});
  out.anchors = A;
  if (nn < 1 || A < 2) return out;
  const std::vector<Index>& anchor = anchors.anchor;
  const std::vector<std::vector<float>>& ds = anchors.distance;  // [a][source vertex]

  // The anchors' current matches on the target, and the target's distances from them: dt[a][t].
  std::vector<Index> m(A);
  for (std::size_t a = 0; a < A; ++a) m[a] = nearest_target_vertex(target, anchor_x[a]);
  IntrinsicTargetCache local;
  IntrinsicTargetCache& tc = cache ? *cache : local;
  auto field_of = [&](Index t) {
    return std::size_t(std::find(tc.source.begin(), tc.source.end(), t) - tc.source.begin());
  };
  std::vector<Index> missing;
  for (std::size_t a = 0; a < A; ++a)
    if (field_of(m[a]) == tc.source.size() && std::find(missing.begin(), missing.end(), m[a]) == missing.end())
      missing.push_back(m[a]);
  if (!missing.empty()) {
    std::vector<std::vector<float>> fields = geodesic_distances(target_graph, missing);
    for (std::size_t k = 0; k < missing.size(); ++k) {
      tc.source.push_back(missing[k]);
      tc.distance.push_back(std::move(fields[k]));
    }
  }
  std::vector<std::span<const float>> dt(A);
  for (std::size_t a = 0; a < A; ++a) dt[a] = tc.distance[field_of(m[a])];

  // Consistency of the anchors' matches: the worst anchor dropped until each agrees with most others.
  std::vector<char> kept(A, 1);
  auto pair_ok = [&](std::size_t a, std::size_t b) { return std::isfinite(ds[a][anchor[b]]) && ds[a][anchor[b]] > 0; };
  // (source distances ds and target distances dt are floats; their comparisons below in double)
  auto scale_of_kept = [&] {
    std::vector<double> ratio;
    for (std::size_t a = 0; a < A; ++a)
      for (std::size_t b = a + 1; b < A; ++b)
        if (kept[a] && kept[b] && pair_ok(a, b) && ds[a][anchor[b]] > 2 * spacing &&
            std::isfinite(dt[a][m[b]]))
          ratio.push_back(double(dt[a][m[b]]) / double(ds[a][anchor[b]]));
    return median(std::move(ratio));
  };
  double s = scale_of_kept();
  // Each anchor is judged by its nearest kept anchors (a limb matched onto its mirror image agrees with
  // the far ones).
  const std::size_t L = std::size_t(params.agreement_neighbours);
  for (;;) {
    std::size_t worst = A;
    double worst_agreement = 2;
    for (std::size_t a = 0; a < A; ++a) {
      if (!kept[a]) continue;
      std::vector<std::pair<double, std::size_t>> by_distance;
      for (std::size_t b = 0; b < A; ++b)
        if (b != a && kept[b] && pair_ok(a, b)) by_distance.push_back({double(ds[a][anchor[b]]), b});
      const std::size_t total = std::min(L, by_distance.size());
      std::partial_sort(by_distance.begin(), by_distance.begin() + std::ptrdiff_t(total), by_distance.end());
      std::size_t agree = 0;
      for (std::size_t i = 0; i < total; ++i) {
        const std::size_t b = by_distance[i].second;
        const double want = s * double(ds[a][anchor[b]]);
        agree += std::abs(double(dt[a][m[b]]) - want) <= params.tolerance * want + params.slack * spacing;
      }
      const double agreement = total ? double(agree) / double(total) : 1.0;
      if (agreement < worst_agreement) {
        worst_agreement = agreement;
        worst = a;
      }
    }
    if (worst == A || worst_agreement >= params.min_agreement) break;
    kept[worst] = 0;
    s = scale_of_kept();
  }
  std::vector<std::size_t> good;
  for (std::size_t a = 0; a < A; ++a)
    if (kept[a]) good.push_back(a);
  out.kept = good.size();
  out.scale = s;
  if (good.size() < 4) return out;

  // Each node placed where its distances to its nearest kept anchors are best reproduced: the best
  // of the target's Poisson-disk samples, then steepest descent over target vertices.
  if (tc.candidates.empty() || tc.candidate_spacing != spacing) {
    tc.candidates = poisson_disk_samples(target_graph, spacing);
    tc.candidate_spacing = spacing;
  }
  const std::vector<Index>& candidates = tc.candidates;
  const auto& TP = target.positions();
  std::vector<char> misplaced(nn, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nn, 16), [&](const auto& r) {
    std::vector<std::pair<double, std::size_t>> near;
    for (std::size_t j = r.begin(); j != r.end(); ++j) {
      near.clear();
      for (const std::size_t a : good)
        if (std::isfinite(ds[a][nodes[j]])) near.push_back({double(ds[a][nodes[j]]), a});
      if (near.size() < 4) continue;
      const std::size_t K = std::min<std::size_t>(near.size(), std::size_t(params.signature_anchors));
      std::partial_sort(near.begin(), near.begin() + std::ptrdiff_t(K), near.end());
      auto misfit = [&](Index t) {
        double e = 0;
        for (std::size_t k = 0; k < K; ++k) {
          const double want = s * near[k].first;
          const double q = (double(dt[near[k].second][t]) - want) / (want + spacing);
          e += q * q;
        }
        return e;
      };
      Index best = kInvalidIndex;
      double best_e = kInf;
      for (const Index t : candidates)
        if (const double e = misfit(t); e < best_e) {
          best_e = e;
          best = t;
        }
      if (best == kInvalidIndex || !std::isfinite(best_e)) continue;
      for (bool moved = true; moved;) {
        moved = false;
        const Index at = best;
        for (Index i = target_graph.offset[at]; i < target_graph.offset[at + 1]; ++i)
          if (const double e = misfit(target_graph.target[i]); e < best_e) {
            best_e = e;
            best = target_graph.target[i];
            moved = true;
          }
      }
      if ((TP[best] - node_x[j]).norm() <= params.misplaced_spacings * spacing) continue;
      const TargetSurface::Hit on = target.closest_point(TP[best]);
      Correspondence& c = out.match[j];
      c.status = CorrespondenceStatus::Ok;
      c.point = TP[best];
      c.normal = on.normal;
      c.distance = (TP[best] - node_x[j]).norm();
      misplaced[j] = 1;
    }
  });
  for (const char x : misplaced) out.misplaced += std::size_t(x);
  return out;
}

}  // namespace topotrack
