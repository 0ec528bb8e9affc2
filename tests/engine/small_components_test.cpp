// Components below the lattice's resolution (engine/small_components.hpp): copied from S into M when M lacks
// them, removed from M when S lacks them or when they lie on a larger part of M, kept when both have them; and,
// in the tracker, a droplet thinner than a voxel is in the output with the defaults and lost with the paper's
// rule.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "engine/small_components.hpp"
#include "engine/tracker.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

constexpr double kRadius = 0.025;      // half a voxel of 0.05
constexpr double kMaxExtent = 0.4;     // 8 voxels
constexpr double kEdge = 0.05;         // L: octahedra for components up to 2√2 L = 0.141 across

//! A flat speck: an icosahedron squashed to 5 % of its height in z, centred at c, `size` across in x and y.
test::Soup flat_speck(const Vec3& c, double size) {
  test::Soup s = test::icosphere(0, 0.5 * size);
  for (Vec3& p : s.positions) p = c + Vec3(p.x(), p.y(), 0.05 * p.z());
  return s;
}

double min_dihedral_deg(const SurfaceMesh& m) {
  double lo = 180;
  for (Index e = 0; e < m.edges_size(); ++e) {
    if (m.is_deleted(Edge(e))) continue;
    const Vec3 a = face_normal(m, m.face(m.halfedge(Edge(e), 0))), b = face_normal(m, m.face(m.halfedge(Edge(e), 1)));
    lo = std::min(lo, 180.0 - std::acos(std::clamp(a.dot(b), -1.0, 1.0)) * 180.0 / M_PI);
  }
  return lo;
}

double min_angle_deg(const SurfaceMesh& m) {
  double lo = 180;
  for (Index f = 0; f < m.faces_size(); ++f) {
    const auto v = m.vertices(Face(f));
    for (int k = 0; k < 3; ++k) {
      const Vec3 a = m.position(v[(k + 1) % 3]) - m.position(v[k]), b = m.position(v[(k + 2) % 3]) - m.position(v[k]);
      lo = std::min(lo, std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI);
    }
  }
  return lo;
}

//! The vertices of M whose id is not among `before`'s.
std::vector<Vertex> new_vertices(const SurfaceMesh& m, const SurfaceMesh& before) {
  std::set<VertexId> old(before.ids().begin(), before.ids().end());
  std::vector<Vertex> out;
  for (Index i = 0; i < m.vertices_size(); ++i)
    if (!old.count(m.id(Vertex(i)))) out.push_back(Vertex(i));
  return out;
}

TEST(SmallComponents, CopiesASpeckMLacksAsAWellShapedOctahedron) {
  const test::Soup sphere = test::icosphere(3, 1.0);
  SurfaceMesh m = sphere.mesh();
  const SurfaceMesh before = m.clone();
  const Vec3 c(1.5, 0.2, 0.1);
  const TargetSurface s(test::merge(sphere, flat_speck(c, 0.08)).positions, test::merge(sphere, flat_speck(c, 0.08)).triangles);
  EventList events;
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, &events);
  EXPECT_EQ(r.added, 1u);
  EXPECT_EQ(r.removed, 0u);
  m.validate();
  EXPECT_EQ(connected_components(m), 2);
  // M's own vertices keep their ids and positions, in order.
  for (Index i = 0; i < before.vertices_size(); ++i) {
    EXPECT_EQ(m.id(Vertex(i)), before.id(Vertex(i)));
    EXPECT_EQ(m.position(Vertex(i)), before.position(Vertex(i)));
  }
  const std::vector<Vertex> added = new_vertices(m, before);
  ASSERT_EQ(added.size(), 6u);
  for (Vertex v : added) {
    EXPECT_LT((m.position(v) - c).norm(), 0.041 + 1e-9);  // spans the speck's extent
    EXPECT_GE(m.id(v), before.next_id());
  }
  // The copied speck is flat (its dihedrals are folds); the octahedron meets the quality bounds of §4.1.
  EXPECT_GE(min_dihedral_deg(m), 45.0);
  EXPECT_GE(min_angle_deg(m), 10.0);
  // One PatchCreate event: the new vertices, each with the material of the closest point of M.
  ASSERT_EQ(events.size(), 1u);
  const EventList::View e = events.event(0);
  EXPECT_EQ(e.kind, EventKind::PatchCreate);
  EXPECT_EQ(e.forward_end - e.forward_begin, 6u);
  for (std::size_t k = e.forward_begin; k < e.forward_end; ++k) {
    const EventList::Rule rule = events.rule(k);
    double w = 0;
    for (const RuleTerm& t : rule.terms) {
      w += t.weight;
      EXPECT_LT(t.source, before.next_id());  // sources are vertices M already had
    }
    EXPECT_NEAR(w, 1.0, 1e-12);
  }
}

