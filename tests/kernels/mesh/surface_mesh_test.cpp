#include "kernels/mesh/surface_mesh.hpp"

#include <gtest/gtest.h>

#include <random>

#include "kernels/mesh/mesh_queries.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

TEST(SurfaceMesh, BuildsClosedMeshes) {
  for (const auto& soup : {test::tetrahedron(), test::icosphere(2), test::torus(12, 8)}) {
    SurfaceMesh m = soup.mesh();
    EXPECT_NO_THROW(m.validate());
    EXPECT_EQ(m.n_vertices(), soup.positions.size());
    EXPECT_EQ(m.n_faces(), soup.triangles.size());
    EXPECT_EQ(m.n_edges() * 2, m.n_faces() * 3);
  }
  EXPECT_EQ(euler_characteristic(test::icosphere(2).mesh()), 2);
  EXPECT_EQ(euler_characteristic(test::torus(12, 8).mesh()), 0);
  EXPECT_EQ(genus(test::torus(12, 8).mesh()), 1);
}

TEST(SurfaceMesh, OpenMeshHasBoundary) {
  SurfaceMesh m = test::open_box().mesh();
  EXPECT_NO_THROW(m.validate(false));
  EXPECT_THROW(m.validate(true), TopologyError);
  EXPECT_EQ(boundary_edge_count(m), 4u);
  for (Index v = 4; v < 8; ++v) EXPECT_TRUE(m.is_boundary(Vertex(v)));
  EXPECT_FALSE(m.is_boundary(Vertex(0)));
}

TEST(SurfaceMesh, RejectsBrokenSoups) {
  auto tet = test::tetrahedron();
  {
    auto s = tet;
    s.triangles[0] = {0, 0, 1};
    EXPECT_THROW(s.mesh(), InvalidInput);
  }
  {
    auto s = tet;
    s.triangles[0] = {0, 1, 9};
    EXPECT_THROW(s.mesh(), InvalidInput);
  }
  {
    auto s = tet;
    std::swap(s.triangles[0][0], s.triangles[0][1]);  // flip one triangle's orientation
    EXPECT_THROW(s.mesh(), InvalidInput);
  }
  {
    auto s = tet;
    s.triangles.push_back({0, 1, 3});  // third triangle on edge (0,1)
    EXPECT_THROW(s.mesh(), InvalidInput);
  }
  {
    // Two tetrahedra sharing only vertex 0: a non-manifold vertex.
    auto s = test::merge(tet, tet);
    for (auto& t : s.triangles)
      for (auto& i : t)
        if (i == 4) i = 0;
    EXPECT_THROW(s.mesh(), InvalidInput);
  }
}

TEST(SurfaceMesh, IdsArePersistentAndFresh) {
  SurfaceMesh m = test::icosphere(1).mesh();
  const VertexId next = m.next_id();
  EXPECT_EQ(next, m.n_vertices());
  const Vertex v = m.split(Edge(0), 0.5 * (m.position(m.vertex(Edge(0), 0)) + m.position(m.vertex(Edge(0), 1))));
  EXPECT_EQ(m.id(v), next);
  EXPECT_EQ(m.next_id(), next + 1);
  m.validate();
}

TEST(SurfaceMesh, SplitEdgeAndFaceKeepInvariants) {
  SurfaceMesh m = test::icosphere(1).mesh();
  const std::size_t nv = m.n_vertices(), nf = m.n_faces();
  for (Index e = 0; e < 10; ++e) {
    const Vec3 mid = 0.5 * (m.position(m.vertex(Edge(e), 0)) + m.position(m.vertex(Edge(e), 1)));
    m.split(Edge(e), mid);
    ASSERT_NO_THROW(m.validate());
  }
  EXPECT_EQ(m.n_vertices(), nv + 10);
  EXPECT_EQ(m.n_faces(), nf + 20);
  const auto t = m.vertices(Face(3));
  const Vec3 c = (m.position(t[0]) + m.position(t[1]) + m.position(t[2])) / 3;
  m.split(Face(3), c, {1.0 / 3, 1.0 / 3, 1.0 / 3});
  EXPECT_NO_THROW(m.validate());
  EXPECT_EQ(euler_characteristic(m), 2);
}

