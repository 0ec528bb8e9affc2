// Tests of ConstrainTopology (§4.3) and its events (§4.4).
#include "kernels/topology/constrain.hpp"

#include <gtest/gtest.h>
#include <openvdb/tools/Composite.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <tbb/global_control.h>

#include <filesystem>

#include "io/mesh_reader.hpp"
#include "kernels/gen/synthetic.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/propagate/propagate.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "kernels/topology/classify.hpp"
#include "kernels/topology/lattice_cut.hpp"
#include "tests/kernels/topology/cell_checks.hpp"
#include "tests/kernels/topology/self_intersection.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

using GridPtr = openvdb::FloatGrid::Ptr;

GridPtr sphere(double r, const Vec3& c, double h) {
  ensure_openvdb_initialized();
  return openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(r), openvdb::Vec3f(float(c.x()), float(c.y()), float(c.z())),
                                                                  float(h), 3.0f);
}
GridPtr unite(GridPtr a, GridPtr b) {
  openvdb::tools::csgUnion(*a, *b);
  return a;
}
SurfaceMesh mc_mesh(const openvdb::FloatGrid& g) { return to_surface_mesh(marching_cubes(g)); }

struct Topo {
  long components, euler;
};
Topo topo(const SurfaceMesh& m) { return {long(connected_components(m)), euler_characteristic(m)}; }

// Closed 2-manifold, consistent, free of self-intersections.
void expect_sound(const SurfaceMesh& m) {
  EXPECT_NO_THROW(m.validate(true));
  EXPECT_EQ(boundary_edge_count(m), 0u);
  std::vector<std::pair<std::array<Index, 3>, std::array<Index, 3>>> pairs;
  EXPECT_EQ(test::count_self_intersections(m, &pairs), 0u);
  for (std::size_t i = 0; i < std::min<std::size_t>(pairs.size(), 4); ++i) {
    std::ostringstream os;
    for (const auto& t : {pairs[i].first, pairs[i].second}) {
      for (Index v : t) os << v << " (" << m.position(Vertex(v)).transpose() << ")  ";
      os << " | ";
    }
    ADD_FAILURE() << "intersecting: " << os.str() << " of " << m.n_vertices();
  }
}

// Θ with the signs ConstrainTopology decides for mesh m: nodes within kSignTolerance of the zero set take
// m's side (classify.hpp).
GridPtr as_decided(const SurfaceMesh& m, const openvdb::FloatGrid& theta) {
  const topology::LatticeCut cut = topology::cut_by_lattice(m, theta.transform());
  const topology::CellIndex index = topology::index_cells(cut, theta);
  GridPtr g = theta.deepCopy();
  auto acc = g->getAccessor();
  const auto src = theta.getConstAccessor();
  for (std::uint64_t k : index.flipped) {
    const openvdb::Coord c = topology::cell_from_key(k);
    acc.setValue(c, topology::node_value(src, index, c));
  }
  return g;
}

// After constraining to Θ, M has Θ's topology (that of its marching-cubes surface).
void expect_topology_of(const SurfaceMesh& m, const openvdb::FloatGrid& theta) {
  const SurfaceMesh target = mc_mesh(theta);
  EXPECT_EQ(topo(m).components, topo(target).components);
  EXPECT_EQ(topo(m).euler, topo(target).euler);
}

TEST(ConstrainTopology, MatchingMeshIsLeftUnchanged) {
  const double h = 0.05;
  GridPtr theta = unite(sphere(0.5, {-0.3, 0, 0}, h), sphere(0.4, {0.35, 0.1, 0}, h));
  SurfaceMesh m = mc_mesh(*theta);
  const std::vector<Vec3> before = m.positions();
  const std::vector<VertexId> ids = m.ids();
  EventList ev;
  const ConstrainReport r = constrain_topology(m, *theta, {}, &ev);
  EXPECT_EQ(r.complex_cells, 0u);
  EXPECT_TRUE(ev.empty());
  EXPECT_EQ(m.positions(), before);
  EXPECT_EQ(m.ids(), ids);
}