TEST(SmallComponents, CopiesALargerComponentTriangleForTriangle) {
  const test::Soup sphere = test::icosphere(3, 1.0);
  const test::Soup blob = test::icosphere(1, 0.1, Vec3(1.6, 0, 0));  // 0.2 across: above 2√2 L, below the limit
  SurfaceMesh m = sphere.mesh();
  const test::Soup both = test::merge(sphere, blob);
  const TargetSurface s(both.positions, both.triangles);
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, nullptr);
  EXPECT_EQ(r.added, 1u);
  EXPECT_EQ(m.n_vertices(), sphere.positions.size() + blob.positions.size());
  EXPECT_EQ(m.n_faces(), sphere.triangles.size() + blob.triangles.size());
}

TEST(SmallComponents, LeavesMAloneWhereBothHaveTheComponent) {
  const test::Soup sphere = test::icosphere(3, 1.0);
  const test::Soup blob = test::icosphere(1, 0.05, Vec3(1.5, 0, 0));
  test::Soup moved = test::icosphere(1, 0.05, Vec3(1.51, 0, 0));  // the alignment left it 0.01 off
  SurfaceMesh m = test::merge(sphere, moved).mesh();
  const SurfaceMesh before = m.clone();
  const test::Soup both = test::merge(sphere, blob);
  const TargetSurface s(both.positions, both.triangles);
  EventList events;
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, &events);
  EXPECT_EQ(r.added + r.removed, 0u);
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(m.positions(), before.positions());
  EXPECT_EQ(m.ids(), before.ids());
}

TEST(SmallComponents, CopiesACrumbBesideALargerPartWhereItLiesApart) {
  // A flat crumb 0.012 above the sphere's north pole, within `radius` (0.025) of it (the resurfaced samba's
  // frame 20 has one 0.07 voxels from the body). Its octahedron, thickened to half its width, would cut into
  // the sphere where the crumb is; moved away from M it lies apart, and M gets the input's components.
  const test::Soup sphere = test::icosphere(3, 1.0);
  SurfaceMesh m = sphere.mesh();
  const SurfaceMesh before = m.clone();
  const Vec3 c(0, 0, 1.012);
  const test::Soup both = test::merge(sphere, flat_speck(c, 0.04));
  const TargetSurface s(both.positions, both.triangles);
  EventList events;
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, &events);
  EXPECT_EQ(r.added, 1u);
  m.validate();
  EXPECT_EQ(connected_components(m), 2);
  EXPECT_EQ(euler_characteristic(m), 4);
  const std::vector<Vertex> added = new_vertices(m, before);
  ASSERT_EQ(added.size(), 6u);
  double lowest = 2;
  for (Vertex v : added) {
    lowest = std::min(lowest, m.position(v).z());
    EXPECT_LT((m.position(v) - c).norm(), 0.02 + 2 * kRadius + 1e-9);  // moved by at most 2 radius
  }
  // Above the sphere (whose highest point is its pole at 1), not through it.
  EXPECT_GT(lowest, 1.0);
  EXPECT_GE(min_dihedral_deg(m), 45.0);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events.event(0).kind, EventKind::PatchCreate);
}

TEST(SmallComponents, LeavesACrumbInsideM) {
  // M's sphere is larger than S's: it covers S's crumb, 0.008 below M's surface. Moving the copy away from M's
  // closest point takes it deeper in; nothing is copied.
  const test::Soup sphere = test::icosphere(3, 1.0), bigger = test::icosphere(3, 1.02);
  SurfaceMesh m = bigger.mesh();
  const test::Soup both = test::merge(sphere, flat_speck(Vec3(0, 0, 1.012), 0.04));
  const TargetSurface s(both.positions, both.triangles);
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, nullptr);
  EXPECT_EQ(r.added, 0u);
  EXPECT_EQ(connected_components(m), 1);
}

TEST(SmallComponents, RemovesAComponentSNoLongerHas) {
  const test::Soup sphere = test::icosphere(3, 1.0);
  SurfaceMesh m = test::merge(sphere, test::icosphere(1, 0.05, Vec3(1.5, 0, 0))).mesh();
  const SurfaceMesh before = m.clone();
  const TargetSurface s(sphere.positions, sphere.triangles);
  EventList events;
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, &events);
  EXPECT_EQ(r.removed, 1u);
  EXPECT_EQ(r.added, 0u);
  EXPECT_EQ(connected_components(m), 1);
  EXPECT_EQ(m.n_vertices(), sphere.positions.size());
  ASSERT_EQ(events.size(), 1u);
  const EventList::View e = events.event(0);
  EXPECT_EQ(e.kind, EventKind::PatchDelete);
  EXPECT_EQ(e.backward_end - e.backward_begin, before.n_vertices() - sphere.positions.size());
  EXPECT_EQ(e.forward_end, e.forward_begin);
}

