#include "kernels/mesh/surface_mesh.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>

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

// A closed double cone: apexes 0 and 1 over a ring of n vertices (apex valence n: more than the 32 corners
// from_triangles sorts by insertion).
test::Soup double_cone(int n) {
  test::Soup s;
  s.positions = {Vec3(0, 0, 1), Vec3(0, 0, -1)};
  for (int i = 0; i < n; ++i) s.positions.emplace_back(std::cos(2 * M_PI * i / n), std::sin(2 * M_PI * i / n), 0);
  for (int i = 0; i < n; ++i) {
    const Index a = Index(2 + i), b = Index(2 + (i + 1) % n);
    s.triangles.push_back({0, a, b});
    s.triangles.push_back({1, b, a});
  }
  return s;
}

// Whether building with require_closed accepts the soup, and whether the reference (build, then the full
// validate(true)) does.
std::pair<bool, bool> closed_build_and_reference(const test::Soup& s) {
  bool closed_ok = true, reference_ok = true;
  try {
    SurfaceMesh::from_triangles(s.positions, s.triangles, {}, true);
  } catch (const InvalidInput&) {
    closed_ok = false;
  }
  try {
    s.mesh().validate(true);
  } catch (const Error&) {
    reference_ok = false;
  }
  return {closed_ok, reference_ok};
}

TEST(SurfaceMesh, ClosedBuildAcceptsExactlyWhatValidateAccepts) {
  std::vector<std::pair<std::string, test::Soup>> soups = {
      {"tetrahedron", test::tetrahedron()}, {"icosphere", test::icosphere(3)},  {"torus", test::torus(16, 9)},
      {"two spheres", test::merge(test::icosphere(1), test::icosphere(2, 1.0, Vec3(3, 0, 0)))},
      {"double cone", double_cone(40)},     {"open box", test::open_box()}};
  {
    auto s = test::icosphere(2);
    s.positions.emplace_back(5, 5, 5);  // a vertex in no triangle
    soups.emplace_back("unused vertex", s);
  }
  {
    auto s = test::icosphere(2);
    s.triangles.erase(s.triangles.begin() + 17);  // a hole
    soups.emplace_back("hole", s);
  }
  {
    auto s = test::merge(test::tetrahedron(), test::tetrahedron());  // closed, but vertex 0 joins two fans
    for (auto& t : s.triangles)
      for (auto& i : t)
        if (i == 4) i = 0;
    soups.emplace_back("pinched", s);
  }
  {
    auto s = double_cone(40);  // both apexes' fans touch at a ring vertex: two cones sharing vertex 2
    auto t = double_cone(40);
    for (auto& p : t.positions) p.x() += 2;
    s = test::merge(s, t);
    for (auto& tri : s.triangles)
      for (auto& i : tri)
        if (i == 42 + 2 + 20) i = 2;
    soups.emplace_back("cones sharing a rim vertex", s);
  }
  {
    auto s = test::icosphere(2);
    std::swap(s.triangles[5][0], s.triangles[5][1]);
    soups.emplace_back("flipped triangle", s);
  }
  int accepted = 0;
  for (const auto& [name, s] : soups) {
    const auto [closed_ok, reference_ok] = closed_build_and_reference(s);
    EXPECT_EQ(closed_ok, reference_ok) << name;
    accepted += closed_ok;
  }
  EXPECT_EQ(accepted, 5);
  EXPECT_THROW(SurfaceMesh::from_triangles(test::open_box().positions, test::open_box().triangles, {}, true), InvalidInput);
}

TEST(SurfaceMesh, ClosedBuildRejectsEveryRemovedTriangleAndUnusedVertex) {
  const test::Soup base = test::icosphere(1);
  for (std::size_t f = 0; f < base.triangles.size(); ++f) {
    auto s = base;
    s.triangles.erase(s.triangles.begin() + std::ptrdiff_t(f));
    EXPECT_THROW(SurfaceMesh::from_triangles(s.positions, s.triangles, {}, true), InvalidInput) << f;
    EXPECT_NO_THROW(s.mesh().validate(false)) << f;
  }
  // Every triangle of one vertex's fan removed: the hole, and then the vertex itself, are rejected.
  auto s = base;
  std::erase_if(s.triangles, [](const auto& t) { return t[0] == 0 || t[1] == 0 || t[2] == 0; });
  EXPECT_THROW(SurfaceMesh::from_triangles(s.positions, s.triangles, {}, true), InvalidInput);
}

TEST(SurfaceMesh, EdgesAreNumberedByVertexPair) {
  // Edge e joins the e-th smallest (min, max) vertex pair; its halfedge 0 is in the lower-numbered triangle.
  for (const auto& soup : {test::icosphere(3), test::torus(20, 7), double_cone(50), test::open_box()}) {
    auto s = soup;
    std::mt19937 rng(3);
    std::shuffle(s.triangles.begin(), s.triangles.end(), rng);
    for (auto& t : s.triangles) std::rotate(t.begin(), t.begin() + rng() % 3, t.end());
    const SurfaceMesh m = s.mesh();
    ASSERT_NO_THROW(m.validate(false));
    std::vector<std::pair<Index, Index>> pairs;
    for (const auto& t : s.triangles)
      for (int k = 0; k < 3; ++k) pairs.emplace_back(std::min(t[k], t[(k + 1) % 3]), std::max(t[k], t[(k + 1) % 3]));
    std::sort(pairs.begin(), pairs.end());
    pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
    ASSERT_EQ(m.edges_size(), pairs.size());
    for (Index e = 0; e < m.edges_size(); ++e) {
      const Index a = m.vertex(Edge(e), 0).idx, b = m.vertex(Edge(e), 1).idx;
      EXPECT_EQ(std::make_pair(std::min(a, b), std::max(a, b)), pairs[e]) << e;
      const Face f0 = m.face(m.halfedge(Edge(e), 0)), f1 = m.face(m.halfedge(Edge(e), 1));
      ASSERT_TRUE(f0.is_valid());
      if (f1.is_valid()) {
        EXPECT_LT(f0.idx, f1.idx);
      }
    }
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
