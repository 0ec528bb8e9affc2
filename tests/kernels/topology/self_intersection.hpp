#pragma once
// Test helper: count pairs of triangles that intersect without sharing a vertex (an edge of one
// piercing the other, touching excluded), over a uniform grid of triangle bounding boxes. Vertices closer
// than 1e-9 of the grid spacing count as shared (degenerate configurations touch, they do not cross).
#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack::test {

// Strict crossing; volumes below eps (coplanar or touching configurations, rounding noise) do not count.
inline bool segment_hits_triangle(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c,
                                  double eps = 0) {
  auto vol = [](const Vec3& x, const Vec3& y, const Vec3& z, const Vec3& w) { return (y - x).cross(z - x).dot(w - x); };
  const double sp = vol(a, b, c, p), sq = vol(a, b, c, q);
  if (!((sp > eps && sq < -eps) || (sp < -eps && sq > eps))) return false;
  const double s1 = vol(p, q, a, b), s2 = vol(p, q, b, c), s3 = vol(p, q, c, a);
  return (s1 > eps && s2 > eps && s3 > eps) || (s1 < -eps && s2 < -eps && s3 < -eps);
}

inline std::size_t count_self_intersections(const SurfaceMesh& mesh,
                                            std::vector<std::pair<std::array<Index, 3>, std::array<Index, 3>>>* pairs = nullptr) {
  std::vector<Vec3> P;
  std::vector<std::array<Index, 3>> T;
  extract_triangles(mesh, P, T);
  if (T.empty()) return 0;
  double mean = 0;
  for (const auto& t : T) mean += (P[t[0]] - P[t[1]]).norm();
  mean /= double(T.size());
  const double h = std::max(2.0 * mean, 1e-12);
  const double tol = 1e-9 * h, eps = 1e-15 * h * h * h;
  auto cell = [&](double x) { return long(std::floor(x / h)); };
  auto key = [](long x, long y, long z) {
    return (std::uint64_t(x + (1 << 20)) << 42) ^ (std::uint64_t(y + (1 << 20)) << 21) ^ std::uint64_t(z + (1 << 20));
  };
  std::unordered_map<std::uint64_t, std::vector<Index>> grid;
  for (Index f = 0; f < T.size(); ++f) {
    Vec3 lo = P[T[f][0]], hi = lo;
    for (int i = 1; i < 3; ++i) lo = lo.cwiseMin(P[T[f][i]]), hi = hi.cwiseMax(P[T[f][i]]);
    for (long x = cell(lo.x()); x <= cell(hi.x()); ++x)
      for (long y = cell(lo.y()); y <= cell(hi.y()); ++y)
        for (long z = cell(lo.z()); z <= cell(hi.z()); ++z) grid[key(x, y, z)].push_back(f);
  }
  std::vector<std::pair<Index, Index>> hits;
  for (const auto& [k, list] : grid)
    for (std::size_t i = 0; i < list.size(); ++i)
      for (std::size_t j = i + 1; j < list.size(); ++j) {
        const auto& A = T[list[i]];
        const auto& B = T[list[j]];
        bool shared = false;
        // Coincident vertices count as shared: triangles touching there do not cross.
        for (Index a : A)
          for (Index b : B) shared = shared || a == b || (P[a] - P[b]).norm() <= tol;
        if (shared) continue;
        bool hit = false;
        for (int e = 0; e < 3 && !hit; ++e) {
          hit = segment_hits_triangle(P[A[e]], P[A[(e + 1) % 3]], P[B[0]], P[B[1]], P[B[2]], eps) ||
                segment_hits_triangle(P[B[e]], P[B[(e + 1) % 3]], P[A[0]], P[A[1]], P[A[2]], eps);
        }
        if (hit) hits.emplace_back(std::min(list[i], list[j]), std::max(list[i], list[j]));
      }
  std::sort(hits.begin(), hits.end());
  hits.erase(std::unique(hits.begin(), hits.end()), hits.end());
  if (pairs)
    for (const auto& [a, b] : hits) pairs->emplace_back(T[a], T[b]);
  return std::size_t(std::unique(hits.begin(), hits.end()) - hits.begin());
}

}  // namespace topotrack::test
