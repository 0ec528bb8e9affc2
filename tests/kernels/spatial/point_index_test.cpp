// PointIndex (nanoflann): nearest, k-nearest and radius queries against brute force; ties by index.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "kernels/spatial/point_index.hpp"

namespace topotrack {
namespace {

std::vector<Vec3> random_points(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Vec3> p(n);
  for (auto& x : p) x = Vec3(u(rng), u(rng), u(rng));
  return p;
}

TEST(PointIndex, MatchesBruteForce) {
  const auto pts = random_points(3000, 1);
  const PointIndex index(pts);
  EXPECT_EQ(index.size(), pts.size());
  const auto queries = random_points(200, 2);
  const auto batch = index.nearest(queries);
  for (std::size_t qi = 0; qi < queries.size(); ++qi) {
    const Vec3& q = queries[qi];
    std::vector<std::pair<double, Index>> all;
    for (std::size_t i = 0; i < pts.size(); ++i) all.push_back({(pts[i] - q).norm(), Index(i)});
    std::sort(all.begin(), all.end());
    const auto knn = index.k_nearest(q, 8);
    ASSERT_EQ(knn.size(), 8u);
    for (int i = 0; i < 8; ++i) {
      EXPECT_EQ(knn[i].index, all[i].second);
      EXPECT_NEAR(knn[i].distance, all[i].first, 1e-12);
    }
    EXPECT_EQ(batch[qi].index, all[0].second);
    const auto ball = index.within_radius(q, 0.2);
    std::size_t expected = 0;
    while (expected < all.size() && all[expected].first <= 0.2) ++expected;
    ASSERT_EQ(ball.size(), expected);
    for (std::size_t i = 0; i < expected; ++i) EXPECT_EQ(ball[i].index, all[i].second);
  }
}

TEST(PointIndex, TiesGoToTheSmallerIndex) {
  const std::vector<Vec3> pts = {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 5)};
  const PointIndex index(pts);
  EXPECT_EQ(index.nearest(Vec3::Zero()).index, 0u);
  const auto two = index.k_nearest(Vec3::Zero(), 2);
  EXPECT_EQ(two[0].index, 0u);
  EXPECT_EQ(two[1].index, 1u);
  EXPECT_EQ(index.k_nearest(Vec3::Zero(), 10).size(), 4u);
}

TEST(PointIndex, EmptyAndInvalid) {
  const PointIndex empty(std::vector<Vec3>{});
  EXPECT_EQ(empty.nearest(Vec3::Zero()).index, kInvalidIndex);
  EXPECT_TRUE(empty.within_radius(Vec3::Zero(), 1).empty());
  std::vector<Vec3> bad = {Vec3(0, 0, 0), Vec3(std::nan(""), 0, 0)};
  EXPECT_THROW(PointIndex{bad}, InvalidInput);
}

}  // namespace
}  // namespace topotrack