// A clean mesh that is not aligned with Θ's lattice, constrained to its own signed distance (exact signs
// near the surface, as the tracker computes φ_M), is well represented wherever M crosses each lattice edge
// at most once: the only complex cells left are those of Wojtan et al.'s edge test (M crossing an edge
// twice where it is nearly tangent to it). Before lattice nodes within kSignTolerance of the surface took
// M's side, every node that the cut's kSnap push moved M across made its cells complex (here 384 of 564
// complex cells; in the blobs demo 28-64 per frame and 1.6 % new vertices per frame).
TEST(ConstrainTopology, CleanMeshAgainstItsOwnDistanceIsComplexOnlyAtMultipleCrossings) {
  using namespace topology;
  SyntheticParams sp;
  sp.kind = SyntheticKind::kBlobs;
  sp.frames = 3;
  const SyntheticScene scene(sp);
  std::size_t complex = 0, sign_only = 0, cells = 0;
  for (int n = 1; n <= 3; n += 2) {
    const SurfaceMesh src = to_surface_mesh(scene.frame_mesh(n));
    const double h = mean_edge_length(src);
    for (int k = 0; k < 3; ++k) {
      // Off the generator's lattice, and off Θ's by a different fraction of a voxel each time.
      SurfaceMesh m = src.clone();
      const Vec3 shift = h * Vec3(0.131 * k + 0.05, 0.071 * k + 0.02, 0.213 * k + 0.01);
      for (Index i = 0; i < m.vertices_size(); ++i) m.position(Vertex(i)) += shift;
      const GridPtr phi = signed_distance(m, h * (1.0 + 0.07 * k), 3.0, 0.25);
      const LatticeCut cut = cut_by_lattice(m, phi->transform());
      const CellIndex index = index_cells(cut, *phi);
      const std::vector<std::uint64_t> bad = complex_cells(m, cut, index, *phi);
      cells += index.cells.size();
      complex += bad.size();
      for (std::uint64_t c : bad) sign_only += !has_multiply_crossed_edge(cut, index, c);
    }
  }
  EXPECT_EQ(sign_only, 0u) << complex << " complex of " << cells << " cells";
  EXPECT_LT(complex, cells / 250);  // 180 of 101540 now, 564 before
}

// The report says why cells were complex: verdict counts over the examined cells, consistent with the
// cells replaced, with a name for each (`topotrack constrain --json` prints them as complex_by_reason).
TEST(ConstrainTopology, ReportsWhyCellsAreComplex) {
  using namespace topology;
  const double h = 0.04;
  SurfaceMesh m = mc_mesh(*unite(sphere(0.5, {-0.42, 0, 0}, h), sphere(0.5, {0.42, 0, 0}, h)));
  const ConstrainReport r = constrain_topology(m, *unite(sphere(0.5, {-0.56, 0.01, 0}, h), sphere(0.5, {0.56, 0.01, 0}, h)));
  std::size_t complex = 0;
  for (int k = 1; k < kVerdictKinds; ++k) complex += r.cells_by_verdict[k];
  EXPECT_GT(complex, 0u);
  EXPECT_LE(complex, r.complex_cells);  // growth and slivers only add cells
  // Θ's balls are 0.14 (3.5 voxels) from M's: cells with M and no sign change of Θ, and the reverse.
  EXPECT_GT(r.cells_by_verdict[int(CellVerdict::kUnmatchedLoop)], 0u);
  EXPECT_GT(r.cells_by_verdict[int(CellVerdict::kMissed)], 0u);
  EXPECT_STREQ(verdict_name(CellVerdict::kSimple), "simple");
  EXPECT_STREQ(verdict_name(CellVerdict::kEdgeCrossedTwice), "edge_crossed_twice");
  // A mesh that already matches: every examined cell simple, nothing replaced.
  SurfaceMesh ball = mc_mesh(*sphere(0.5, {0.01, 0.02, 0.03}, h));
  const ConstrainReport same = constrain_topology(ball, *sphere(0.5, {0.01, 0.02, 0.03}, h));
  EXPECT_EQ(same.complex_cells, 0u);
  for (int k = 1; k < kVerdictKinds; ++k) EXPECT_EQ(same.cells_by_verdict[k], 0u) << verdict_name(CellVerdict(k));
  EXPECT_GT(same.cells_by_verdict[0], 0u);
}

