#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "io/error.hpp"
#include "kernels/eval/drift.hpp"
#include "kernels/eval/plot.hpp"
#include "kernels/eval/surface_distance.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

TEST(SurfaceDistance, ZeroForTheSameSurfaceAndTheGapForAnOffsetOne) {
  const SurfaceMesh a = test::icosphere(3, 1.0).mesh();
  EXPECT_NEAR(surface_distance(a, a).mean(), 0.0, 1e-12);
  EXPECT_NEAR(surface_distance(a, a).hausdorff(), 0.0, 1e-12);
  const SurfaceMesh b = test::icosphere(3, 1.1).mesh();  // same triangulation, 10% larger
  const SurfaceDistance d = surface_distance(a, b);
  EXPECT_GT(d.mean(), 0.09);
  EXPECT_LT(d.mean(), 0.11);
  EXPECT_NEAR(d.hausdorff(), 0.1, 0.01);
  // The Hausdorff distance sees a small bump the mean hardly notices.
  test::Soup s = test::icosphere(3, 1.0);
  s.positions[0] *= 1.5;
  const SurfaceDistance bump = surface_distance(a, s.mesh());
  EXPECT_NEAR(bump.hausdorff(), 0.5, 0.05);
  EXPECT_LT(bump.mean(), 0.01);
}

// Where the Hausdorff distance is attained: the tip of the bump, seen from the bumped surface's side.
TEST(SurfaceDistance, LocatesTheFarthestPoint) {
  const SurfaceMesh a = test::icosphere(3, 1.0).mesh();
  test::Soup s = test::icosphere(3, 1.0);
  s.positions[7] *= 1.5;
  const SurfaceDistance d = surface_distance(a, s.mesh());
  EXPECT_GT(d.b_to_a.max, d.a_to_b.max);
  EXPECT_EQ(d.b_to_a.max_point, s.positions[7]);
  EXPECT_EQ(d.b_to_a.max_index, 7u);  // samples are the vertices first
  EXPECT_NEAR(d.b_to_a.max, 0.5, 0.05);
  const std::vector<Vec3> pts = {Vec3(0, 0, 1.2), Vec3(0, 0, 3), Vec3(0, 0, 0.9)};
  const DistanceStats o = one_sided_distance(pts, TargetSurface::from_mesh(a));
  EXPECT_EQ(o.max_index, 1u);
  EXPECT_EQ(o.max_point, pts[1]);
}

TEST(SurfaceDistance, RejectsEmptyMeshes) {
  const SurfaceMesh a = test::icosphere(1).mesh();
  EXPECT_THROW(surface_distance(a, SurfaceMesh()), InvalidInput);
}

TEST(Drift, RotationGroundTruth) {
  const std::vector<Vec3> material = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5, Vec3::UnitZ()).toRotationMatrix();
  const Vec3 c(0.5, 0, 0);
  const auto expected = expected_by_rotation(material, R, c);
  EXPECT_TRUE(expected[2].isApprox(R * (material[2] - c) + c));
  std::vector<Vec3> tracked = expected;
  tracked[0] += Vec3(0.3, 0, 0);
  const DriftStats s = drift_stats(tracked, expected);
  EXPECT_EQ(s.points, 3u);
  EXPECT_NEAR(s.max, 0.3, 1e-12);
  EXPECT_NEAR(s.mean, 0.1, 1e-12);
  EXPECT_NEAR(s.median, 0.0, 1e-12);
}

TEST(Drift, CorrespondenceGroundTruthFollowsTheCoherentSequence) {
  test::Soup first = test::icosphere(3, 1.0);
  const TargetSurface surface(first.positions, first.triangles);
  // Frame n: the same vertices stretched along x and moved.
  std::vector<Vec3> frame_n = first.positions;
  for (auto& p : frame_n) p = Vec3(2 * p.x(), p.y(), p.z()) + Vec3(0, 0, 3);
  // Material points: vertices and face centroids of frame 1 map exactly (the map is affine per triangle).
  std::vector<Vec3> material = {first.positions[5], (first.positions[0] + first.positions[1]) * 0.5};
  material[1] = material[1].normalized();  // slightly off the surface: projected onto it first
  const auto expected = expected_by_correspondence(material, surface, frame_n);
  EXPECT_TRUE(expected[0].isApprox(frame_n[5], 1e-9));
  EXPECT_NEAR(expected[1].z(), 3.0 + material[1].z(), 0.02);
  EXPECT_NEAR(expected[1].x(), 2 * material[1].x(), 0.05);
  frame_n.pop_back();
  EXPECT_THROW(expected_by_correspondence(material, surface, frame_n), InvalidInput);
}

TEST(Drift, Barycentric) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  const Eigen::Vector3d w = barycentric(Vec3(0.25, 0.5, 0.7), a, b, c);
  EXPECT_NEAR(w[0], 0.25, 1e-12);
  EXPECT_NEAR(w[1], 0.25, 1e-12);
  EXPECT_NEAR(w[2], 0.5, 1e-12);
}

std::size_t count_color(const Image& img, std::array<std::uint8_t, 3> c) {
  std::size_t n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) n += std::equal(c.begin(), c.end(), img.pixel(x, y));
  return n;
}

TEST(Plot, DrawsEverySeriesAndText) {
  std::vector<PlotSeries> s(2);
  s[0] = {"up", {1, 2, 3, 4}, {0, 1, 2, 3}, {200, 0, 0}};
  s[1] = {"flat", {1, 2, 3, 4}, {1, 1, NAN, 1}, {0, 0, 200}};
  const Image img = line_plot(s, {640, 300, "title", "frame", "value"});
  EXPECT_EQ(img.width, 640);
  EXPECT_EQ(img.height, 300);
  EXPECT_GT(count_color(img, {200, 0, 0}), 200u);  // a line across the plot plus the legend swatch
  EXPECT_GT(count_color(img, {0, 0, 200}), 100u);
  EXPECT_GT(count_color(img, {0, 0, 0}), 300u);    // axes and title
  s[0].y.pop_back();
  EXPECT_THROW(line_plot(s), InvalidInput);
  PlotParams tiny;
  tiny.width = 100;
  tiny.height = 50;
  EXPECT_THROW(line_plot({}, tiny), InvalidInput);
}

TEST(Plot, TextUsesTheFont) {
  Image img(60, 10, 255);
  draw_text(img, 0, 0, "10%", {0, 0, 0});
  const std::size_t dark = count_color(img, {0, 0, 0});
  EXPECT_GT(dark, 20u);
  Image blank(60, 10, 255);
  draw_text(blank, 0, 0, "   ", {0, 0, 0});
  EXPECT_EQ(count_color(blank, {0, 0, 0}), 0u);
}

}  // namespace
}  // namespace topotrack