TEST(SurfaceMesh, SplitBoundaryEdge) {
  SurfaceMesh m = test::open_box().mesh();
  Edge boundary;
  for (Index e = 0; e < m.edges_size(); ++e)
    if (m.is_boundary(Edge(e))) boundary = Edge(e);
  ASSERT_TRUE(boundary.is_valid());
  const Vertex v = m.split(boundary, Vec3(0.5, 0.5, 1.0));
  EXPECT_NO_THROW(m.validate(false));
  EXPECT_TRUE(m.is_boundary(v));
  EXPECT_EQ(boundary_edge_count(m), 5u);
}

TEST(SurfaceMesh, RandomCollapsesFlipsSplitsThenCompact) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 5; ++trial) {
    SurfaceMesh m = test::icosphere(3).mesh();
    auto prop = m.add_vertex_property<float>("x", 2);
    for (Index v = 0; v < m.vertices_size(); ++v) {
      prop(Vertex(v), 0) = float(m.position(Vertex(v)).x());
      prop(Vertex(v), 1) = 1.0f;
    }
    std::size_t collapses = 0;
    for (int op = 0; op < 400; ++op) {
      const Index e = std::uniform_int_distribution<Index>(0, Index(m.edges_size() - 1))(rng);
      if (m.is_deleted(Edge(e))) continue;
      const int kind = op % 3;
      if (kind == 0) {
        const Halfedge h = m.halfedge(Edge(e), 0);
        if (!m.is_collapse_ok(h)) continue;
        const Vec3 mid = 0.5 * (m.position(m.from_vertex(h)) + m.position(m.to_vertex(h)));
        m.collapse(h, mid);
        ++collapses;
      } else if (kind == 1) {
        if (m.is_flip_ok(Edge(e))) m.flip(Edge(e));
      } else {
        m.split(Edge(e), 0.5 * (m.position(m.vertex(Edge(e), 0)) + m.position(m.vertex(Edge(e), 1))));
      }
      ASSERT_NO_THROW(m.validate()) << "trial " << trial << " op " << op;
      ASSERT_EQ(euler_characteristic(m), 2);
    }
    EXPECT_GT(collapses, 0u);
    std::vector<VertexId> ids_before;
    for (Index v = 0; v < m.vertices_size(); ++v)
      if (!m.is_deleted(Vertex(v))) ids_before.push_back(m.id(Vertex(v)));
    const auto maps = m.compact();
    EXPECT_FALSE(m.has_garbage());
    ASSERT_NO_THROW(m.validate());
    EXPECT_EQ(m.ids(), ids_before);  // ids survive compaction, in order
    EXPECT_EQ(euler_characteristic(m), 2);
    for (Index v = 0; v < m.vertices_size(); ++v) EXPECT_FLOAT_EQ(m.get_vertex_property<float>("x")(Vertex(v), 1), 1.0f);
    std::size_t live = 0;
    for (Index i : maps.vertices) live += i != kInvalidIndex;
    EXPECT_EQ(live, m.n_vertices());
  }
}

TEST(SurfaceMesh, CollapseRefusedOnTetrahedron) {
  SurfaceMesh m = test::tetrahedron().mesh();
  for (Index h = 0; h < m.halfedges_size(); ++h) EXPECT_FALSE(m.is_collapse_ok(Halfedge(h)));
  for (Index e = 0; e < m.edges_size(); ++e) EXPECT_FALSE(m.is_flip_ok(Edge(e)));
}

TEST(SurfaceMesh, CloneIsDeep) {
  SurfaceMesh a = test::icosphere(1).mesh();
  SurfaceMesh b = a.clone();
  b.position(Vertex(0)) = Vec3(9, 9, 9);
  EXPECT_NE(a.position(Vertex(0)), b.position(Vertex(0)));
  b.validate();
}

TEST(SurfaceMesh, PropertiesAreTyped) {
  SurfaceMesh m = test::icosphere(0).mesh();
  auto p = m.add_vertex_property<double>("w", 3, 2.0);
  EXPECT_EQ(p.width(), 3);
  EXPECT_EQ(p[Vertex(5)].size(), 3u);
  EXPECT_DOUBLE_EQ(p(Vertex(5), 2), 2.0);
  EXPECT_FALSE(m.get_vertex_property<float>("w").is_valid());
  EXPECT_TRUE(m.get_vertex_property<double>("w").is_valid());
  EXPECT_THROW(m.add_vertex_property<double>("w"), Error);
  m.remove_vertex_property("w");
  EXPECT_FALSE(m.get_vertex_property<double>("w").is_valid());
}

}  // namespace
}  // namespace topotrack
