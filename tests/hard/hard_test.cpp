// Hard but valid input (issue #9, docs/robustness.md): a surface that vanishes and comes back, a component
// appearing from nothing, identical consecutive frames, a sheet thinner than a voxel, droplets below the
// voxel size, very large and very small coordinates, through the library Tracker API (Algorithm 1); and
// open surfaces through the frame loader (rejected by default, closed with close_holes).
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <fstream>
#include <set>

#include "engine/frame_loader.hpp"
#include "engine/tracker.hpp"
#include "io/error.hpp"
#include "io/mesh_reader.hpp"
#include "io/ply_writer.hpp"
#include "kernels/gen/implicit_grid.hpp"
#include "kernels/gen/shapes.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/raycast/target_surface.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "tests/support/test_meshes.hpp"

#include <openvdb/tools/Interpolation.h>

namespace topotrack {
namespace {

namespace fs = std::filesystem;

//! The marching-cubes surface of an implicit function (kernels/gen): incoherent from frame to frame, as
//! simulation output is.
SurfaceMesh implicit_frame(const ImplicitFunction& f, const BoundingBox& box, double voxel) {
  return to_surface_mesh(mesh_implicit(f, box, voxel));
}

SurfaceMesh sphere_frame(const Vec3& c, double r, double voxel) {
  const Vec3 e = Vec3::Constant(r + 3 * voxel);
  return implicit_frame([&](const Vec3& p) { return sdf_shapes::sphere(p, c, r); }, {c - e, c + e}, voxel);
}

std::set<VertexId> ids_of(const SurfaceMesh& m) {
  std::set<VertexId> s;
  for (Index i = 0; i < m.vertices_size(); ++i)
    if (!m.is_deleted(Vertex(i))) s.insert(m.id(Vertex(i)));
  return s;
}

double max_speed(const Tracker& t) {
  double v = 0;
  for (const auto& x : t.velocities()) v = std::max(v, x.norm());
  return v;
}

std::size_t count(const FrameReport& r, EventKind k) { return r.events_by_kind.at(std::size_t(k) - 1); }

// A frame with no surface at all (the liquid drained away): M is deleted by ConstrainTopology(M, φ_S) with
// one patch_delete event, stays empty, and a surface appearing later starts again with fresh ids.
TEST(Hard, SurfaceVanishesAndComesBack) {
  Tracker t;
  t.add_frame(sphere_frame(Vec3::Zero(), 0.5, 0.05));
  const auto first_ids = ids_of(t.mesh());
  const FrameReport& gone = t.add_frame(SurfaceMesh(), "empty");
  EXPECT_EQ(gone.vertices, 0u);
  EXPECT_EQ(gone.components, 0u);
  EXPECT_GE(count(gone, EventKind::PatchDelete), 1u);
  EXPECT_EQ(count(gone, EventKind::PatchCreate), 0u);
  const FrameReport& still = t.add_frame(SurfaceMesh(), "empty again");
  EXPECT_EQ(still.vertices, 0u);
  EXPECT_TRUE(t.events().empty());
  const FrameReport& back = t.add_frame(sphere_frame(Vec3(0.1, 0, 0), 0.4, 0.05), "back");
  EXPECT_EQ(back.components, 1u);
  EXPECT_EQ(back.euler, 2);
  EXPECT_GE(count(back, EventKind::PatchCreate), 1u);
  EXPECT_NO_THROW(t.mesh().validate(true));
  for (VertexId id : ids_of(t.mesh())) EXPECT_EQ(first_ids.count(id), 0u) << "id " << id << " reused";
}

// The first frame cannot be empty: there is no surface to derive L from and nothing to track.
TEST(Hard, EmptyFirstFrameIsRejected) {
  Tracker t;
  EXPECT_THROW(t.add_frame(SurfaceMesh(), "empty"), InvalidInput);
}

// A second body appearing far from the first: a patch is created for it (§4.3), the first keeps its ids.
TEST(Hard, ComponentAppearsFromNothing) {
  Tracker t;
  t.add_frame(sphere_frame(Vec3::Zero(), 0.5, 0.05));
  const auto before = ids_of(t.mesh());
  SurfaceMesh two = to_surface_mesh(mesh_implicit(
      [](const Vec3& p) {
        return std::min(sdf_shapes::sphere(p, Vec3::Zero(), 0.5), sdf_shapes::sphere(p, Vec3(1.5, 0, 0), 0.3));
      },
      {Vec3(-0.7, -0.7, -0.7), Vec3(2.0, 0.7, 0.7)}, 0.05));
  const FrameReport& r = t.add_frame(two, "two");
  EXPECT_EQ(r.components, 2u);
  EXPECT_GE(count(r, EventKind::PatchCreate), 1u);
  EXPECT_NO_THROW(t.mesh().validate(true));
  std::size_t kept = 0;
  for (VertexId id : ids_of(t.mesh())) kept += before.count(id);
  EXPECT_GT(kept, before.size() / 2);
}

// The same surface four times: the paper's ideal, no resampling at all and (almost) no motion: M stays the
// improved first frame, only alignment noise moves it (measured: < 0.006 L per frame).
TEST(Hard, IdenticalFramesKeepTheSurface) {
  Tracker t;
  const SurfaceMesh s = sphere_frame(Vec3(0.01, 0.02, 0.03), 0.5, 0.05);
  for (int i = 0; i < 4; ++i) {
    const FrameReport& r = t.add_frame(s);
    std::printf("identical %d: events %zu split %zu collapse %zu create %zu delete %zu speed %g L %g\n", i,
                t.events().size(), count(r, EventKind::EdgeSplit), count(r, EventKind::EdgeCollapse),
                count(r, EventKind::PatchCreate), count(r, EventKind::PatchDelete), max_speed(t), t.edge_length());
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.euler, 2);
    EXPECT_EQ(t.events().size(), 0u) << "frame " << i;
    EXPECT_LT(max_speed(t), 0.02 * t.edge_length());
  }
}

// A sheet thinner than a voxel.
TEST(Hard, SheetThinnerThanAVoxel) {
  TrackerParams p;
  p.edge_length = 0.05;
  Tracker t(p);
  auto slab = [](double half) {
    return [half](const Vec3& q) {
      return std::max({std::abs(q.x()) - 0.5, std::abs(q.y()) - 0.5, std::abs(q.z()) - half});
    };
  };
  const BoundingBox box{Vec3(-0.6, -0.6, -0.1), Vec3(0.6, 0.6, 0.1)};
  for (int i = 0; i < 3; ++i) {
    const FrameReport& r = t.add_frame(implicit_frame(slab(0.008), box, 0.004));
    std::printf("sheet %d: verts %zu comps %zu create %zu delete %zu failures %zu\n", i, r.vertices, r.components,
                count(r, EventKind::PatchCreate), count(r, EventKind::PatchDelete), r.topology_failures);
  }
  EXPECT_NO_THROW(t.mesh().validate(true));
}

// A droplet smaller than a voxel next to a big body.
TEST(Hard, DropletBelowTheVoxelSize) {
  test::Soup s = test::merge(test::icosphere(3, 0.5), test::icosphere(1, 0.015, Vec3(1.0, 0, 0)));
  const SurfaceMesh frame = s.mesh();
  TrackerParams p;
  p.edge_length = 0.05;
  Tracker t(p);
  for (int i = 0; i < 3; ++i) {
    const FrameReport& r = t.add_frame(frame);
    std::printf("droplet %d: verts %zu comps %zu create %zu delete %zu failures %zu\n", i, r.vertices, r.components,
                count(r, EventKind::PatchCreate), count(r, EventKind::PatchDelete), r.topology_failures);
  }
  EXPECT_NO_THROW(t.mesh().validate(true));
}

void scaled_run(double scale, const Vec3& offset) {
  Tracker t;
  for (int i = 0; i < 3; ++i) {
    test::Soup s = test::icosphere(3, scale);
    for (auto& q : s.positions) q += offset + Vec3(0.05 * scale * i, 0, 0);
    const FrameReport& r = t.add_frame(s.mesh());
    std::printf("scale %g offset %g %d: verts %zu comps %zu L %g voxel %g\n", scale, offset.x(), i, r.vertices,
                r.components, t.edge_length(), t.voxel_size());
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.euler, 2);
  }
}