TEST(ConstrainTopology, SphereSplitsIntoTwo) {
  const double h = 0.04;
  // M: two overlapping balls, one component; target: the same balls pulled apart.
  SurfaceMesh m = mc_mesh(*unite(sphere(0.5, {-0.42, 0, 0}, h), sphere(0.5, {0.42, 0, 0}, h)));
  ASSERT_EQ(connected_components(m), 1u);
  GridPtr theta = unite(sphere(0.5, {-0.56, 0.01, 0}, h), sphere(0.5, {0.56, 0.01, 0}, h));
  const std::size_t nv = m.n_vertices();
  EventList ev;
  const ConstrainReport r = constrain_topology(m, *theta, {}, &ev);
  expect_sound(m);
  EXPECT_EQ(connected_components(m), 2u);
  EXPECT_EQ(r.components_before, 1);
  EXPECT_EQ(r.components_after, 2);
  expect_topology_of(m, *theta);
  EXPECT_GT(r.complex_cells, 0u);
  EXPECT_LT(r.vertices_removed, nv);  // a local change, not a re-meshing
  EXPECT_GT(r.patches_created, 0u);
  EXPECT_GT(r.patches_deleted, 0u);
  EXPECT_FALSE(ev.empty());
}

TEST(ConstrainTopology, UnitSphereToTwoSeparateSpheres) {
  SurfaceMesh m = test::icosphere(4).mesh();
  GridPtr theta = unite(sphere(0.45, {-0.55, 0, 0}, 0.05), sphere(0.45, {0.55, 0, 0}, 0.05));
  constrain_topology(m, *theta);
  expect_sound(m);
  EXPECT_EQ(connected_components(m), 2u);
  EXPECT_EQ(euler_characteristic(m), 4);
}

TEST(ConstrainTopology, InterpenetratingSpheresMerge) {
  // ConstrainTopology(M, φ_M): the self-intersection of two overlapping spheres becomes a merge.
  test::Soup s = test::merge(test::icosphere(4, 0.6, Vec3(-0.35, 0, 0)), test::icosphere(4, 0.6, Vec3(0.35, 0.02, 0.01)));
  SurfaceMesh m = s.mesh();
  ASSERT_GT(test::count_self_intersections(m), 0u);
  const GridPtr phi = signed_distance(m, 0.04);
  EventList ev;
  const ConstrainReport r = constrain_topology(m, *phi, {}, &ev);
  expect_sound(m);
  EXPECT_EQ(connected_components(m), 1u);
  EXPECT_EQ(euler_characteristic(m), 2);
  EXPECT_EQ(r.components_before, 2);
  EXPECT_GT(r.vertices_removed, 0u);
}

TEST(ConstrainTopology, TorusAndSphereExchangeGenus) {
  const double h = 0.04;
  test::Soup t = test::torus(96, 48, 1.0, 0.4);
  const SurfaceMesh torus_mesh = t.mesh();
  const GridPtr torus = signed_distance(torus_mesh, h);
  GridPtr filled = signed_distance(torus_mesh, h);
  filled = unite(filled, sphere(0.75, Vec3::Zero(), h));
  {
    SurfaceMesh m = t.mesh();  // torus -> filled torus: genus 1 -> 0
    ASSERT_EQ(genus(m), 1);
    constrain_topology(m, *filled);
    expect_sound(m);
    EXPECT_EQ(genus(m), 0);
    EXPECT_EQ(connected_components(m), 1u);
  }
  {
    SurfaceMesh m = mc_mesh(*filled);  // filled torus -> torus: genus 0 -> 1
    ASSERT_EQ(genus(m), 0);
    constrain_topology(m, *torus);
    expect_sound(m);
    EXPECT_EQ(genus(m), 1);
    EXPECT_EQ(connected_components(m), 1u);
  }
}

