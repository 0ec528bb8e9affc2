#pragma once
//! Approximate Hausdorff distance between two triangle meshes for tests: samples (vertices, edge
//! midpoints, face centroids and interior points) of each mesh against the exact closest point on the
//! other's triangles, found through a uniform grid of triangle bounding boxes.
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack::test {

//! Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5).
inline Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double den = 1.0 / (va + vb + vc);
  return a + ab * (vb * den) + ac * (vc * den);
}

//! Distance queries to a fixed triangle mesh, capped at `cap` (farther points report `cap`).
class TriangleDistance {
public:
  TriangleDistance(const SurfaceMesh& mesh, double cap) : cap_(cap) {
    extract_triangles(mesh, pos_, tri_);
    cell_ = cap;
    for (const auto& t : tri_)
      for (int k = 0; k < 3; ++k) cell_ = std::max(cell_, (pos_[t[k]] - pos_[t[(k + 1) % 3]]).norm());
    for (Index f = 0; f < tri_.size(); ++f) {
      Vec3 lo = pos_[tri_[f][0]], hi = lo;
      for (int k = 1; k < 3; ++k) {
        lo = lo.cwiseMin(pos_[tri_[f][k]]);
        hi = hi.cwiseMax(pos_[tri_[f][k]]);
      }
      const auto a = cell_of(lo), b = cell_of(hi);
      for (long i = a[0]; i <= b[0]; ++i)
        for (long j = a[1]; j <= b[1]; ++j)
          for (long k = a[2]; k <= b[2]; ++k) grid_[key(i, j, k)].push_back(f);
    }
  }

  double operator()(const Vec3& p) const {
    double best = cap_;
    const auto a = cell_of(p - Vec3::Constant(cap_)), b = cell_of(p + Vec3::Constant(cap_));
    for (long i = a[0]; i <= b[0]; ++i)
      for (long j = a[1]; j <= b[1]; ++j)
        for (long k = a[2]; k <= b[2]; ++k) {
          const auto it = grid_.find(key(i, j, k));
          if (it == grid_.end()) continue;
          for (Index f : it->second) {
            const auto& t = tri_[f];
            best = std::min(best, (closest_point_on_triangle(p, pos_[t[0]], pos_[t[1]], pos_[t[2]]) - p).norm());
          }
        }
    return best;
  }

private:
  std::array<long, 3> cell_of(const Vec3& p) const {
    return {long(std::floor(p.x() / cell_)), long(std::floor(p.y() / cell_)), long(std::floor(p.z() / cell_))};
  }
  static std::int64_t key(long i, long j, long k) {
    return (std::int64_t(i) & 0x1FFFFF) | ((std::int64_t(j) & 0x1FFFFF) << 21) | ((std::int64_t(k) & 0x1FFFFF) << 42);
  }
  double cap_, cell_ = 0;
  std::vector<Vec3> pos_;
  std::vector<std::array<Index, 3>> tri_;
  std::unordered_map<std::int64_t, std::vector<Index>> grid_;
};

//! Largest distance from samples of `a` to the surface of `b` (capped at `cap`).
inline double one_sided_distance(const SurfaceMesh& a, const SurfaceMesh& b, double cap) {
  const TriangleDistance dist(b, cap);
  std::vector<Vec3> pos;
  std::vector<std::array<Index, 3>> tri;
  extract_triangles(a, pos, tri);
  double d = 0;
  for (const Vec3& p : pos) d = std::max(d, dist(p));
  static constexpr double kBary[][3] = {{0.5, 0.5, 0}, {0, 0.5, 0.5}, {0.5, 0, 0.5}, {1 / 3., 1 / 3., 1 / 3.},
                                        {0.6, 0.2, 0.2}, {0.2, 0.6, 0.2}, {0.2, 0.2, 0.6}};
  for (const auto& t : tri)
    for (const auto& w : kBary) d = std::max(d, dist(w[0] * pos[t[0]] + w[1] * pos[t[1]] + w[2] * pos[t[2]]));
  return d;
}

//! Symmetric approximate Hausdorff distance, capped at `cap`.
inline double hausdorff_distance(const SurfaceMesh& a, const SurfaceMesh& b, double cap) {
  return std::max(one_sided_distance(a, b, cap), one_sided_distance(b, a, cap));
}

}  // namespace topotrack::test
