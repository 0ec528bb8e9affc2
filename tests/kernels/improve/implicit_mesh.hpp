#pragma once
//! Marching-tetrahedra meshes of implicit surfaces, for the improvement tests and benchmark: a closed
//! 2-manifold with the slivers, needles and near-zero edges typical of iso-surface extraction.
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "tests/support/test_meshes.hpp"

namespace topotrack::test {

//! Iso-surface f = 0 (f < 0 inside) on an n^3 grid over [lo, hi]^3 by marching tetrahedra (6 tets per
//! cube around the main diagonal, consistent across cubes). Triangles face outwards.
template <class F>
Soup marching_tets(F&& f, int n, double lo, double hi) {
  const double h = (hi - lo) / n;
  const int s = n + 1;
  auto gid = [&](int i, int j, int k) { return std::int64_t(i) + std::int64_t(s) * (j + std::int64_t(s) * k); };
  auto gpos = [&](std::int64_t g) {
    const int i = int(g % s), j = int((g / s) % s), k = int(g / (std::int64_t(s) * s));
    return Vec3(lo + i * h, lo + j * h, lo + k * h);
  };
  std::vector<double> val(std::size_t(s) * s * s);
  for (int k = 0; k < s; ++k)
    for (int j = 0; j < s; ++j)
      for (int i = 0; i < s; ++i) val[gid(i, j, k)] = f(gpos(gid(i, j, k)));
  Soup out;
  std::unordered_map<std::int64_t, Index> edge_vertex;
  auto crossing = [&](std::int64_t a, std::int64_t b) {
    if (a > b) std::swap(a, b);
    const std::int64_t key = a * std::int64_t(s) * s * s + b;
    auto [it, inserted] = edge_vertex.try_emplace(key, Index(out.positions.size()));
    if (inserted) {
      const double fa = val[a], fb = val[b], t = fa / (fa - fb);
      out.positions.push_back(gpos(a) + t * (gpos(b) - gpos(a)));
    }
    return it->second;
  };
  auto emit = [&](Index a, Index b, Index c, const Vec3& outward) {
    const Vec3 nrm = (out.positions[b] - out.positions[a]).cross(out.positions[c] - out.positions[a]);
    if (nrm.dot(outward) >= 0)
      out.triangles.push_back({a, b, c});
    else
      out.triangles.push_back({a, c, b});
  };
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (const auto& perm : kPerm) {
          std::array<int, 3> c = {i, j, k};
          std::array<std::int64_t, 4> t;
          t[0] = gid(c[0], c[1], c[2]);
          for (int q = 0; q < 3; ++q) {
            ++c[perm[q]];
            t[q + 1] = gid(c[0], c[1], c[2]);
          }
          std::array<std::int64_t, 4> in, outv;
          int ni = 0, no = 0;
          for (auto g : t) (val[g] < 0 ? in[ni++] : outv[no++]) = g;
          if (ni == 0 || no == 0) continue;
          if (ni == 1 || no == 1) {
            const bool single_in = ni == 1;
            const std::int64_t a = single_in ? in[0] : outv[0];
            const auto& o = single_in ? outv : in;
            const Index p0 = crossing(a, o[0]), p1 = crossing(a, o[1]), p2 = crossing(a, o[2]);
            const Vec3 ctr = (out.positions[p0] + out.positions[p1] + out.positions[p2]) / 3.0;
            const Vec3 dir = single_in ? Vec3(ctr - gpos(a)) : Vec3(gpos(a) - ctr);
            emit(p0, p1, p2, dir);
          } else {
            const Index ac = crossing(in[0], outv[0]), ad = crossing(in[0], outv[1]);
            const Index bd = crossing(in[1], outv[1]), bc = crossing(in[1], outv[0]);
            const Vec3 dir = 0.5 * (gpos(outv[0]) + gpos(outv[1])) - 0.5 * (gpos(in[0]) + gpos(in[1]));
            emit(ac, ad, bd, dir);
            emit(ac, bd, bc, dir);
          }
        }
  return out;
}

//! A torus about z (major radius R, minor r) by marching tetrahedra on an n^3 grid.
inline Soup mt_torus(int n, double R = 1.0, double r = 0.4) {
  return marching_tets(
      [&](const Vec3& p) {
        const double q = std::sqrt(p.x() * p.x() + p.y() * p.y()) - R;
        return std::sqrt(q * q + p.z() * p.z()) - r;
      },
      n, -(R + r) * 1.1, (R + r) * 1.1);
}

//! An ellipsoid with semi-axes (a, b, c) by marching tetrahedra on an n^3 grid.
inline Soup mt_ellipsoid(int n, const Vec3& axes, const Vec3& offset = Vec3(0.0123, 0.0071, 0.0047)) {
  const double m = axes.maxCoeff() * 1.1;
  return marching_tets(
      [&](const Vec3& p) { return (p - offset).cwiseQuotient(axes).norm() - 1.0; }, n, -m, m);
}

}  // namespace topotrack::test