TEST(ConstrainTopology, ComponentsAppearAndVanish) {
  const double h = 0.05;
  SurfaceMesh m = mc_mesh(*unite(sphere(0.5, {0, 0, 0}, h), sphere(0.2, {1.2, 0, 0}, h)));
  ASSERT_EQ(connected_components(m), 2u);
  GridPtr theta = unite(sphere(0.5, {0, 0, 0}, h), sphere(0.25, {0, 1.3, 0}, h));
  EventList ev;
  const ConstrainReport r = constrain_topology(m, *theta, {}, &ev);
  expect_sound(m);
  expect_topology_of(m, *theta);
  EXPECT_EQ(r.patches_created, 1u);  // the new ball, created from nothing
  EXPECT_EQ(r.patches_deleted, 1u);  // the old ball
  // A patch with no boundary has no rule: the propagated field is absent there.
  const auto counts = ev.count_by_kind();
  EXPECT_EQ(counts[int(EventKind::PatchCreate) - 1], 1u);
  EXPECT_EQ(counts[int(EventKind::PatchDelete) - 1], 1u);
  const auto c = ev.event(ev.size() - 1);
  EXPECT_TRUE(c.in.empty());
  EXPECT_EQ(c.forward_begin, c.forward_end);
}

TEST(ConstrainTopology, WholeMeshVanishesOrAppears) {
  const double h = 0.05;
  GridPtr empty = openvdb::FloatGrid::create(float(3 * h));
  empty->setTransform(voxel_transform(h));
  empty->setGridClass(openvdb::GRID_LEVEL_SET);
  SurfaceMesh m = test::icosphere(3, 0.5).mesh();
  EventList ev;
  ConstrainReport r = constrain_topology(m, *empty, {}, &ev);
  EXPECT_EQ(m.n_vertices(), 0u);
  EXPECT_EQ(r.patches_deleted, 1u);
  EXPECT_EQ(ev.size(), 1u);
  // And back: an empty mesh constrained to a ball becomes that ball, with fresh ids.
  SurfaceMesh none;
  GridPtr ball = sphere(0.5, Vec3::Zero(), h);
  r = constrain_topology(none, *ball);
  expect_sound(none);
  EXPECT_EQ(connected_components(none), 1u);
  EXPECT_EQ(euler_characteristic(none), 2);
  EXPECT_EQ(r.patches_created, 1u);
}

