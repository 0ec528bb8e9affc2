// Algorithm 1 end to end on small generated sequences: coherence (ids follow the surface), topology
// following the input, determinism across thread counts, and bit-identical resume from a checkpoint.
#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/task_group.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <unordered_map>

#include "engine/checkpoint.hpp"
#include "engine/frame_loader.hpp"
#include "engine/tracker.hpp"
#include "io/error.hpp"
#include "io/event_file.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack {
namespace {

constexpr double kVoxel = 0.05;

//! An incoherent input frame: the marching-cubes surface of the union of spheres (centre, radius), so the
//! connectivity differs from frame to frame as it does for simulation output.
SurfaceMesh spheres_frame(const std::vector<std::pair<Vec3, double>>& spheres, double voxel = kVoxel) {
  test::Soup all;
  for (const auto& [c, r] : spheres) all = test::merge(all, test::icosphere(4, r, c));
  const auto grid = signed_distance(all.positions, all.triangles, voxel, 3.0);
  return to_surface_mesh(marching_cubes(*grid));
}

//! A peanut (two overlapping spheres of different size) translated by `t`.
SurfaceMesh peanut(const Vec3& t) { return spheres_frame({{Vec3(-0.25, 0, 0) + t, 0.5}, {Vec3(0.35, 0.1, 0) + t, 0.35}}); }

struct TrackRun {
  std::vector<std::string> meshes;  // encoded tracked meshes per frame (positions, ids, triangles)
  std::vector<std::string> events;  // encoded event lists per frame
};

std::string encode_mesh(const SurfaceMesh& m) {
  const MeshData d = to_mesh_data(m, false);
  std::string s;
  for (const auto& p : d.positions) s.append(reinterpret_cast<const char*>(p.data()), sizeof(p));
  for (const auto& t : d.triangles) s.append(reinterpret_cast<const char*>(t.data()), sizeof(t));
  for (auto id : *d.ids) s.append(reinterpret_cast<const char*>(&id), sizeof(id));
  return s;
}

TrackRun track(const std::vector<SurfaceMesh>& frames, std::size_t first = 0, Tracker* tracker_in = nullptr) {
  Tracker own;
  Tracker& tracker = tracker_in ? *tracker_in : own;
  TrackRun run;
  for (std::size_t i = first; i < frames.size(); ++i) {
    tracker.add_frame(frames[i]);
    run.meshes.push_back(encode_mesh(tracker.mesh()));
    run.events.push_back(encode_events(tracker.events()));
  }
  return run;
}

std::vector<SurfaceMesh> translating_peanut(int n, const Vec3& step) {
  std::vector<SurfaceMesh> frames;
  for (int i = 0; i < n; ++i) frames.push_back(peanut(double(i) * step));
  return frames;
}

TEST(Tracker, FollowsATranslationCoherently) {
  const Vec3 step(0.04, 0.01, 0);
  const auto frames = translating_peanut(4, step);
  Tracker tracker;
  tracker.add_frame(frames[0]);
  std::unordered_map<VertexId, Vec3> start;
  for (Index i = 0; i < tracker.mesh().vertices_size(); ++i) start[tracker.mesh().id(Vertex(i))] = tracker.mesh().position(Vertex(i));
  EXPECT_TRUE(tracker.events().empty());
  for (std::size_t f = 1; f < frames.size(); ++f) {
    const FrameReport& r = tracker.add_frame(frames[f]);
    EXPECT_EQ(r.components, 1u);
    EXPECT_EQ(r.euler, 2);
    EXPECT_NO_THROW(tracker.mesh().validate(true));
  }
  // Points that were never resampled moved with the translation: ids follow the surface.
  const Vec3 total = 3.0 * step;
  std::size_t kept = 0;
  double err = 0;
  for (Index i = 0; i < tracker.mesh().vertices_size(); ++i) {
    auto it = start.find(tracker.mesh().id(Vertex(i)));
    if (it == start.end()) continue;
    ++kept;
    err += (tracker.mesh().position(Vertex(i)) - (it->second + total)).norm();
  }
  ASSERT_GT(kept, start.size() * 8 / 10) << "most vertices survive a rigid translation";
  const double diag = bounding_box(tracker.mesh()).diagonal();
  EXPECT_LT(err / double(kept), 0.01 * diag) << "mean drift against the true translation";
  // Velocities are the per-frame motion.
  Vec3 mean_v = Vec3::Zero();
  for (const Vec3& v : tracker.velocities()) mean_v += v;
  mean_v /= double(tracker.velocities().size());
  EXPECT_LT((mean_v - step).norm(), 0.2 * step.norm());
}

// FineParams::relax in the tracker (off by default): each frame's M slides along S_n towards its own shape before
// the frame; a translation keeps the shape, so the tracking stays as coherent.
TEST(Tracker, RelaxesOnTheTargetWhenAsked) {
  const Vec3 step(0.04, 0.01, 0);
  const auto frames = translating_peanut(3, step);
  TrackerParams params;
  params.fine_params.relax.iterations = 3;
  Tracker tracker(params);
  std::unordered_map<VertexId, Vec3> start;
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const FrameReport& r = tracker.add_frame(frames[f]);
    EXPECT_EQ(r.relax_iterations, f == 0 ? 0 : 3);
    if (f == 0)
      for (Index i = 0; i < tracker.mesh().vertices_size(); ++i) start[tracker.mesh().id(Vertex(i))] = tracker.mesh().position(Vertex(i));
  }
  EXPECT_NO_THROW(tracker.mesh().validate(true));
  // A translation keeps the shape: the points that were never resampled moved with it, as without the relaxation.
  const Vec3 total = 2.0 * step;
  std::size_t kept = 0;
  double err = 0;
  for (Index i = 0; i < tracker.mesh().vertices_size(); ++i) {
    const auto it = start.find(tracker.mesh().id(Vertex(i)));
    if (it == start.end()) continue;
    ++kept;
    err += (tracker.mesh().position(Vertex(i)) - (it->second + total)).norm();
  }
  ASSERT_GT(kept, start.size() * 8 / 10);
  EXPECT_LT(err / double(kept), 0.01 * bounding_box(tracker.mesh()).diagonal());
  EXPECT_EQ(Tracker().add_frame(frames[0]).relax_iterations, 0);  // off by default
}

