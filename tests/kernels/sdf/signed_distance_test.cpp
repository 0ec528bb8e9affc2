#include "kernels/sdf/signed_distance.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>

#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

TEST(SignedDistance, SphereValuesAndConvention) {
  const test::Soup s = test::icosphere(4, 1.0);
  const double h = 0.05;
  auto grid = signed_distance(s.positions, s.triangles, h);
  EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
  EXPECT_NEAR(grid->voxelSize()[0], h, 1e-12);
  // Voxel (i, j, k) is centred at (i, j, k) * h.
  const auto w = grid->transform().indexToWorld(openvdb::Coord(3, -2, 7));
  EXPECT_NEAR(w.x(), 3 * h, 1e-12);
  EXPECT_NEAR(w.y(), -2 * h, 1e-12);
  EXPECT_NEAR(w.z(), 7 * h, 1e-12);
  EXPECT_NEAR(grid->background(), 3 * h, 1e-6);
  auto acc = grid->getConstAccessor();
  std::size_t checked = 0;
  for (auto it = grid->cbeginValueOn(); it; ++it) {
    const auto p = grid->transform().indexToWorld(it.getCoord());
    EXPECT_NEAR(*it, p.length() - 1.0, 0.012) << it.getCoord();  // facets are within 0.01 of the sphere
    ++checked;
  }
  EXPECT_GT(checked, 10000u);
  EXPECT_LT(acc.getValue(openvdb::Coord(0, 0, 0)), 0);   // deep inside: -background
  EXPECT_GT(acc.getValue(openvdb::Coord(40, 0, 0)), 0);  // far outside: +background
}

TEST(SignedDistance, SurfaceMeshOverloadMatches) {
  const test::Soup s = test::torus(48, 24);
  auto a = signed_distance(s.positions, s.triangles, 0.04);
  auto b = signed_distance(s.mesh(), 0.04);
  EXPECT_EQ(a->activeVoxelCount(), b->activeVoxelCount());
  auto acc = b->getConstAccessor();
  for (auto it = a->cbeginValueOn(); it; ++it) ASSERT_EQ(*it, acc.getValue(it.getCoord()));
}

// A lattice through another origin (the grid a surface was extracted on): node (i, j, k) at origin + (i, j, k) h,
// each value the distance from that point, and the same values, node for node, as the plain lattice's for the
// mesh moved by -origin (both methods).
TEST(SignedDistance, LatticeThroughAnotherOrigin) {
  const test::Soup s = test::torus(48, 24);
  const double h = 0.04;
  const Vec3 origin(0.013, -0.02, 0.5 * h);
  test::Soup moved = s;
  for (Vec3& p : moved.positions) p -= origin;
  for (const SdfMethod method : {SdfMethod::kNarrowBand, SdfMethod::kOpenVdb}) {
    SignedDistanceParams p;
    p.voxel_size = h;
    p.origin = origin;
    p.method = method;
    auto a = signed_distance(s.positions, s.triangles, p);
    p.origin = Vec3::Zero();
    auto b = signed_distance(moved.positions, moved.triangles, p);
    EXPECT_TRUE(is_lattice(a->transform(), h, origin));
    EXPECT_FALSE(is_lattice(a->transform(), h, Vec3::Zero()));
    EXPECT_TRUE(is_lattice(b->transform(), h, Vec3::Zero()));
    EXPECT_FALSE(is_lattice(a->transform(), 1.01 * h, origin));
    const auto w = a->transform().indexToWorld(openvdb::Coord(3, -2, 7));
    EXPECT_NEAR(w.x(), origin.x() + 3 * h, 1e-12);
    EXPECT_NEAR(w.y(), origin.y() - 2 * h, 1e-12);
    EXPECT_NEAR(w.z(), origin.z() + 7 * h, 1e-12);
    EXPECT_EQ(a->activeVoxelCount(), b->activeVoxelCount());
    auto acc = b->getConstAccessor();
    for (auto it = a->cbeginValueOn(); it; ++it) ASSERT_NEAR(*it, acc.getValue(it.getCoord()), 1e-6) << it.getCoord();
  }
  EXPECT_EQ(signed_distance(s.mesh(), h, 3.0, 0.0, origin)->activeVoxelCount(),
            signed_distance(moved.mesh(), h)->activeVoxelCount());
  auto rotated = voxel_transform(h);
  rotated->postRotate(0.3, openvdb::math::Z_AXIS);
  EXPECT_FALSE(is_lattice(*rotated, h, Vec3::Zero()));
}

TEST(SignedDistance, DeterministicAcrossThreadCounts) {
  const test::Soup s = test::torus(64, 32);
  openvdb::FloatGrid::Ptr one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = signed_distance(s.positions, s.triangles, 0.03);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = signed_distance(s.positions, s.triangles, 0.03);
  }
  ASSERT_EQ(one->activeVoxelCount(), two->activeVoxelCount());
  auto acc = two->getConstAccessor();
  for (auto it = one->cbeginValueOn(); it; ++it) {
    ASSERT_TRUE(acc.isValueOn(it.getCoord()));
    ASSERT_EQ(*it, acc.getValue(it.getCoord()));
  }
}

TEST(SignedDistance, Errors) {
  const test::Soup s = test::tetrahedron();
  EXPECT_THROW(signed_distance(s.positions, s.triangles, 0.0), InvalidInput);
  EXPECT_THROW(signed_distance(s.positions, s.triangles, -1.0), InvalidInput);
  EXPECT_THROW(signed_distance(s.positions, s.triangles, std::nan("")), InvalidInput);
  EXPECT_THROW(signed_distance(s.positions, s.triangles, 0.1, 0.5), InvalidInput);
  auto bad = s;
  bad.positions[1].x() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(signed_distance(bad.positions, bad.triangles, 0.1), InvalidInput);
  bad = s;
  bad.triangles[0][2] = 99;
  EXPECT_THROW(signed_distance(bad.positions, bad.triangles, 0.1), InvalidInput);
  auto empty = signed_distance(std::span<const Vec3>{}, std::span<const std::array<Index, 3>>{}, 0.1);
  EXPECT_EQ(empty->activeVoxelCount(), 0u);
}

}  // namespace
}  // namespace topotrack