TEST(ConstrainTopology, EventsPropagateAffineFieldsExactlyAtCutsAndConstantsEverywhere) {
  const double h = 0.04;
  SurfaceMesh m = mc_mesh(*unite(sphere(0.5, {-0.42, 0, 0}, h), sphere(0.5, {0.42, 0, 0}, h)));
  GridPtr theta = unite(sphere(0.5, {-0.56, 0.01, 0}, h), sphere(0.5, {0.56, 0.01, 0}, h));
  // Field before: (1, x) per vertex; also stored as a property to check the carried values.
  IdField before;
  before.width = 2;
  auto prop = m.add_vertex_property<float>("field", 2);
  for (Index v = 0; v < m.vertices_size(); ++v) {
    before.ids.push_back(m.id(Vertex(v)));
    before.values.push_back(1.f);
    before.values.push_back(float(m.position(Vertex(v)).x()));
    prop(Vertex(v), 0) = 1.f;
    prop(Vertex(v), 1) = float(m.position(Vertex(v)).x());
  }
  EventList ev;
  const ConstrainReport r = constrain_topology(m, *theta, {}, &ev);
  PropagateReport pr;
  const IdField after = propagate_forward(ev, before, &pr);
  EXPECT_EQ(pr.targets_missing, 0u);
  ASSERT_EQ(after.ids.size(), m.n_vertices());
  auto carried = m.get_vertex_property<float>("field");
  ASSERT_TRUE(carried.is_valid());
  for (std::size_t i = 0; i < after.ids.size(); ++i) EXPECT_NEAR(after.values[2 * i], 1.0, 1e-5);
  // Every vertex of the result has a value; the carried property equals the propagated one.
  std::unordered_map<VertexId, std::size_t> row;
  for (std::size_t i = 0; i < after.ids.size(); ++i) row[after.ids[i]] = i;
  std::size_t exact = 0;
  for (Index v = 0; v < m.vertices_size(); ++v) {
    const std::size_t i = row.at(m.id(Vertex(v)));
    EXPECT_NEAR(carried(Vertex(v), 0), after.values[2 * i], 1e-5);
    EXPECT_NEAR(carried(Vertex(v), 1), after.values[2 * i + 1], 1e-5);
    exact += std::abs(after.values[2 * i + 1] - m.position(Vertex(v)).x()) < topology::kSnap * h + 1e-5;
  }
  // Kept vertices and the cut points (linear interpolation) reproduce x exactly, up to the move of the
  // vertices next to lattice planes (at most kSnap voxels, see lattice_cut.hpp).
  EXPECT_GE(exact, m.n_vertices() - r.vertices_added + (r.vertices_added > 0 ? 1 : 0));
  // Backward: the removed vertices get values from the kept ones around them.
  const IdField back = propagate_backward(ev, after, &pr);
  EXPECT_EQ(pr.targets_missing, 0u);
  EXPECT_EQ(back.ids.size(), before.ids.size());
}

// ConstrainParams::max_cut_cells: the complex cells found slab by slab, the replacement cut only around
// them. M: two pairs of overlapping balls far apart, one component each; Θ: both pairs pulled apart.
TEST(ConstrainTopology, SlabsGiveTheResultOfOnePass) {
  const double h = 0.04;
  const SurfaceMesh m = mc_mesh(*unite(unite(sphere(0.5, {-2.42, 0, 0}, h), sphere(0.5, {-1.58, 0, 0}, h)),
                                       unite(sphere(0.5, {1.58, 0, 0}, h), sphere(0.5, {2.42, 0, 0}, h))));
  const GridPtr theta = unite(unite(sphere(0.5, {-2.56, 0.01, 0}, h), sphere(0.5, {-1.44, 0.01, 0}, h)),
                              unite(sphere(0.5, {1.44, 0.01, 0}, h), sphere(0.5, {2.56, 0.01, 0}, h)));
  auto run = [&](double max_cut_cells, ConstrainReport& r) {
    SurfaceMesh out = m.clone();
    ConstrainParams p;
    p.max_cut_cells = max_cut_cells;
    EventList ev;
    r = constrain_topology(out, *theta, p, &ev);
    expect_sound(out);
    std::vector<Vec3> P;
    std::vector<std::array<Index, 3>> T;
    extract_triangles(out, P, T);
    return std::tuple(P, T, out.ids(), ev);
  };
  ConstrainReport one, sliced, fine;
  const auto a = run(0, one);
  const auto b = run(20000, sliced);
  const auto c = run(2000, fine);
  EXPECT_EQ(one.slabs, 0);
  EXPECT_GT(sliced.slabs, 1);
  EXPECT_GT(fine.slabs, sliced.slabs);
  EXPECT_EQ(one.components_after, 4);
  EXPECT_GT(one.complex_cells, 0u);
  for (const ConstrainReport* r : {&sliced, &fine}) {
    EXPECT_EQ(r->complex_cells, one.complex_cells);
    EXPECT_EQ(r->cells_by_verdict, one.cells_by_verdict);
    EXPECT_EQ(r->vertices_added, one.vertices_added);
  }
  EXPECT_TRUE(a == b);
  EXPECT_TRUE(a == c);
}

