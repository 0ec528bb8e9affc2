#include "kernels/sdf/extraction_grid.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

//! Marching cubes of a torus's signed distance on a grid of spacing h, as float coordinates (as a PLY stores them).
SurfaceMesh extracted_torus(double h) {
  const test::Soup torus = test::torus(96, 48, 1.0, 0.35);
  auto grid = signed_distance(torus.positions, torus.triangles, h, 2.0);
  MeshData m = marching_cubes(*grid);
  for (auto& p : m.positions)
    for (double& c : p) c = double(float(c));
  return to_surface_mesh(m);
}

std::vector<Vec3> moved(const SurfaceMesh& m, const Vec3& by) {
  std::vector<Vec3> out = m.positions();
  for (Vec3& p : out) p += by;
  return out;
}

TEST(ExtractionGrid, RecognisesMarchingCubesOutputAndItsSpacing) {
  for (const double h : {0.05, 0.0371, 0.0123}) {
    const SurfaceMesh m = extracted_torus(h);
    const auto g = extraction_grid(m.positions(), mean_edge_length(m));
    ASSERT_TRUE(g) << "h " << h;
    EXPECT_NEAR(g->spacing, h, 1e-6 * h);
    EXPECT_EQ(g->origin, Vec3::Zero()) << "nodes at multiples of the spacing: exactly 0";
  }
}

// A simulation domain's corner, cell-centred samples: the grid through another origin, found with it (each axis
// in [-h/2, h/2]), also far from the world's origin.
TEST(ExtractionGrid, FindsTheGridsOrigin) {
  const double h = 0.0371;
  const SurfaceMesh m = extracted_torus(h);
  const double l = mean_edge_length(m);
  for (const Vec3& by : {Vec3(0.37 * h, 0, 0), Vec3(0.3 * h, 0.6 * h, 0.1 * h), Vec3(0.5 * h, 0.5 * h, 0.5 * h),
                         Vec3(41.25 * h, -17.8 * h, 3.5 * h)}) {
    const auto g = extraction_grid(moved(m, by), l);
    ASSERT_TRUE(g) << by.transpose();
    EXPECT_NEAR(g->spacing, h, 1e-6 * h);
    for (int a = 0; a < 3; ++a) {
      const double t = (g->origin[a] - by[a]) / h;  // the same grid: a whole number of spacings apart
      EXPECT_NEAR(t, std::round(t), 1e-4) << "axis " << a << " by " << by.transpose();
      EXPECT_LE(std::abs(g->origin[a]), 0.5 * h + 1e-12);
    }
  }
}

TEST(ExtractionGrid, RejectsSurfacesOffAnyGrid) {
  const double h = 0.0371;
  const SurfaceMesh m = extracted_torus(h);
  const double l = mean_edge_length(m);
  // A mesh not extracted from a grid.
  const test::Soup sphere = test::icosphere(5);
  const SurfaceMesh s = sphere.mesh();
  EXPECT_FALSE(extraction_grid(s.positions(), mean_edge_length(s)));
  // Its coordinates rounded to 4 decimals: all three on a grid of 1e-4, far below its edge length.
  std::vector<Vec3> rounded = s.positions();
  for (Vec3& p : rounded)
    for (int a = 0; a < 3; ++a) p[a] = std::round(p[a] * 1e4) * 1e-4;
  EXPECT_FALSE(extraction_grid(rounded, mean_edge_length(s)));
  // Marching-cubes output tracked and resampled: most vertices moved off the planes.
  test::Soup soup;
  soup.positions = m.positions();
  for (std::size_t f = 0; f < m.faces_size(); ++f) {
    const auto v = m.vertices(Face(Index(f)));
    soup.triangles.push_back({v[0].idx, v[1].idx, v[2].idx});
  }
  test::jitter(soup, 0.01 * h, 7);
  EXPECT_FALSE(extraction_grid(soup.positions, l));
  EXPECT_FALSE(extraction_grid(std::vector<Vec3>(10, Vec3::Zero()), 1.0));  // too few points
  std::vector<Vec3> bad = m.positions();
  bad[5].y() = std::nan("");
  EXPECT_FALSE(extraction_grid(bad, l));
}

}  // namespace
}  // namespace topotrack