TEST(Tracker, TakesTheTopologyOfTheInput) {
  // A peanut whose neck pinches off: the tracked mesh must split into two components and stay closed.
  std::vector<SurfaceMesh> frames;
  for (int i = 0; i < 5; ++i) {
    const double gap = 0.1 * i;
    frames.push_back(spheres_frame({{Vec3(-0.4 - gap, 0, 0), 0.45}, {Vec3(0.4 + gap, 0, 0), 0.45}}));
  }
  Tracker tracker;
  std::size_t last_components = 0, target_cells = 0, target_reasons = 0;
  for (const auto& f : frames) {
    const std::size_t want = connected_components(f);
    last_components = tracker.add_frame(f).components;
    EXPECT_EQ(last_components, want);
    EXPECT_EQ(tracker.report().euler, euler_characteristic(f));
    EXPECT_NO_THROW(tracker.mesh().validate(true));
    // The report says why cells were complex: verdict counts, at most the cells replaced.
    const FrameReport& r = tracker.report();
    std::size_t self = 0, target = 0;
    for (int k = 1; k < topology::kVerdictKinds; ++k) {
      self += r.complex_reasons_self[k];
      target += r.complex_reasons_target[k];
    }
    EXPECT_LE(self, r.complex_cells_self);
    EXPECT_LE(target, r.complex_cells_target);
    EXPECT_EQ(self == 0, r.complex_cells_self == 0);
    EXPECT_EQ(target == 0, r.complex_cells_target == 0);
    target_cells += r.complex_cells_target;
    target_reasons += target;
  }
  EXPECT_EQ(last_components, 2u);
  EXPECT_GT(target_reasons, 0u) << "the pinch-off is resampled against φ_S";
  EXPECT_GE(target_cells, target_reasons);
}

TEST(Tracker, SameOutputWithOneOrTwoThreads) {
  const auto frames = translating_peanut(3, Vec3(0.05, 0, 0.02));
  TrackRun one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = track(frames);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = track(frames);
  }
  ASSERT_EQ(one.meshes.size(), two.meshes.size());
  for (std::size_t i = 0; i < one.meshes.size(); ++i) {
    EXPECT_EQ(one.meshes[i], two.meshes[i]) << "frame " << i;
    EXPECT_EQ(one.events[i], two.events[i]) << "frame " << i;
  }
}

