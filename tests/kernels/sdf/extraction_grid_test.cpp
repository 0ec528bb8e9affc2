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
    const auto r = extraction_grid_spacing(m.positions(), mean_edge_length(m));
    ASSERT_TRUE(r) << "h " << h;
    EXPECT_NEAR(*r, h, 1e-6 * h);
  }
}

TEST(ExtractionGrid, RejectsOtherOriginsAndSurfacesOffAnyGrid) {
  const double h = 0.0371;
  const SurfaceMesh m = extracted_torus(h);
  const double l = mean_edge_length(m);
  // The same grid moved by 0.37 voxels: its nodes are not at multiples of the spacing (nor of a tenth of it).
  EXPECT_FALSE(extraction_grid_spacing(moved(m, Vec3(0.37 * h, 0, 0)), l));
  EXPECT_FALSE(extraction_grid_spacing(moved(m, Vec3(0.3 * h, 0.6 * h, 0.1 * h)), l));
  // A mesh not extracted from a grid.
  const test::Soup sphere = test::icosphere(5);
  const SurfaceMesh s = sphere.mesh();
  EXPECT_FALSE(extraction_grid_spacing(s.positions(), mean_edge_length(s)));
  // Its coordinates rounded to 4 decimals: all three on a grid of 1e-4, far below its edge length.
  std::vector<Vec3> rounded = s.positions();
  for (Vec3& p : rounded)
    for (int a = 0; a < 3; ++a) p[a] = std::round(p[a] * 1e4) * 1e-4;
  EXPECT_FALSE(extraction_grid_spacing(rounded, mean_edge_length(s)));
  // Marching-cubes output tracked and resampled: most vertices moved off the planes.
  test::Soup soup;
  soup.positions = m.positions();
  for (std::size_t f = 0; f < m.faces_size(); ++f) {
    const auto v = m.vertices(Face(Index(f)));
    soup.triangles.push_back({v[0].idx, v[1].idx, v[2].idx});
  }
  test::jitter(soup, 0.01 * h, 7);
  EXPECT_FALSE(extraction_grid_spacing(soup.positions, l));
  EXPECT_FALSE(extraction_grid_spacing(std::vector<Vec3>(10, Vec3::Zero()), 1.0));  // too few points
  std::vector<Vec3> bad = m.positions();
  bad[5].y() = std::nan("");
  EXPECT_FALSE(extraction_grid_spacing(bad, l));
}

}  // namespace
}  // namespace topotrack
