#include "kernels/mesh/mesh_queries.hpp"

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>

#include "kernels/mesh/mesh_convert.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

TEST(MeshQueries, ComponentsAndGenus) {
  SurfaceMesh two = test::merge(test::icosphere(1), test::icosphere(1, 1.0, Vec3(5, 0, 0))).mesh();
  std::vector<Index> labels;
  EXPECT_EQ(connected_components(two, &labels), 2u);
  EXPECT_EQ(euler_characteristic(two), 4);
  EXPECT_EQ(genus(two), 0);
  EXPECT_NE(labels.front(), labels.back());
  SurfaceMesh t = test::merge(test::torus(16, 8), test::torus(16, 8)).mesh();
  EXPECT_EQ(genus(t), 2);
}

TEST(MeshQueries, GeometryOfSphere) {
  SurfaceMesh m = test::icosphere(4, 2.0).mesh();
  EXPECT_NEAR(surface_area(m), 4 * M_PI * 4, 0.05 * 4 * M_PI * 4);
  const auto n = vertex_normals(m);
  for (Index v = 0; v < m.vertices_size(); ++v) EXPECT_GT(n[v].dot(m.position(Vertex(v)).normalized()), 0.999);
  const BoundingBox b = bounding_box(m);
  EXPECT_NEAR(b.diagonal(), 4 * std::sqrt(3.0), 1e-9);
  const auto q = quality_stats(m);
  EXPECT_GT(q.min_angle_deg, 40);
  EXPECT_GT(q.min_dihedral_deg, 150);
  EXPECT_EQ(q.below_2deg, 0u);
  EXPECT_NEAR(q.edge_length.mean, mean_edge_length(m), 1e-12);
}

// The parallel sum (per face, then per vertex in face order) is bit for bit one loop over the faces, on
// any thread count: the reference below is that loop.
TEST(MeshQueries, VertexNormalsAreTheSerialSumOnAnyThreadCount) {
  test::Soup soup = test::merge(test::icosphere(5), test::torus(64, 32, 1.0, 0.35));
  test::jitter(soup, 0.01, 7);
  const SurfaceMesh m = soup.mesh();
  std::vector<Vec3> expected(m.vertices_size(), Vec3::Zero());
  for (Index f = 0; f < m.faces_size(); ++f) {
    const auto t = m.vertices(Face(f));
    const Vec3 fn = face_normal(m, Face(f));
    for (int k = 0; k < 3; ++k) {
      const Vec3 a = m.position(t[(k + 1) % 3]) - m.position(t[k]), b = m.position(t[(k + 2) % 3]) - m.position(t[k]);
      expected[t[k].idx] += std::atan2(a.cross(b).norm(), a.dot(b)) * fn;
    }
  }
  for (Vec3& n : expected)
    if (const double len = n.norm(); len > 0) n /= len;
  ASSERT_GT(m.faces_size(), 20000u);  // many parallel chunks
  for (const int threads : {1, 2}) {
    tbb::task_arena arena(threads);
    std::vector<Vec3> n;
    arena.execute([&] { n = vertex_normals(m); });
    ASSERT_EQ(n.size(), expected.size());
    EXPECT_EQ(0, std::memcmp(n.data(), expected.data(), n.size() * sizeof(Vec3))) << threads << " threads";
  }
}

TEST(MeshQueries, DihedralOfFold) {
  // Two triangles folded onto each other across edge (0,1): dihedral angle near 0.
  std::vector<Vec3> p = {{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {0.5, 1, 0.01}};
  std::vector<std::array<Index, 3>> t = {{0, 1, 2}, {1, 0, 3}};
  SurfaceMesh m = SurfaceMesh::from_triangles(p, t);
  Edge shared;
  for (Index e = 0; e < m.edges_size(); ++e)
    if (!m.is_boundary(Edge(e))) shared = Edge(e);
  EXPECT_LT(dihedral_angle_deg(m, shared), 5.0);
}

TEST(MeshQueries, NearDegenerateTriangles) {
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(0.5, 0.8, 0);
  EXPECT_FALSE(is_near_degenerate(a, b, c));
  EXPECT_NEAR(min_angle_sin(a, b, Vec3(0, 1, 0)), std::sin(M_PI / 4), 1e-12);
  EXPECT_TRUE(is_near_degenerate(a, b, Vec3(0.5, 0, 0)));      // zero area: a corner on the opposite edge
  EXPECT_TRUE(is_near_degenerate(a, b, Vec3(0.5, 1e-4, 0)));   // cap
  EXPECT_TRUE(is_near_degenerate(a, b, Vec3(1e-4, 1e-5, 0)));  // needle: two corners almost together
  EXPECT_TRUE(is_near_degenerate(a, a, c));
  // Well shaped in double, zero area once rounded to float (as a PLY file stores it, where `eval` looks).
  const Vec3 far(1000, 1000, 1000), d(1e-6, 0, 0), e(0.5e-6, 0.8e-6, 0);
  ASSERT_GT(min_angle_sin(far, far + d, far + e), 0.5);
  EXPECT_TRUE(is_near_degenerate(far, far + d, far + e));
  // quality_stats counts them.
  const SurfaceMesh m = test::icosphere(2).mesh();
  EXPECT_EQ(quality_stats(m).near_degenerate, 0u);
}

TEST(MeshConvert, RoundTripKeepsIdsAndAttributes) {
  MeshData d;
  auto s = test::icosphere(1);
  for (const auto& p : s.positions) d.positions.push_back({p.x(), p.y(), p.z()});
  d.positions.push_back({100, 100, 100});  // unreferenced: dropped
  for (const auto& t : s.triangles) d.triangles.push_back({t[0], t[1], t[2]});
  d.ids.emplace();
  for (std::size_t i = 0; i < d.positions.size(); ++i) d.ids->push_back(std::int64_t(1000 + 3 * i));
  VertexAttribute c{"color", 3, {}};
  for (std::size_t i = 0; i < d.positions.size(); ++i)
    for (int k = 0; k < 3; ++k) c.values.push_back(float(i) + 0.1f * float(k));
  d.attributes.push_back(c);
  SurfaceMesh m = to_surface_mesh(d);
  EXPECT_EQ(m.n_vertices(), s.positions.size());
  EXPECT_EQ(m.id(Vertex(3)), 1009u);
  EXPECT_EQ(m.next_id(), 1000u + 3 * (s.positions.size() - 1) + 1);
  MeshData back = to_mesh_data(m);
  ASSERT_EQ(back.positions.size(), s.positions.size());
  EXPECT_EQ((*back.ids)[5], 1015);
  ASSERT_NE(back.attribute("color"), nullptr);
  EXPECT_FLOAT_EQ(back.attribute("color")->values[3 * 7 + 2], 7.2f);
  EXPECT_EQ(back.triangles, d.triangles);
}

TEST(MeshConvert, RejectsBadData) {
  MeshData d;
  auto s = test::tetrahedron();
  for (const auto& p : s.positions) d.positions.push_back({p.x(), p.y(), p.z()});
  for (const auto& t : s.triangles) d.triangles.push_back({t[0], t[1], t[2]});
  {
    auto b = d;
    b.positions[1][2] = std::nan("");
    EXPECT_THROW(to_surface_mesh(b), InvalidInput);
  }
  {
    auto b = d;
    b.triangles[2][1] = -1;
    EXPECT_THROW(to_surface_mesh(b), InvalidInput);
  }
  {
    auto b = d;
    b.ids = std::vector<std::int64_t>{1, 2, 2, 3};
    EXPECT_THROW(to_surface_mesh(b), InvalidInput);
  }
}

}  // namespace
}  // namespace topotrack