TEST(Tracker, ResumeFromCheckpointIsBitIdentical) {
  const auto frames = translating_peanut(4, Vec3(0.05, -0.02, 0.01));
  const TrackRun straight = track(frames);
  // Interrupted after frame 2: write a checkpoint, read it back into a fresh tracker, continue.
  Tracker first;
  first.add_frame(frames[0]);
  first.add_frame(frames[1]);
  const auto path = std::filesystem::temp_directory_path() / "topotrack_tracker_test.checkpoint";
  write_checkpoint(path, {2, 1, first.edge_length(), first.voxel_size(), first.mesh().clone()});
  Checkpoint c = read_checkpoint(path);
  std::filesystem::remove(path);
  Tracker resumed;
  resumed.restore(std::move(c.mesh), 2, c.target_edge_length, c.voxel_size);
  const TrackRun rest = track(frames, 2, &resumed);
  ASSERT_EQ(rest.meshes.size(), 2u);
  EXPECT_EQ(rest.meshes[0], straight.meshes[2]);
  EXPECT_EQ(rest.events[0], straight.events[2]);
  EXPECT_EQ(rest.meshes[1], straight.meshes[3]);
  EXPECT_EQ(rest.events[1], straight.events[3]);
}

// A checkpoint of version 1 (before the lattice's origin was stored) is still read, with origin 0.
TEST(Tracker, CheckpointOfVersionOneIsReadWithOriginZero) {
  Tracker t;
  t.add_frame(peanut(Vec3::Zero()));
  const auto path = std::filesystem::temp_directory_path() / "topotrack_tracker_v1.checkpoint";
  write_checkpoint(path, {1, 0, t.edge_length(), t.voxel_size(), t.mesh().clone(), Vec3(0.25, -0.5, 1.0)});
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(bytes.size(), 76u);
  // Version 2 -> 1: drop the 24 bytes of the origin after the voxel size, set the version, hash again.
  const std::uint32_t v1 = 1;
  std::memcpy(&bytes[8], &v1, 4);
  bytes.erase(44, 24);
  bytes.resize(bytes.size() - 8);
  std::uint64_t h = 1469598103934665603ull;  // FNV-1a, as docs/formats.md
  for (const char c : bytes) h = (h ^ std::uint8_t(c)) * 1099511628211ull;
  bytes.append(reinterpret_cast<const char*>(&h), 8);
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
  }
  const Checkpoint c = read_checkpoint(path);
  std::filesystem::remove(path);
  EXPECT_EQ(c.lattice_origin, Vec3::Zero());
  EXPECT_EQ(c.voxel_size, t.voxel_size());
  EXPECT_EQ(encode_mesh(c.mesh), encode_mesh(t.mesh()));
}

//! The pipelined use of the API (what `track` does): frame n+1 prepared in a task while frame n is tracked.
TrackRun track_pipelined(const std::vector<SurfaceMesh>& frames) {
  Tracker tracker;
  TrackRun run;
  PreparedFrame next = tracker.prepare(frames[0].clone());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    PreparedFrame cur = std::move(next);
    tbb::task_group ahead;
    // Before the first frame the voxel size is not known: prepare then only checks the surface.
    const bool overlap = tracker.frames() > 0 && i + 1 < frames.size();
    if (overlap) ahead.run([&] { next = tracker.prepare(frames[i + 1].clone()); });
    tracker.add_frame(std::move(cur));
    ahead.wait();
    if (!overlap && i + 1 < frames.size()) next = tracker.prepare(frames[i + 1].clone());
    run.meshes.push_back(encode_mesh(tracker.mesh()));
    run.events.push_back(encode_events(tracker.events()));
  }
  return run;
}

TEST(Tracker, PreparedAheadGivesTheSameOutputWithOneOrTwoThreads) {
  const auto frames = translating_peanut(4, Vec3(0.05, 0.01, -0.02));
  TrackRun plain, one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    plain = track(frames);
    one = track_pipelined(frames);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = track_pipelined(frames);
  }
  ASSERT_EQ(plain.meshes.size(), frames.size());
  ASSERT_EQ(one.meshes.size(), frames.size());
  ASSERT_EQ(two.meshes.size(), frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(one.meshes[i], plain.meshes[i]) << "frame " << i;
    EXPECT_EQ(one.events[i], plain.events[i]) << "frame " << i;
    EXPECT_EQ(two.meshes[i], plain.meshes[i]) << "frame " << i;
    EXPECT_EQ(two.events[i], plain.events[i]) << "frame " << i;
  }
}