TEST(ConstrainTopology, IdenticalWithOneThreadOrMany) {
  const double h = 0.04;
  auto run = [&](int threads) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, threads);
    test::Soup s = test::merge(test::icosphere(4, 0.6, Vec3(-0.35, 0, 0)), test::icosphere(4, 0.6, Vec3(0.35, 0.02, 0.01)));
    SurfaceMesh m = s.mesh();
    const GridPtr phi = signed_distance(m, h);
    EventList ev;
    constrain_topology(m, *phi, {}, &ev);
    std::vector<Vec3> P;
    std::vector<std::array<Index, 3>> T;
    extract_triangles(m, P, T);
    return std::tuple(P, T, m.ids(), ev);
  };
  EXPECT_TRUE(run(1) == run(4));
}

// ConstrainTopology reads Θ's values only within a cell diagonal (√3 voxels) of its zero set, its sign
// elsewhere: a band of 1.75 voxels (the tracker's sdf_half_width) gives the same result, events and ids as
// one of 3, both against the next frame (splits, merges) and against M's own distance (self-intersections).
TEST(ConstrainTopology, SameResultWithABandJustBeyondTheCellDiagonal) {
  SyntheticParams sp;
  sp.kind = SyntheticKind::kMetaballs;
  sp.frames = 6;
  const SyntheticScene scene(sp);
  std::size_t complex = 0;
  for (int n = 1; n < sp.frames; ++n) {
    const SurfaceMesh next = to_surface_mesh(scene.frame_mesh(n + 1));
    for (bool self : {false, true}) {
      auto run = [&](double half_width) {
        SurfaceMesh m = to_surface_mesh(scene.frame_mesh(n));
        const GridPtr theta = signed_distance(self ? m : next, scene.voxel_size(), half_width, 0.25);
        EventList ev;
        const ConstrainReport r = constrain_topology(m, *theta, {}, &ev);
        complex += r.complex_cells;
        std::vector<Vec3> P;
        std::vector<std::array<Index, 3>> T;
        extract_triangles(m, P, T);
        return std::tuple(P, T, m.ids(), ev, r.complex_cells);
      };
      SCOPED_TRACE("frame " + std::to_string(n) + (self ? " against itself" : " against the next"));
      EXPECT_TRUE(run(1.75) == run(3.0));
    }
  }
  EXPECT_GT(complex, 0u);
}

// Θ need not be a distance: the tracker gives nodes of φ_S the value of φ_M (agree_near_surface), so a node at
// the band's edge can turn inside while its neighbours beyond the band stay inactive. The cells around it
// with an inactive minimum corner change sign too and must be examined: before they were, they passed for
// simple, the replacement next to them found no crossing of M on their lattice edges, and the complex region
// grew by a whole layer (resurfaced pcow, capture profile: ~30 000 cells replaced on the finer lattice
// instead of ~3 000).
TEST(ConstrainTopology, ExaminesSignChangesAtTheBandsEdge) {
  using namespace topology;
  SurfaceMesh m = test::icosphere(4).mesh();
  const double h = 0.05;
  GridPtr theta = signed_distance(m, h, 1.75);
  // An outside node near the band's edge whose neighbour below along x is beyond the band.
  openvdb::Coord node;
  bool found = false;
  auto acc = theta->getAccessor();
  for (auto it = theta->cbeginValueOn(); it && !found; ++it) {
    const openvdb::Coord c = it.getCoord();
    found = *it > 1.2 * h && !acc.isValueOn(c.offsetBy(-1, 0, 0)) && acc.isValueOn(c.offsetBy(1, 0, 0));
    if (found) node = c;
  }
  ASSERT_TRUE(found);
  acc.setValueOnly(node, float(-0.5 * h));  // a speck of Θ's inside, apart from the sphere

  const LatticeCut cut = cut_by_lattice(m, theta->transform());
  const CellIndex index = index_cells(cut, *theta);
  const std::vector<std::uint64_t> bad = complex_cells(m, cut, index, *theta);
  for (int d = 0; d < 8; ++d) {
    const std::uint64_t k = cell_key(node.offsetBy(-(d & 1), -((d >> 1) & 1), -((d >> 2) & 1)));
    EXPECT_TRUE(std::binary_search(index.cells.begin(), index.cells.end(), k)) << "cell " << d << " not examined";
    EXPECT_TRUE(std::binary_search(bad.begin(), bad.end(), k)) << "cell " << d << " not complex";
  }
  EventList ev;
  const ConstrainReport r = constrain_topology(m, *theta, {}, &ev);
  EXPECT_EQ(r.region_growth, 0);
  expect_sound(m);
  EXPECT_EQ(connected_components(m), 2u);
  expect_topology_of(m, *theta);
}

