#pragma once
//! Approximate Hausdorff distance between two triangle meshes for tests: samples (vertices, edge
//! midpoints, face centroids and interior points) of each mesh against the exact closest point on the
//! other's triangles (TargetSurface, the library's closest-point query).
#include <algorithm>
#include <vector>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack::test {

//! Largest distance from samples of `a` to the surface of `b` (capped at `cap`).
inline double one_sided_distance(const SurfaceMesh& a, const SurfaceMesh& b, double cap) {
  const TargetSurface to = TargetSurface::from_mesh(b);
  const auto dist = [&](const Vec3& p) {
    const TargetSurface::Hit h = to.closest_point(p, cap);
    return h.hit ? h.distance : cap;
  };
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