TEST(Tracker, PrepareComputesTheTargetWorkOnceTheVoxelSizeIsKnown) {
  const auto frames = translating_peanut(2, Vec3(0.03, 0, 0));
  Tracker tracker;
  const PreparedFrame early = tracker.prepare(frames[1].clone(), "early");
  EXPECT_FALSE(early.phi) << "no voxel size before the first frame";
  EXPECT_FALSE(early.target);
  tracker.add_frame(frames[0]);
  PreparedFrame p = tracker.prepare(frames[1].clone(), "second");
  ASSERT_TRUE(p.phi);
  ASSERT_TRUE(p.target);
  EXPECT_EQ(p.voxel_size, tracker.voxel_size());
  EXPECT_GT(p.seconds.signed_distance, 0);
  EXPECT_GE(p.seconds.prepare, p.seconds.signed_distance);
  const double phi_s_seconds = p.seconds.signed_distance;
  const FrameReport& r = tracker.add_frame(std::move(p));
  EXPECT_GE(r.seconds.signed_distance, phi_s_seconds) << "φ_S is counted in its frame";
  EXPECT_GT(r.seconds.prepare, 0);
  EXPECT_GE(r.seconds.total, r.seconds.prepare);
}

TEST(Tracker, PrepareRejectsWhatAddFrameRejects) {
  Tracker tracker;
  try {
    (void)tracker.prepare(test::open_box().mesh(), "box.ply");
    ADD_FAILURE() << "an open surface was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("box.ply: not a closed 2-manifold"), std::string::npos) << e.what();
  }
  PreparedFrame empty = tracker.prepare(SurfaceMesh(), "nothing");
  EXPECT_THROW(tracker.add_frame(std::move(empty)), InvalidInput);
}

TEST(Tracker, AcceptsLevelSetFrames) {
  test::Soup s = test::icosphere(4, 0.5);
  Tracker tracker;
  for (int i = 0; i < 2; ++i) {
    for (auto& p : s.positions) p.x() += 0.03;
    const auto grid = signed_distance(s.positions, s.triangles, kVoxel, 3.0);
    tracker.add_frame(*grid, "sphere.vdb");
    EXPECT_NO_THROW(tracker.mesh().validate(true));
  }
  EXPECT_EQ(tracker.report().components, 1u);
}

// A level set on another lattice than the tracker's (here: its voxel size, but a translation, as a simulation
// domain's corner gives) is not φ_S: φ_M and φ_S are combined node for node. Its zero set is then tracked as a
// mesh frame would be, bit for bit.
TEST(Tracker, LevelSetFramesOnAnotherLatticeAreTrackedThroughTheirSurface) {
  const test::Soup s = test::icosphere(4, 0.5);
  TrackerParams p;
  p.voxel_size = kVoxel;
  Tracker from_grids(p), from_meshes(p);
  for (int i = 0; i < 3; ++i) {
    test::Soup moved = s;
    for (auto& q : moved.positions) q += Vec3(0.03 * i, 0.01 * i, 0);
    SignedDistanceParams sp;
    sp.voxel_size = kVoxel;
    sp.origin = kVoxel * Vec3(0.4, 0.1, -0.3);
    const auto grid = signed_distance(moved.positions, moved.triangles, sp);
    ASSERT_FALSE(is_lattice(grid->transform(), kVoxel, Vec3::Zero()));
    from_grids.add_frame(*grid, "sphere.vdb");
    from_meshes.add_frame(to_surface_mesh(marching_cubes(*grid)), "sphere.ply");
    EXPECT_TRUE(encode_mesh(from_grids.mesh()) == encode_mesh(from_meshes.mesh())) << "frame " << i;
    EXPECT_TRUE(encode_events(from_grids.events()) == encode_events(from_meshes.events())) << "frame " << i;
  }
}

