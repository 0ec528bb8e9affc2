#include "kernels/sdf/close_holes.hpp"

#include <gtest/gtest.h>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

TEST(CloseHoles, BoundaryLoops) {
  test::Soup s = test::icosphere(1);
  EXPECT_TRUE(boundary_loops(s.triangles).empty());
  s.triangles.erase(s.triangles.begin());
  s.triangles.erase(s.triangles.begin() + 20);
  const auto loops = boundary_loops(s.triangles);
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0].size(), 3u);
  EXPECT_EQ(loops[1].size(), 3u);
  EXPECT_GT(loop_extent(s.positions, loops[0]), 0.5);
}

// A sphere with a cap of triangles removed: one closed sphere again, on the original surface.
TEST(CloseHoles, SphereWithAHole) {
  test::Soup s = test::icosphere(4, 1.0);
  std::erase_if(s.triangles, [&](const std::array<Index, 3>& t) { return s.positions[t[0]].z() > 0.9; });
  CloseHolesParams p;
  p.voxel_size = 0.05;
  CloseHolesReport r;
  const MeshData closed = close_holes(s.positions, s.triangles, p, &r);
  const SurfaceMesh m = to_surface_mesh(closed);
  EXPECT_NO_THROW(m.validate(true));
  EXPECT_EQ(connected_components(m), 1u);
  EXPECT_EQ(euler_characteristic(m), 2);
  EXPECT_EQ(r.holes_closed, 1u);
  EXPECT_GT(r.largest_hole, 0.5);
  EXPECT_EQ(r.thin_vertices, 0u);
  // On the sphere, or on the flat cap (at most its sagitta, 0.1, inside).
  for (const auto& q : closed.positions) {
    EXPECT_LT(Vec3(q[0], q[1], q[2]).norm(), 1.02);
    EXPECT_GT(Vec3(q[0], q[1], q[2]).norm(), q[2] > 0.85 ? 0.88 : 0.98);
  }
  p.max_hole_voxels = 5;  // the hole is ~0.87 across: 17 voxels
  EXPECT_THROW(close_holes(s.positions, s.triangles, p), InvalidInput);
  p.max_hole_voxels = 100;
  p.voxel_size = 0;
  EXPECT_THROW(close_holes(s.positions, s.triangles, p), InvalidInput);
  EXPECT_THROW(close_holes(s.positions, {}, {0.05}), InvalidInput);
}

}  // namespace
}  // namespace topotrack