// Nodes within kSignTolerance of Θ's zero set take M's side only where that keeps Θ's topology
// (ConstrainParams::flips_keep_topology, on by default). Θ: two balls
// a twentieth of a voxel from a lattice node on either side of it; M: one ball across both. M's crossings
// put that node inside, which would bridge the balls and leave M one component; the flip is not a simple
// point of Θ's inside, so the node keeps Θ's sign and M splits.
TEST(ConstrainTopology, SignsTakenFromMKeepThetasTopology) {
  using namespace topology;
  const double h = 0.02, R = 20 * h, gap = 0.05 * h;
  GridPtr theta = unite(sphere(R, {-R - gap, 0, 0}, h), sphere(R, {R + gap, 0, 0}, h));
  const openvdb::Coord node(0, 0, 0);
  ASSERT_GT(theta->getConstAccessor().getValue(node), 0.f);
  ASSERT_LT(theta->getConstAccessor().getValue(node), float(kSignTolerance * h));
  SurfaceMesh m = test::icosphere(5, 1.2 * R).mesh();
  ASSERT_EQ(connected_components(m), 1u);
  {
    const LatticeCut cut = cut_by_lattice(m, theta->transform());
    EXPECT_FALSE(index_cells(cut, *theta).is_flipped(node));
    // Without the topology check (the tracker's first lattice) the node takes M's side.
    EXPECT_TRUE(index_cells(cut, *theta, false).is_flipped(node));
  }
  constrain_topology(m, *theta);
  expect_sound(m);
  EXPECT_EQ(connected_components(m), 2u);
  expect_topology_of(m, *theta);
}

TEST(ConstrainTopology, CountsComponentsOnlyWhenAsked) {
  SurfaceMesh m = test::icosphere(4, 0.5).mesh();
  const GridPtr two = unite(sphere(0.3, Vec3(-0.4, 0, 0), 0.05), sphere(0.3, Vec3(0.4, 0, 0), 0.05));
  ConstrainParams p;
  p.count_components = false;
  SurfaceMesh a = m.clone();
  const ConstrainReport r = constrain_topology(a, *two, p);
  EXPECT_EQ(r.components_before, 0);
  EXPECT_EQ(r.components_after, 0);
  EXPECT_EQ(connected_components(a), 2u);
  const ConstrainReport q = constrain_topology(m, *two);
  EXPECT_EQ(q.components_before, 1);
  EXPECT_EQ(q.components_after, 2);
}

TEST(ConstrainTopology, ThrowsOnBadInput) {
  SurfaceMesh m = test::icosphere(2).mesh();
  GridPtr theta = sphere(0.5, Vec3::Zero(), 0.05);
  m.position(Vertex(3)) = Vec3(std::nan(""), 0, 0);
  EXPECT_THROW(constrain_topology(m, *theta), InvalidInput);
  SurfaceMesh far = test::icosphere(2, 1.0, Vec3(1e6, 0, 0)).mesh();
  EXPECT_THROW(constrain_topology(far, *theta), InvalidInput);
  ConstrainParams p;
  p.max_region_growth = -1;
  SurfaceMesh ok = test::icosphere(2).mesh();
  EXPECT_THROW(constrain_topology(ok, *theta, p), InvalidInput);

}