TEST(Hard, VeryLargeScale) { scaled_run(1e6, Vec3::Zero()); }
// Scale 1e-6: L ~ 1.5e-7, and OpenVDB refuses a voxel that small ("Non-zero scale values required"): the
// first frame is taken, the second is rejected with InvalidInput (docs/robustness.md: rescale such data).
TEST(Hard, VerySmallScaleIsRejectedCleanly) { EXPECT_THROW(scaled_run(1e-6, Vec3::Zero()), InvalidInput); }
// A unit sphere 1e6 away from the origin: more than 2^20 voxels out, beyond the lattice keys of §4.3's grids:
// rejected with InvalidInput at the second frame (docs/robustness.md: translate such data).
TEST(Hard, VeryLargeOffsetIsRejectedCleanly) { EXPECT_THROW(scaled_run(1.0, Vec3(1e6, 1e6, 1e6)), InvalidInput); }

// ---- Open surfaces (the paper's limitation): the frame loader ----------------------------------------------

const fs::path kOpen = fs::path(TOPOTRACK_SOURCE_DIR) / "tests/data/sequences/open_holes";

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(no InvalidInput)";
}

TEST(OpenSurface, RejectedNamingTheFileAndItsHoles) {
  const std::string m = message_of([] { load_frame(kOpen / "sphere.0002.ply"); });
  EXPECT_NE(m.find("sphere.0002.ply: the surface is open: "), std::string::npos) << m;
  EXPECT_NE(m.find(" boundary edges in 2 holes (largest: "), std::string::npos) << m;
  EXPECT_NE(m.find("--close-holes"), std::string::npos) << m;
  const std::string one = message_of([] { load_frame(fs::path(TOPOTRACK_SOURCE_DIR) / "tests/data/bad/open_surface.ply"); });
  EXPECT_NE(one.find("open_surface.ply: the surface is open: 3 boundary edges in 1 hole"), std::string::npos) << one;
}

