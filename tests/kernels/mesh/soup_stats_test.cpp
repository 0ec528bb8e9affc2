#include "kernels/mesh/soup_stats.hpp"

#include <gtest/gtest.h>

#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

MeshData data_of(const test::Soup& s) {
  MeshData d;
  for (const auto& p : s.positions) d.positions.push_back({p.x(), p.y(), p.z()});
  for (const auto& t : s.triangles) d.triangles.push_back({t[0], t[1], t[2]});
  return d;
}

TEST(SoupStats, ClosedSurfaces) {
  const SoupStats s = analyze_soup(data_of(test::torus(20, 10)));
  EXPECT_TRUE(s.closed_manifold());
  EXPECT_EQ(s.euler, 0);
  EXPECT_EQ(s.genus, 1);
  EXPECT_EQ(s.components, 1u);
  const SoupStats two = analyze_soup(data_of(test::merge(test::icosphere(1), test::icosphere(1, 1, Vec3(3, 0, 0)))));
  EXPECT_EQ(two.components, 2u);
  EXPECT_EQ(two.genus, 0);
}

TEST(SoupStats, ReportsDefects) {
  const SoupStats open = analyze_soup(data_of(test::open_box()));
  EXPECT_FALSE(open.closed);
  EXPECT_EQ(open.boundary_edges, 4u);
  EXPECT_EQ(open.genus, -1);

  auto d = data_of(test::tetrahedron());
  d.triangles.push_back({0, 1, 2});  // edge (0,1) now in three triangles, (0,1,2) duplicated
  const SoupStats nm = analyze_soup(d);
  EXPECT_GT(nm.non_manifold_edges, 0u);
  EXPECT_FALSE(nm.manifold);

  auto flipped = data_of(test::tetrahedron());
  std::swap(flipped.triangles[0][0], flipped.triangles[0][1]);
  EXPECT_EQ(analyze_soup(flipped).inconsistent_edges, 3u);

  auto pinch = test::merge(test::tetrahedron(), test::tetrahedron());
  for (auto& t : pinch.triangles)
    for (auto& i : t)
      if (i == 4) i = 0;
  const SoupStats p = analyze_soup(data_of(pinch));
  EXPECT_EQ(p.non_manifold_vertices, 1u);
  EXPECT_EQ(p.non_manifold_edges, 0u);

  auto deg = data_of(test::tetrahedron());
  deg.positions.push_back({0, 0, 0});
  deg.triangles.push_back({0, 0, 1});
  const SoupStats ds = analyze_soup(deg);
  EXPECT_EQ(ds.degenerate_triangles, 1u);
  EXPECT_EQ(ds.unreferenced_vertices, 1u);
}

}  // namespace
}  // namespace topotrack
