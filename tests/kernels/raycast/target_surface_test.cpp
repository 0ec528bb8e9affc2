// EmbreeScene and TargetSurface (Embree): scene set-up, undirected rays, closest points, batch queries,
// invalid input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "kernels/raycast/embree_scene.hpp"
#include "kernels/raycast/target_surface.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

TEST(EmbreeScene, HitsReportTheTriangleIndex) {
  const test::Soup s = test::icosphere(3);
  EmbreeScene scene(s.positions, s.triangles);
  ASSERT_NE(scene.get(), nullptr);
  EXPECT_EQ(embree_device(), embree_device());  // one device for the process
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit rh{};
  rh.ray.org_x = 0.0f;
  rh.ray.org_y = 0.0f;
  rh.ray.org_z = 0.0f;
  rh.ray.dir_x = 0.0f;
  rh.ray.dir_y = 1.0f;
  rh.ray.dir_z = 0.0f;
  rh.ray.tfar = 10.0f;
  rh.ray.mask = ~0u;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(scene.get(), &context, &rh);
  ASSERT_EQ(rh.hit.geomID, 0u);
  ASSERT_LT(rh.hit.primID, s.triangles.size());
  EXPECT_NEAR(rh.ray.tfar, 1.0f, 2e-2f);
  // Moving hands the scene over.
  EmbreeScene moved = std::move(scene);
  EXPECT_EQ(scene.get(), nullptr);
  EXPECT_NE(moved.get(), nullptr);
  // An index out of range is invalid input; an empty scene is valid (nothing to hit).
  std::vector<std::array<Index, 3>> bad = s.triangles;
  bad[5][1] = Index(s.positions.size());
  EXPECT_THROW(EmbreeScene(s.positions, bad), InvalidInput);
  EXPECT_NE(EmbreeScene({}, {}).get(), nullptr);
}

TEST(TargetSurface, UndirectedRayTakesTheNearerSide) {
  const test::Soup s = test::icosphere(5);
  const TargetSurface t(s.positions, s.triangles);
  EXPECT_EQ(t.n_triangles(), s.triangles.size());
  EXPECT_NEAR(t.bbox_diagonal(), 2 * std::sqrt(3.0), 1e-2);
  // From (0, 0.8, 0) along +y: the wall at y = 1 is 0.2 away; the one at y = -1 is 1.8 away.
  TargetSurface::Hit h = t.cast_undirected(Vec3(0, 0.8, 0), Vec3(0, -3, 0), 10);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 0.2, 2e-3);
  EXPECT_NEAR(h.point.y(), 1.0, 2e-3);
  EXPECT_GT(h.normal.y(), 0.99);
  EXPECT_LT(h.face, t.n_triangles());
  // Directed cast along -y goes to the far wall.
  h = t.cast(Vec3(0, 0.8, 0), Vec3(0, -1, 0), 10);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 1.8, 2e-3);
  // Length limit, misses and degenerate directions.
  EXPECT_FALSE(t.cast_undirected(Vec3(0, 0.8, 0), Vec3(0, 1, 0), 0.1).hit);
  EXPECT_FALSE(t.cast_undirected(Vec3(5, 5, 5), Vec3(1, 0, 0), 100).hit);
  EXPECT_FALSE(t.cast_undirected(Vec3(0, 0, 0), Vec3::Zero(), 100).hit);
  EXPECT_FALSE(t.cast_undirected(Vec3(0, std::nan(""), 0), Vec3(1, 0, 0), 100).hit);
}

TEST(TargetSurface, HitDistanceIsRefinedInDouble) {
  // A single large triangle in the plane z = 1e-3 far from the origin: float rounding of the origin
  // alone would be ~1e-4.
  const std::vector<Vec3> p = {Vec3(1000, 1000, 1e-3), Vec3(1002, 1000, 1e-3), Vec3(1000, 1002, 1e-3)};
  const std::vector<std::array<Index, 3>> f = {{0, 1, 2}};
  const TargetSurface t(p, f);
  const TargetSurface::Hit h = t.cast_undirected(Vec3(1000.3, 1000.3, 0.5), Vec3(0, 0, 1), 10);
  ASSERT_TRUE(h.hit);
  EXPECT_NEAR(h.distance, 0.5 - 1e-3, 1e-9);
  EXPECT_NEAR(h.point.z(), 1e-3, 1e-9);
}

TEST(TargetSurface, ClosestPoint) {
  const test::Soup s = test::icosphere(5);
  const TargetSurface t(s.positions, s.triangles);
  for (const Vec3& q : {Vec3(0, 0, 3), Vec3(0.1, 0.2, 0.3), Vec3(-2, 1, 0.5)}) {
    const TargetSurface::Hit h = t.closest_point(q);
    ASSERT_TRUE(h.hit);
    EXPECT_NEAR(h.distance, std::abs(q.norm() - 1.0), 2e-3);
    EXPECT_NEAR((h.point - q).norm(), h.distance, 1e-12);
    // Brute force agrees.
    double best = std::numeric_limits<double>::infinity();
    for (const auto& tri : s.triangles)
      best = std::min(best, (closest_point_on_triangle(q, s.positions[tri[0]], s.positions[tri[1]],
                                                       s.positions[tri[2]]) - q).norm());
    EXPECT_DOUBLE_EQ(h.distance, best);
  }
  EXPECT_FALSE(t.closest_point(Vec3(0, 0, 3), 1.5).hit);
  EXPECT_TRUE(t.closest_point(Vec3(0, 0, 3), 2.1).hit);
}

