#include "kernels/sdf/marching_cubes.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <map>
#include <random>

#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

// A dense random field on [0, n)^3, every voxel active, background +1 (outside) around it.
openvdb::FloatGrid::Ptr random_grid(int n, unsigned seed, bool quantized) {
  ensure_openvdb_initialized();
  auto grid = openvdb::FloatGrid::create(1.0f);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> q(-1, 1);
  auto acc = grid->getAccessor();
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) acc.setValue(openvdb::Coord(i - 3, j - 2, k - 5), quantized ? float(q(rng)) : u(rng));
  return grid;
}

SurfaceMesh as_surface(const MeshData& m) { return to_surface_mesh(m); }

double min_triangle_area(const MeshData& m) {
  double a = std::numeric_limits<double>::infinity();
  for (const auto& t : m.triangles) {
    Vec3 p[3];
    for (int j = 0; j < 3; ++j) p[j] = Vec3(m.positions[t[j]][0], m.positions[t[j]][1], m.positions[t[j]][2]);
    a = std::min(a, 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).norm());
  }
  return a;
}

TEST(MarchingCubes, RandomFieldsGiveClosedManifolds) {
  for (unsigned seed = 1; seed <= 150; ++seed) {
    const bool quantized = seed % 3 == 0;
    auto grid = random_grid(4 + int(seed % 5), seed, quantized);
    const MeshData m = marching_cubes(*grid);
    if (m.triangles.empty()) continue;
    SurfaceMesh s;
    ASSERT_NO_THROW(s = as_surface(m)) << "seed " << seed;
    ASSERT_NO_THROW(s.validate(true)) << "seed " << seed;
    EXPECT_EQ(s.n_vertices(), m.vertex_count()) << "seed " << seed;
    EXPECT_EQ(euler_characteristic(s) % 2, 0);
    EXPECT_GT(min_triangle_area(m), 0.0) << "seed " << seed;
  }
}

TEST(MarchingCubes, ThresholdsAndOrientation) {
  // A single inside voxel: an octahedron around it, normals pointing away from it.
  ensure_openvdb_initialized();
  auto grid = openvdb::FloatGrid::create(1.0f);
  grid->tree().setValue(openvdb::Coord(0, 0, 0), -1.0f);
  const MeshData m = marching_cubes(*grid);
  SurfaceMesh s = as_surface(m);
  s.validate(true);
  EXPECT_EQ(s.n_vertices(), 6u);
  EXPECT_EQ(s.n_faces(), 8u);
  for (std::size_t f = 0; f < s.faces_size(); ++f) {
    const auto v = s.vertices(Face(Index(f)));
    const Vec3 c = (s.position(v[0]) + s.position(v[1]) + s.position(v[2])) / 3.0;
    EXPECT_GT(face_normal(s, Face(Index(f))).dot(c), 0);
  }
  for (const auto& p : m.positions) EXPECT_NEAR(std::abs(p[0]) + std::abs(p[1]) + std::abs(p[2]), 0.5, 1e-9);
}

struct Shape {
  const char* name;
  test::Soup soup;
  long euler;
  Index components;
};

TEST(MarchingCubes, TopologyOfSignedDistanceShapes) {
  std::vector<Shape> shapes;
  shapes.push_back({"sphere", test::icosphere(4, 1.0), 2, 1});
  shapes.push_back({"torus", test::torus(96, 48, 1.0, 0.35), 0, 1});
  shapes.push_back({"two spheres", test::merge(test::icosphere(3, 0.6, Vec3(-1, 0, 0)), test::icosphere(3, 0.6, Vec3(1, 0, 0))), 4, 2});
  for (const auto& sh : shapes) {
    const double h = 0.05;
    auto grid = signed_distance(sh.soup.positions, sh.soup.triangles, h);
    const MeshData m = marching_cubes(*grid);
    SurfaceMesh s = as_surface(m);
    ASSERT_NO_THROW(s.validate(true)) << sh.name;
    EXPECT_EQ(euler_characteristic(s), sh.euler) << sh.name;
    EXPECT_EQ(connected_components(s), sh.components) << sh.name;
    if (std::string(sh.name) == "sphere") {
      // The icosphere's facets lie within 0.01 of the unit sphere.
      for (const auto& p : m.positions) EXPECT_NEAR(std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]), 1.0, 0.5 * h);
    }
  }
}

TEST(MarchingCubes, BandBorderLeavesNoHoles) {
  // A band of half width 1 voxel: crossed edges reach inactive voxels; their background sign closes the surface.
  const test::Soup sphere = test::icosphere(3, 1.0);
  auto grid = signed_distance(sphere.positions, sphere.triangles, 0.1, 1.0);
  SurfaceMesh s = as_surface(marching_cubes(*grid));
  ASSERT_NO_THROW(s.validate(true));
  EXPECT_EQ(euler_characteristic(s), 2);
}