TEST(OpenSurface, BoundaryLoops) {
  MeshData closed = to_mesh_data(test::icosphere(1).mesh(), false);
  EXPECT_TRUE(boundary_loops(closed).empty());
  MeshData open = closed;
  open.triangles.erase(open.triangles.begin());                         // one hole of 3 edges
  open.triangles.erase(open.triangles.begin() + 20, open.triangles.begin() + 21);  // and another
  const auto loops = boundary_loops(open);
  ASSERT_EQ(loops.size(), 2u);
  EXPECT_EQ(loops[0].size(), 3u);
  EXPECT_EQ(loops[1].size(), 3u);
}

//! Largest |φ| of `of` at the vertices of `m`: how far m is from the surface `of` (trilinear in the band).
double max_distance(const SurfaceMesh& m, const SurfaceMesh& of, double voxel) {
  const auto grid = signed_distance(of, voxel, 4.0);
  double d = 0;
  for (Index i = 0; i < m.vertices_size(); ++i) {
    if (m.is_deleted(Vertex(i))) continue;
    const Vec3 p = m.position(Vertex(i)) / voxel;
    d = std::max(d, double(std::abs(openvdb::tools::BoxSampler::sample(grid->tree(), openvdb::Vec3R(p.x(), p.y(), p.z())))));
  }
  return d;
}

TEST(OpenSurface, CloseHolesMakesAClosedSphere) {
  FrameLoadParams p;
  p.close_holes = true;
  p.voxel_size = 0.05;
  p.max_hole_voxels = 16;  // the holes are about 0.55 across (bounding-box diagonal)
  const LoadedFrame f = load_frame(kOpen / "sphere.0002.ply", p);
  EXPECT_NO_THROW(f.mesh.validate(true));
  EXPECT_EQ(connected_components(f.mesh), 1);
  EXPECT_EQ(euler_characteristic(f.mesh), 2);
  EXPECT_EQ(f.report.holes_closed, 2u);
  EXPECT_GT(f.report.hole_boundary_edges, 20u);
  EXPECT_GT(f.report.largest_hole, 0.2);
  EXPECT_LT(f.report.largest_hole, 0.6);
  EXPECT_EQ(f.report.voxel_size, 0.05);
  ASSERT_EQ(f.report.warnings.size(), 1u);
  EXPECT_NE(f.report.warnings[0].find("closed 2 holes"), std::string::npos) << f.report.warnings[0];
  // On the sphere (centre (0.05, 0, 0), radius 0.5) within half a voxel, caps included.
  const SurfaceMesh sphere = test::icosphere(5, 0.5, Vec3(0.05, 0, 0)).mesh();
  EXPECT_LT(max_distance(f.mesh, sphere, 0.025), 0.025);
  // A closed frame is left as it is.
  const LoadedFrame c = load_frame(fs::path(TOPOTRACK_SOURCE_DIR) / "tests/data/sequences/gap/g.0001.ply", p);
  EXPECT_EQ(c.report.holes_closed, 0u);
  EXPECT_TRUE(c.report.warnings.empty());
  EXPECT_EQ(c.mesh.n_vertices(), read_mesh(fs::path(TOPOTRACK_SOURCE_DIR) / "tests/data/sequences/gap/g.0001.ply").vertex_count());
}