// The smallest triangle area over the mean (slivers: a marching-cubes vertex next to a lattice corner).
double min_area_ratio(const SurfaceMesh& m) {
  double sum = 0, lo = std::numeric_limits<double>::infinity();
  for (Index i = 0; i < m.faces_size(); ++i) {
    if (m.is_deleted(Face(i))) continue;
    const double a = face_area(m, Face(i));
    sum += a;
    lo = std::min(lo, a);
  }
  return m.n_faces() ? lo / (sum / double(m.n_faces())) : 1.0;
}

// Every frame of `gen morph` and `gen metaballs` constrained to the next frame takes that frame's number of
// components and Euler characteristic, stays sound and has no near-zero-area triangle (§4.3 patches).
void check_sequence(SyntheticKind kind, int frames) {
  SyntheticParams sp;
  sp.kind = kind;
  sp.frames = frames;
  const SyntheticScene scene(sp);
  std::size_t changed = 0;
  for (int n = 1; n < frames; ++n) {
    SurfaceMesh m = to_surface_mesh(scene.frame_mesh(n));
    const SurfaceMesh next = to_surface_mesh(scene.frame_mesh(n + 1));
    const GridPtr phi = signed_distance(next, scene.voxel_size());
    const ConstrainReport r = constrain_topology(m, *phi);
    changed += r.complex_cells > 0;
    SCOPED_TRACE(std::string(synthetic_kind_name(kind)) + " frame " + std::to_string(n));
    EXPECT_NO_THROW(m.validate(true));
    EXPECT_EQ(connected_components(m), connected_components(next));
    EXPECT_EQ(euler_characteristic(m), euler_characteristic(next));
    EXPECT_EQ(test::count_self_intersections(m), 0u);
    // Slivers (#5: no triangle below 1e-6 of the mean area): the patch keeps its vertices kSnap off the
    // lattice nodes, M's vertices are pushed kSnap off the planes, tiny pieces of M are absorbed into the
    // patch, and the cells of any triangle below kMinTriangleArea join the region (replace.hpp). These frames
    // (M's vertices on Θ's own lattice lines, the hardest case for exact cutting) had triangles down to 1e-13
    // of the mean area two sessions ago, 1.5e-8 before absorb_sliver_triangles; now >= 4e-6.
    if (r.complex_cells > 0) {
      EXPECT_GE(min_area_ratio(m), 1e-6);
    }
  }
  EXPECT_GT(changed, 0u);
}

TEST(ConstrainTopology, MorphFramesTakeTheNextFramesTopology) { check_sequence(SyntheticKind::kMorph, 6); }
TEST(ConstrainTopology, MetaballsFramesTakeTheNextFramesTopology) { check_sequence(SyntheticKind::kMetaballs, 6); }

// Real data: a cow frame constrained to its own signed distance (the captured frames self-intersect:
// those become merges) and then to a later frame's takes that frame's topology and is left sound.
TEST(ConstrainTopology, RealSequenceFrames) {
  const std::filesystem::path dir = std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / "pcow";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << "no " << dir;
  SurfaceMesh m = to_surface_mesh(read_mesh(dir / "pcow.0001.ply"));
  const SurfaceMesh target = to_surface_mesh(read_mesh(dir / "pcow.0040.ply"));
  const double h = mean_edge_length(m);
  EXPECT_GT(test::count_self_intersections(m), 0u) << "the input self-intersects";
  const GridPtr phi_m = signed_distance(m, h);
  constrain_topology(m, *phi_m);
  expect_sound(m);
  const GridPtr phi_s = signed_distance(target, h);
  // Two of the target's small components (inside the head, where the capture crosses itself) are 0.34 voxel
  // apart, with lattice nodes between them within 0.03 voxel of φ_S's zero set: they take M's side where
  // that keeps φ_S's topology.
  const GridPtr decided = as_decided(m, *phi_s);
  constrain_topology(m, *phi_s);
  expect_sound(m);
  expect_topology_of(m, *decided);
}

}  // namespace
}  // namespace topotrack
