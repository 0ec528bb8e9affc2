// Tests of the §4.4 patch march's adjacency (patch_march.hpp).
#include "kernels/topology/patch_march.hpp"

#include <gtest/gtest.h>

#include "tests/support/test_meshes.hpp"

namespace topotrack::topology {
namespace {

void expect_same(const std::vector<MarchedPatch>& a, const std::vector<MarchedPatch>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].order, b[i].order) << i;
    EXPECT_EQ(a[i].rule_begin, b[i].rule_begin) << i;
    EXPECT_EQ(a[i].terms, b[i].terms) << i;
    EXPECT_EQ(a[i].ruled, b[i].ruled) << i;
    EXPECT_EQ(a[i].boundary, b[i].boundary) << i;
  }
}

// Patches: a cap, a band, a single vertex and a whole second component (no boundary, no rules), on a mesh
// with deleted vertices (collapses, not compacted).
TEST(PatchMarch, RowsOfThePatchesOnlyGiveTheSameMarch) {
  SurfaceMesh m = test::merge(test::icosphere(3), test::icosphere(1, 0.5, Vec3(3, 0, 0))).mesh();
  const std::size_t first = test::icosphere(3).positions.size();
  int collapsed = 0;
  for (Index h = 0; h < m.halfedges_size() && collapsed < 20; h += 97)
    if (!m.is_deleted(SurfaceMesh::edge(Halfedge(h))) && m.is_collapse_ok(Halfedge(h))) {
      m.collapse(Halfedge(h), m.position(m.to_vertex(Halfedge(h))));
      ++collapsed;
    }
  ASSERT_GT(collapsed, 5);
  ASSERT_NO_THROW(m.validate(true));
  std::vector<std::uint8_t> in(m.vertices_size(), 0);
  std::size_t marked = 0;
  Index single = kInvalidIndex;  // a lone vertex near the south pole
  for (Index v = 0; v < first; ++v)
    if (!m.is_deleted(Vertex(v)) && m.position(Vertex(v)).z() < -0.9) single = v;
  ASSERT_NE(single, kInvalidIndex);
  for (Index v = 0; v < m.vertices_size(); ++v) {
    if (m.is_deleted(Vertex(v))) continue;
    const Vec3& p = m.position(Vertex(v));
    in[v] = v >= first || (v < first && (p.z() > 0.8 || std::abs(p.z()) < 0.1)) || v == single;
    marked += in[v];
  }
  ASSERT_GT(marked, 50u);
  std::vector<std::uint32_t> full_begin, rows_begin;
  std::vector<Index> full, rows;
  mesh_adjacency(m, full_begin, full);
  mesh_adjacency(m, in, rows_begin, rows);
  ASSERT_EQ(rows_begin.size(), full_begin.size());
  EXPECT_LT(rows.size(), full.size());
  for (Index v = 0; v < m.vertices_size(); ++v) {
    const std::vector<Index> want(full.begin() + full_begin[v], full.begin() + full_begin[v + 1]);
    const std::vector<Index> got(rows.begin() + rows_begin[v], rows.begin() + rows_begin[v + 1]);
    if (in[v]) {
      EXPECT_EQ(got, want) << v;
    } else {
      EXPECT_TRUE(got.empty()) << v;
    }
  }
  const auto expected = march_patches(in, full_begin, full);
  EXPECT_EQ(expected.size(), 4u);  // cap, band, lone vertex, second sphere
  expect_same(march_patches(in, rows_begin, rows), expected);
}

TEST(PatchMarch, RowFlagsMustCoverTheVertices) {
  const SurfaceMesh m = test::tetrahedron().mesh();
  std::vector<std::uint32_t> begin;
  std::vector<Index> adj;
  EXPECT_THROW(mesh_adjacency(m, std::vector<std::uint8_t>(3, 1), begin, adj), InvalidInput);
}

}  // namespace
}  // namespace topotrack::topology
