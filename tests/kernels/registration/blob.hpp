#pragma once
//! The registration tests' shapes: an asymmetric closed blob (a bumpy ellipsoid, so that rotations are
//! observable) and a mesh with a component that has no counterpart in the target, plus their error measure.
#include <gtest/gtest.h>

#include <cmath>

#include "kernels/raycast/target_surface.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack::test {

inline Soup blob(int subdivisions = 4) {
  Soup s = icosphere(subdivisions);
  for (Vec3& p : s.positions) {
    const double bump = 1 + 0.25 * std::exp(-8 * (p - Vec3(0.6, 0.6, 0.5).normalized()).squaredNorm()) +
                        0.15 * std::exp(-10 * (p - Vec3(-0.7, 0.1, -0.7).normalized()).squaredNorm());
    p = Vec3(1.0 * p.x(), 0.7 * p.y(), 0.5 * p.z()) * bump;
  }
  return s;
}

//! Mean distance of the mesh's vertices to their ground-truth positions.
inline double mean_error(const SurfaceMesh& m, const std::vector<Vec3>& truth) {
  double e = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) e += (m.positions()[i] - truth[i]).norm();
  return e / double(truth.size());
}

//! A unit sphere (the first `near_vertices` vertices) and a sphere of radius 0.5 at x = 4 with no
//! counterpart in the target, a sphere of radius 1.03: the far one lies beyond the fine stage's sigma.
struct FarSphereCase {
  SurfaceMesh mesh;
  std::size_t near_vertices = 0, far_vertices = 0;
  TargetSurface target;
};

inline FarSphereCase far_sphere_case() {
  const Soup near_sphere = icosphere(3, 1.0), far_sphere = icosphere(3, 0.5, Vec3(4, 0, 0));
  const Soup t = icosphere(4, 1.03);
  return {merge(near_sphere, far_sphere).mesh(), near_sphere.positions.size(), far_sphere.positions.size(),
          TargetSurface(t.positions, t.triangles)};
}

//! After a fine alignment of far_sphere_case() from `before`: the far sphere got no correspondence and did
//! not move (displacements diffuse within a component only), the near one lies on the target.
inline void expect_far_sphere_kept(const FarSphereCase& c, const std::vector<Vec3>& before, std::size_t pruned) {
  EXPECT_EQ(pruned, c.far_vertices);
  for (std::size_t i = c.near_vertices; i < before.size(); ++i) EXPECT_EQ(c.mesh.positions()[i], before[i]);
  for (std::size_t i = 0; i < c.near_vertices; ++i) EXPECT_NEAR(c.mesh.positions()[i].norm(), 1.03, 2e-3);
}

}  // namespace topotrack::test