TEST(MarchingCubes, DeterministicAcrossThreadCounts) {
  const test::Soup torus = test::torus(64, 32, 1.0, 0.4);
  auto grid = signed_distance(torus.positions, torus.triangles, 0.03);
  MeshData one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = marching_cubes(*grid);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = marching_cubes(*grid);
  }
  ASSERT_GT(one.vertex_count(), 1000u);
  EXPECT_EQ(one.positions, two.positions);
  EXPECT_EQ(one.triangles, two.triangles);
}

TEST(MarchingCubes, CellSubsetsStitchIntoTheWholeSurface) {
  const test::Soup torus = test::torus(64, 32, 1.0, 0.4);
  auto grid = signed_distance(torus.positions, torus.triangles, 0.05);
  const MeshData whole = marching_cubes(*grid);
  // Every crossed cell, split in two sets by a checkerboard of 4-voxel blocks.
  std::vector<openvdb::Coord> a, b;
  openvdb::CoordBBox box = grid->evalActiveVoxelBoundingBox();
  box.expand(1);
  for (auto it = box.begin(); it; ++it) {
    const std::uint8_t m = inside_mask(cell_values(*grid, *it));
    if (m == 0 || m == 255) continue;
    const openvdb::Coord c = *it;
    (((c.x() >> 2) + (c.y() >> 2) + (c.z() >> 2)) & 1 ? a : b).push_back(c);
  }
  const CellMesh ma = marching_cubes_cells(*grid, a), mb = marching_cubes_cells(*grid, b);
  ASSERT_EQ(ma.triangle_cells.size(), ma.mesh.triangle_count());
  EXPECT_EQ(ma.mesh.triangle_count() + mb.mesh.triangle_count(), whole.triangle_count());
  // Merge by lattice-edge key; centroids stay separate.
  MeshData merged;
  std::map<std::uint64_t, std::int64_t> index;
  for (const CellMesh* cm : {&ma, &mb}) {
    std::vector<std::int64_t> map(cm->mesh.vertex_count());
    for (std::size_t v = 0; v < map.size(); ++v) {
      const std::uint64_t k = cm->vertex_keys[v];
      auto it = k == CellMesh::kCentroidVertex ? index.end() : index.find(k);
      if (it != index.end()) {
        map[v] = it->second;
        EXPECT_EQ(merged.positions[it->second], cm->mesh.positions[v]);
        continue;
      }
      map[v] = std::int64_t(merged.positions.size());
      merged.positions.push_back(cm->mesh.positions[v]);
      if (k != CellMesh::kCentroidVertex) index[k] = map[v];
    }
    for (const auto& t : cm->mesh.triangles) merged.triangles.push_back({map[t[0]], map[t[1]], map[t[2]]});
  }
  EXPECT_EQ(merged.vertex_count(), whole.vertex_count());
  SurfaceMesh s = as_surface(merged);
  ASSERT_NO_THROW(s.validate(true));
  EXPECT_EQ(euler_characteristic(s), 0);
  // A subset alone has boundaries: edges used by one triangle only.
  std::map<std::pair<std::int64_t, std::int64_t>, int> uses;
  for (const auto& t : ma.mesh.triangles)
    for (int j = 0; j < 3; ++j) ++uses[std::minmax(t[j], t[(j + 1) % 3])];
  std::size_t boundary = 0;
  for (const auto& [e, n] : uses) boundary += n == 1;
  EXPECT_GT(boundary, 0u);
}

TEST(MarchingCubes, Errors) {
  ensure_openvdb_initialized();
  auto grid = openvdb::FloatGrid::create(1.0f);
  grid->tree().setValue(openvdb::Coord(0, 0, 0), std::numeric_limits<float>::quiet_NaN());
  grid->tree().setValue(openvdb::Coord(1, 0, 0), -1.0f);
  EXPECT_THROW(marching_cubes(*grid), InvalidInput);
  auto far = openvdb::FloatGrid::create(1.0f);
  far->tree().setValue(openvdb::Coord(1 << 20, 0, 0), -1.0f);
  EXPECT_THROW(marching_cubes(*far), InvalidInput);
  EXPECT_THROW(lattice_edge_key({openvdb::Coord(0, 0, 0), 3}), InvalidInput);
  const LatticeEdge e{openvdb::Coord(-5, 7, -(1 << 19)), 2};
  EXPECT_EQ(lattice_edge_from_key(lattice_edge_key(e)), e);
  auto empty = openvdb::FloatGrid::create(1.0f);
  EXPECT_EQ(marching_cubes(*empty).vertex_count(), 0u);
}

}  // namespace
}  // namespace topotrack