// .vdb frames (engine/frame_loader.hpp): the first level set of the file (else its first float grid), with its
// transform; a grid with non-cubic voxels or a file without a float grid is rejected, naming the file.
TEST(Tracker, ReadsLevelSetFiles) {
  const test::Soup s = test::icosphere(3, 0.5);
  SignedDistanceParams sp;
  sp.voxel_size = kVoxel;
  sp.origin = kVoxel * Vec3(0.4, 0.1, -0.3);
  const openvdb::FloatGrid::Ptr level_set = signed_distance(s.positions, s.triangles, sp);
  const auto dir = std::filesystem::temp_directory_path() / "topotrack_tracker_vdb_test";
  std::filesystem::create_directories(dir);
  const auto write = [&](const char* name, openvdb::GridPtrVec grids) {
    openvdb::io::File(dir.string() + "/" + name).write(grids);
    return dir / name;
  };
  openvdb::FloatGrid::Ptr fog = openvdb::FloatGrid::create(0.0f);
  fog->setName("density");
  fog->setGridClass(openvdb::GRID_FOG_VOLUME);
  level_set->setName("surface");
  const auto both = write("both.vdb", {fog, level_set});
  const openvdb::FloatGrid::Ptr read = read_level_set(both);
  EXPECT_EQ(read->getName(), "surface");
  EXPECT_TRUE(is_lattice(read->transform(), kVoxel, sp.origin));
  EXPECT_EQ(read->activeVoxelCount(), level_set->activeVoxelCount());
  const LoadedFrame frame = load_frame(both);
  ASSERT_TRUE(frame.grid);
  Tracker tracker;
  tracker.add_frame(*frame.grid, both.string());
  EXPECT_EQ(tracker.report().components, 1u);

  openvdb::FloatGrid::Ptr stretched = level_set->deepCopy();
  auto xform = voxel_transform(kVoxel);
  xform->preScale(openvdb::Vec3d(1, 1, 2));
  stretched->setTransform(xform);
  const auto bad = write("stretched.vdb", {fog, stretched});
  try {
    read_level_set(bad);
    ADD_FAILURE() << "a level set with non-cubic voxels was read";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("stretched.vdb: grid 'surface' has non-uniform voxels"), std::string::npos)
        << e.what();
  }
  openvdb::Vec3SGrid::Ptr velocity = openvdb::Vec3SGrid::create();
  const auto none = write("velocity.vdb", {velocity});
  try {
    read_level_set(none);
    ADD_FAILURE() << "a file without a float grid was read";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("velocity.vdb: no float grid"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

//! Two spheres of radius 0.45 on the x axis with a gap between x = lo and x = hi, the input sampled finely
//! enough (voxel 0.01) to keep the gap open, moving by `t` in y: two components.
SurfaceMesh spheres_with_gap(double lo, double hi, double t) {
  return spheres_frame({{Vec3(lo - 0.45, t, 0), 0.45}, {Vec3(hi + 0.45, t, 0), 0.45}}, 0.01);
}

//! A tracker whose lattice is 0.1 (L 0.05, voxels 2 L): nodes at multiples of 0.1 (and 0.05, 0.025 when
//! halved), so a gap is seen by a lattice exactly when a node lies in it.
TrackerParams coarse_lattice(int refinements) {
  TrackerParams p;
  p.edge_length = 0.05;
  p.voxel_size_factor = 2.0;
  p.topology_refinements = refinements;
  return p;
}

TEST(Tracker, ExtractionGridFoundOrAWarning) {
  EXPECT_EQ(extraction_grid_voxel(0.01, 0.02), 0.005);
  EXPECT_EQ(extraction_grid_voxel(0.01, 0.03), 0.01);  // half the spacing would be finer than 0.03 / 4
  EXPECT_EQ(extraction_grid_voxel(0.01, 0.04), 0.01);
  EXPECT_FALSE(extraction_grid_voxel(0.01, 0.05));
  const SurfaceMesh grid_frame = spheres_with_gap(0.02, 0.08, 0);  // marching cubes on a grid of 0.01
  const auto voxel_for = [&](double edge_length, std::size_t want_warnings) {
    TrackerParams p;
    p.edge_length = edge_length;
    p.extraction_grid = true;
    Tracker tracker(p);
    const FrameReport& r = tracker.add_frame(grid_frame);
    EXPECT_EQ(r.warnings.size(), want_warnings) << "edge length " << edge_length;
    for (const std::string& w : r.warnings) EXPECT_NE(w.find("tracker.extraction_grid"), std::string::npos) << w;
    return tracker.voxel_size();
  };
  EXPECT_NEAR(voxel_for(0.01, 0), 0.005, 1e-9);  // the grid at half its spacing
  EXPECT_NEAR(voxel_for(0.03, 0), 0.01, 1e-9);   // at its spacing
  // A fine extraction tracked at a far larger edge length: the profile's lattice, and a warning that says why.
  EXPECT_DOUBLE_EQ(voxel_for(0.05, 1), 0.05);
  TrackerParams p = coarse_lattice(0);  // voxels of 0.1 without the grid
  p.extraction_grid = true;
  {  // An icosphere's own triangles lie on no grid: a warning, and voxel_size_factor × L.
    Tracker tracker(p);
    const FrameReport& r = tracker.add_frame(test::icosphere(4, 0.5).mesh());
    ASSERT_EQ(r.warnings.size(), 1u);
    EXPECT_NE(r.warnings[0].find("tracker.extraction_grid"), std::string::npos) << r.warnings[0];
    EXPECT_NE(r.warnings[0].find("do not lie on the edges"), std::string::npos) << r.warnings[0];
    EXPECT_DOUBLE_EQ(tracker.voxel_size(), 0.1);
  }
  p.voxel_size = 0.07;  // tracker.voxel_size comes first
  Tracker fixed(p);
  EXPECT_TRUE(fixed.add_frame(spheres_with_gap(0.02, 0.08, 0)).warnings.empty());
  EXPECT_DOUBLE_EQ(fixed.voxel_size(), 0.07);
}

//! Two spheres of radius 0.2 whose gap [lo, hi] along x lies across the grid node x = origin.x(), extracted by
//! marching cubes on the grid of `voxel` through `origin` (a simulation domain's corner), moved by t along y.
SurfaceMesh spheres_on_grid(double lo, double hi, double t, double voxel, const Vec3& origin) {
  test::Soup all = test::merge(test::icosphere(4, 0.2, Vec3(lo - 0.2, t, 0)), test::icosphere(4, 0.2, Vec3(hi + 0.2, t, 0)));
  SignedDistanceParams p;
  p.voxel_size = voxel;
  p.origin = origin;
  return to_surface_mesh(marching_cubes(*signed_distance(all.positions, all.triangles, p)));
}

// A grid through another origin (tracker.extraction_grid finds it): the lattice runs through the grid's nodes,
// so a gap 0.003 wide around the node x = 0.0025, which the input's marching cubes saw, is seen by the tracker
// too. The same lattice through 0 has no node in the gap, and ConstrainTopology(M, φ_M) merges the spheres.
// A run resumed from a checkpoint (which keeps the origin) continues bit for bit.
TEST(Tracker, ExtractionGridThroughAnotherOrigin) {
  const Vec3 origin(0.0025, 0.0013, -0.0041);
  std::vector<SurfaceMesh> frames;
  for (int i = 0; i < 3; ++i) frames.push_back(spheres_on_grid(0.001, 0.004, 0.002 * i, 0.01, origin));
  for (const auto& f : frames) ASSERT_EQ(connected_components(f), 2) << "the input's extraction sees the gap";
  TrackerParams p;
  p.edge_length = 0.01;
  p.extraction_grid = true;
  Tracker tracker(p);
  EXPECT_TRUE(tracker.add_frame(frames[0]).warnings.empty());
  EXPECT_NEAR(tracker.voxel_size(), 0.005, 1e-9);
  for (int a = 0; a < 3; ++a) EXPECT_NEAR(tracker.lattice_origin()[a], origin[a], 1e-6) << a;
  // Interrupted after frame 1: the checkpoint keeps the origin.
  const auto path = std::filesystem::temp_directory_path() / "topotrack_tracker_origin_test.checkpoint";
  write_checkpoint(path, {1, 0, tracker.edge_length(), tracker.voxel_size(), tracker.mesh().clone(),
                          tracker.lattice_origin()});
  Checkpoint c = read_checkpoint(path);
  std::filesystem::remove(path);
  EXPECT_EQ(c.lattice_origin, tracker.lattice_origin());
  Tracker resumed(p);
  resumed.restore(std::move(c.mesh), 1, c.target_edge_length, c.voxel_size, c.lattice_origin);
  const TrackRun rest = track(frames, 1, &resumed);
  for (std::size_t i = 1; i < frames.size(); ++i) {
    const FrameReport& r = tracker.add_frame(frames[i]);
    tracker.mesh().validate(true);
    EXPECT_EQ(r.components, 2u) << "frame " << i;
    EXPECT_EQ(encode_mesh(tracker.mesh()), rest.meshes[i - 1]) << "frame " << i;
    EXPECT_EQ(encode_events(tracker.events()), rest.events[i - 1]) << "frame " << i;
  }
  // The same spacing through 0 (tracker.voxel_size): no node in the gap.
  TrackerParams at_zero = p;
  at_zero.voxel_size = 0.005;
  Tracker plain(at_zero);
  plain.add_frame(frames[0]);
  EXPECT_EQ(plain.lattice_origin(), Vec3::Zero());
  EXPECT_EQ(plain.add_frame(frames[1]).components, 1u) << "the case this test is about";
}

TEST(Tracker, RefinesTheLatticeWhereItMissesTheInputsTopology) {
  // A gap from 0.02 to 0.08 holds no node of the 0.1 lattice, but the node 0.05 of the halved one.
  std::vector<SurfaceMesh> frames;
  for (int i = 0; i < 3; ++i) frames.push_back(spheres_with_gap(0.02, 0.08, 0.01 * i));
  ASSERT_EQ(connected_components(frames[1]), 2);
  {  // One lattice (the paper's rule): ConstrainTopology bridges the gap it cannot see.
    Tracker tracker(coarse_lattice(0));
    tracker.add_frame(frames[0]);
    const FrameReport& r = tracker.add_frame(frames[1]);
    EXPECT_EQ(r.components, 1u) << "the test needs a gap the 0.1 lattice misses";
    EXPECT_EQ(r.topology_retries, 0);
  }
  TrackRun one, two;
  for (int threads : {1, 2}) {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
    Tracker tracker(coarse_lattice(1));
    (threads == 1 ? one : two) = track(frames, 0, &tracker);
    const FrameReport& r = tracker.report();
    EXPECT_EQ(r.components, 2u);
    EXPECT_EQ(r.euler, 4);
    EXPECT_EQ(r.topology_retries, 1);
    EXPECT_EQ(r.topology_level, 1);
    EXPECT_NO_THROW(tracker.mesh().validate(true));
    const QualityStats q = quality_stats(tracker.mesh());
    EXPECT_EQ(q.below_2deg, 0u);
    EXPECT_EQ(q.dihedral_below_45deg, 0u);
  }
  EXPECT_EQ(one.meshes, two.meshes) << "1 and 2 threads";
  EXPECT_EQ(one.events, two.events);
}

TEST(Tracker, KeepsTheFirstResultWhenNoFinerLatticeMatches) {
  // A gap from 0.055 to 0.095 holds no node of the 0.1 lattice nor of the 0.05 one: the retry cannot help,
  // and the output is that of one lattice, bit for bit.
  std::vector<SurfaceMesh> frames;
  for (int i = 0; i < 3; ++i) frames.push_back(spheres_with_gap(0.055, 0.095, 0.01 * i));
  ASSERT_EQ(connected_components(frames[1]), 2);
  Tracker plain(coarse_lattice(0)), refined(coarse_lattice(1));
  const TrackRun a = track(frames, 0, &plain), b = track(frames, 0, &refined);
  EXPECT_EQ(refined.report().components, 1u);
  EXPECT_EQ(refined.report().topology_retries, 1);
  EXPECT_EQ(refined.report().topology_level, 0);
  EXPECT_EQ(refined.report().topology_rejected_for_quality, 0) << "rejected for its topology";
  EXPECT_EQ(a.meshes, b.meshes);
  EXPECT_EQ(a.events, b.events);
  EXPECT_EQ(refined.report().complex_cells_target, plain.report().complex_cells_target);
  // Frames whose topology the first lattice gets right are not retried.
  Tracker easy(coarse_lattice(1));
  for (double t : {0.0, 0.01}) EXPECT_EQ(easy.add_frame(spheres_with_gap(-0.3, 0.3, t)).topology_retries, 0);
}

TEST(Tracker, RejectsOpenInput) {
  Tracker tracker;
  EXPECT_THROW(tracker.add_frame(test::open_box().mesh(), "box.ply"), InvalidInput);
}

}  // namespace
}  // namespace topotrack