TEST(SmallComponents, RemovesADropletLyingOnALargerPart) {
  // The droplet merged into the sphere in S; the alignment laid M's copy of it on the sphere.
  const test::Soup sphere = test::icosphere(3, 1.0);
  SurfaceMesh m = test::merge(sphere, flat_speck(Vec3(0, 0, 1.0), 0.06)).mesh();
  const TargetSurface s(sphere.positions, sphere.triangles);
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, nullptr);
  EXPECT_EQ(r.removed, 1u);
  EXPECT_EQ(connected_components(m), 1);
}

TEST(SmallComponents, KeepsAPieceThatCoversALargerPartOfS) {
  // S has a second large sphere that M covers only with a small piece (as where the lattice cut a thin
  // part off): the piece is near S, not on M's large components, and stays.
  const test::Soup a = test::icosphere(3, 1.0), b = test::icosphere(3, 1.0, Vec3(4, 0, 0));
  SurfaceMesh m = test::merge(a, flat_speck(Vec3(3, 0, 0), 0.06)).mesh();
  const test::Soup both = test::merge(a, b);
  const TargetSurface s(both.positions, both.triangles);
  const SmallComponentReport r = match_small_components(m, s, kRadius, kMaxExtent, kEdge, nullptr);
  EXPECT_EQ(r.removed, 0u);
  EXPECT_EQ(r.added, 0u);
  EXPECT_EQ(connected_components(m), 2);
}

TEST(SmallComponents, IgnoresComponentsAboveTheSizeLimit) {
  const test::Soup sphere = test::icosphere(3, 1.0);
  const test::Soup big = test::icosphere(2, 0.3, Vec3(2, 0, 0));  // 0.6 across, above the 0.4 limit
  SurfaceMesh m = sphere.mesh();
  const test::Soup both = test::merge(sphere, big);
  const TargetSurface s(both.positions, both.triangles);
  EXPECT_EQ(match_small_components(m, s, kRadius, kMaxExtent, kEdge, nullptr).added, 0u);
  SurfaceMesh m2 = both.mesh();
  const TargetSurface s2(sphere.positions, sphere.triangles);
  EXPECT_EQ(match_small_components(m2, s2, kRadius, kMaxExtent, kEdge, nullptr).removed, 0u);
}

//! A marching-cubes peanut with, from the second frame on, a droplet far thinner than the tracker's voxel
//! beside it (the resurfaced captures' crumbs, a simulation's spray).
std::vector<SurfaceMesh> peanut_with_droplet() {
  std::vector<SurfaceMesh> frames;
  for (int i = 0; i < 3; ++i) {
    test::Soup body = test::icosphere(4, 0.5, Vec3(0.02 * i, 0, 0));
    const auto grid = signed_distance(body.positions, body.triangles, 0.05, 3.0);
    SurfaceMesh f = to_surface_mesh(marching_cubes(*grid));
    if (i > 0) {
      std::vector<Vec3> pos;
      std::vector<std::array<Index, 3>> tris;
      for (Index v = 0; v < f.vertices_size(); ++v) pos.push_back(f.position(Vertex(v)));
      for (Index t = 0; t < f.faces_size(); ++t) {
        const auto v = f.vertices(Face(t));
        tris.push_back({v[0].idx, v[1].idx, v[2].idx});
      }
      const test::Soup drop = flat_speck(Vec3(0.85 + 0.02 * i, 0.1, 0), 0.03);
      for (const auto& t : drop.triangles)
        tris.push_back({t[0] + Index(pos.size()), t[1] + Index(pos.size()), t[2] + Index(pos.size())});
      pos.insert(pos.end(), drop.positions.begin(), drop.positions.end());
      f = SurfaceMesh::from_triangles(pos, tris);
    }
    frames.push_back(std::move(f));
  }
  return frames;
}

TEST(SmallComponents, TrackerKeepsASubVoxelDropletAndThePapersRuleLosesIt) {
  const auto frames = peanut_with_droplet();
  for (double voxels : {8.0, 0.0}) {
    TrackerParams p;
    p.small_component_voxels = voxels;
    Tracker tracker(p);
    for (const SurfaceMesh& f : frames) tracker.add_frame(f);
    EXPECT_EQ(connected_components(tracker.mesh()), voxels > 0 ? 2 : 1) << voxels;
    tracker.mesh().validate();
    if (voxels > 0) {
      EXPECT_GE(min_dihedral_deg(tracker.mesh()), 45.0);
    }
  }
}

}  // namespace
}  // namespace topotrack