TEST(TargetSurface, ClosestPointOnTriangleRegions) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  EXPECT_EQ(closest_point_on_triangle(Vec3(-1, -1, 0), a, b, c), a);
  EXPECT_EQ(closest_point_on_triangle(Vec3(2, -1, 0), a, b, c), b);
  EXPECT_EQ(closest_point_on_triangle(Vec3(-1, 2, 0), a, b, c), c);
  EXPECT_TRUE(closest_point_on_triangle(Vec3(0.5, -1, 3), a, b, c).isApprox(Vec3(0.5, 0, 0)));
  EXPECT_TRUE(closest_point_on_triangle(Vec3(1, 1, 0), a, b, c).isApprox(Vec3(0.5, 0.5, 0)));
  EXPECT_TRUE(closest_point_on_triangle(Vec3(0.2, 0.3, -2), a, b, c).isApprox(Vec3(0.2, 0.3, 0)));
}

TEST(TargetSurface, BatchQueriesMatchSingleOnes) {
  const test::Soup s = test::torus(64, 32);
  const TargetSurface t = TargetSurface::from_mesh(s.mesh());
  std::vector<Vec3> o, d;
  for (int i = 0; i < 2000; ++i) {
    const double a = 0.01 * i;
    o.push_back(Vec3(1.5 * std::cos(a), 1.5 * std::sin(a), 0.3 * std::sin(3 * a)));
    d.push_back(Vec3(std::cos(a), std::sin(a), 0.1));
  }
  const auto hits = t.cast_undirected(o, d, 5.0);
  const auto closest = t.closest_points(o);
  for (std::size_t i = 0; i < o.size(); ++i) {
    const auto h = t.cast_undirected(o[i], d[i], 5.0);
    EXPECT_EQ(h.hit, hits[i].hit);
    EXPECT_EQ(h.face, hits[i].face);
    EXPECT_EQ(h.distance, hits[i].distance);
    EXPECT_EQ(t.closest_point(o[i]).point, closest[i].point);
    if (h.hit) {
      EXPECT_GE(h.distance, closest[i].distance - 1e-9);
    }
  }
  EXPECT_THROW(t.cast_undirected(o, std::span<const Vec3>(d).first(3), 1.0), InvalidInput);
}

TEST(TargetSurface, InvalidInputThrows) {
  const std::vector<Vec3> p = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  const std::vector<std::array<Index, 3>> bad = {{0, 1, 5}};
  EXPECT_THROW(TargetSurface(p, bad), InvalidInput);
  EXPECT_THROW(TargetSurface(p, {}), InvalidInput);
  std::vector<Vec3> nan = p;
  nan[1].x() = std::nan("");
  const std::vector<std::array<Index, 3>> ok = {{0, 1, 2}};
  EXPECT_THROW(TargetSurface(nan, ok), InvalidInput);
  SurfaceMesh empty;
  EXPECT_THROW(TargetSurface::from_mesh(empty), InvalidInput);
}

}  // namespace
// Embree's kernels for different instruction sets answer differently, so embree_device() pins one. A fixed set
// of queries on a bumpy sphere must give bit for bit what it gives on the project's machine with the AVX2
// kernels (with the SSE4.2 kernels the hash differs there: a machine where Embree picked its own would fail).
TEST(EmbreeScene, PinsTheKernelsSoHitsAreTheSameOnEveryMachine) {
  const bool avx2 = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma") &&
                    __builtin_cpu_supports("bmi") && __builtin_cpu_supports("bmi2");
  EXPECT_STREQ(embree_isa(), avx2 ? "avx2" : "sse4.2");
  test::Soup s = test::icosphere(6);
  test::jitter(s, 0.004, 7);
  const TargetSurface t(s.positions, s.triangles);
  std::vector<Vec3> origins, directions;
  for (int i = 0; i < 40000; ++i) {
    // A golden-angle spiral just off the surface, rays along a skewed radial direction.
    const double z = 1 - 2 * (i + 0.5) / 40000, r = std::sqrt(1 - z * z), a = 2.399963229728653 * i;
    const Vec3 p(r * std::cos(a), r * std::sin(a), z);
    origins.push_back(p * (1 + 0.01 * std::sin(7.0 * i)));
    directions.push_back(p + 0.3 * Vec3(std::sin(3.0 * i), std::cos(5.0 * i), std::sin(11.0 * i)));
  }
  // Queries whose answer is a vertex of the mesh, where the face reported (from the several that meet there)
  // depends on the order the kernels visit them in.
  for (std::size_t v = 0; v < s.positions.size(); v += 3) {
    origins.push_back(1.02 * s.positions[v]);
    directions.push_back(-s.positions[v]);
  }
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a over every field of every hit
  auto mix = [&hash](const void* bytes, std::size_t n) {
    for (std::size_t k = 0; k < n; ++k) hash = (hash ^ static_cast<const unsigned char*>(bytes)[k]) * 1099511628211ull;
  };
  auto add = [&mix](const std::vector<TargetSurface::Hit>& hits) {
    for (const TargetSurface::Hit& h : hits) {
      mix(&h.hit, sizeof h.hit);
      mix(&h.face, sizeof h.face);
      mix(&h.distance, sizeof h.distance);
      mix(h.point.data(), 3 * sizeof(double));
    }
  };
  add(t.cast_undirected(origins, directions, 0.5));
  add(t.closest_points(origins));
  if (avx2) {
    EXPECT_EQ(hash, 0x4dbf21c41373869aull);  // the SSE4.2 kernels: 0x8e8687472080428a
  }
}

}  // namespace topotrack