TEST(OpenSurface, HoleLargerThanTheLimitIsNotClosed) {
  FrameLoadParams p;
  p.close_holes = true;
  p.voxel_size = 0.05;
  p.max_hole_voxels = 3;  // the hole is about 0.55 across: 11 voxels
  const std::string m = message_of([&] { load_frame(kOpen / "sphere.0001.ply", p); });
  EXPECT_NE(m.find("sphere.0001.ply: a hole of "), std::string::npos) << m;
  EXPECT_NE(m.find("larger than --close-holes closes (3 voxels of 0.05)"), std::string::npos) << m;
}

// A real frame (elephant, 42k vertices) with triangles cut out around two vertices: closed again, without
// specks. Before the winding-number sign and the thickening of thin parts (kernels/sdf/close_holes.cpp) it had
// 267 components: the elephant's ears are sheets far thinner than a voxel (kernels/sdf/thicken.hpp).
// Expected values, measured and explained:
//  - 2 components, not the original's 1: the cut around vertex 100 severs the trunk's tip (the cut soup
//    itself has 2 components), and the tip is closed as a piece of its own (45 vertices);
//  - the genus is not 0: the ears pass through the head (656 edge-triangle crossings in six places) and the
//    solid the surface bounds (winding number >= 1/2), which a level set represents, has handles there;
//  - KNOWN PROBLEM: one spot near (0, 0.72, 0.65) is 2.2 L from the source, with or without the cut (cause
//    not yet found; thickening moves the surface at most 0.875 L); everything else is within a voxel.
TEST(OpenSurface, RealFrameWithTrianglesRemoved) {
  const fs::path path = fs::path(TOPOTRACK_SHARED_DIR) / "data/elephant/elephant.0001.ply";
  if (!fs::exists(path)) GTEST_SKIP() << path << " not present";
  const MeshData full = read_mesh(path);
  const SurfaceMesh original = to_surface_mesh(full);
  const double L = mean_edge_length(original);
  MeshData cut = full;
  std::erase_if(cut.triangles, [&](const std::array<std::int64_t, 3>& t) {
    for (std::int64_t centre : {std::int64_t(100), std::int64_t(30000)}) {
      const auto& c = full.positions[std::size_t(centre)];
      const auto& q = full.positions[std::size_t(t[0])];
      if (std::hypot(q[0] - c[0], q[1] - c[1], q[2] - c[2]) < 2.5 * L) return true;
    }
    return false;
  });
  ASSERT_LT(cut.triangles.size(), full.triangles.size());
  FrameLoadParams p;
  p.close_holes = true;
  p.voxel_size = L;
  p.max_hole_voxels = 16;
  FrameLoadReport r;
  const SurfaceMesh closed = close_holes(cut, p, "elephant cut", &r);
  EXPECT_GE(r.holes_closed, 2u);  // the ragged cuts leave pinched loops: 4 here
  EXPECT_NO_THROW(closed.validate(true));
  std::vector<Index> labels;
  ASSERT_EQ(connected_components(closed, &labels), 2u);
  std::vector<std::size_t> sizes(2, 0);
  for (Index v = 0; v < closed.vertices_size(); ++v)
    if (!closed.is_deleted(Vertex(v))) ++sizes[labels[v]];
  EXPECT_GT(std::min(sizes[0], sizes[1]), 30u);  // the trunk's tip, not a speck
  // Distances to the source surface, exact (closest points): all but a handful within a voxel.
  const TargetSurface source = TargetSurface::from_mesh(original);
  std::size_t far = 0;
  double largest = 0;
  for (Index v = 0; v < closed.vertices_size(); ++v) {
    if (closed.is_deleted(Vertex(v))) continue;
    const double d = source.closest_point(closed.position(Vertex(v))).distance;
    far += d > L;
    largest = std::max(largest, d);
  }
  std::printf("closed: %zu vertices, %zu more than L from the source, largest %.3f L\n", closed.n_vertices(), far,
              largest / L);
  // Before the winding-number sign beyond the band (exact_sign.cpp): 11 vertices over 1.5 L, largest 2.2 L.
  EXPECT_LT(far, closed.n_vertices() / 1000);
  EXPECT_LT(largest, 1.25 * L);
}

}  // namespace
}  // namespace topotrack
