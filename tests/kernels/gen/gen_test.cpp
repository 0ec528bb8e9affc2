#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <openvdb/tools/Interpolation.h>

#include "io/mesh_reader.hpp"
#include "kernels/gen/fill_voids.hpp"
#include "kernels/gen/gen_sequence.hpp"
#include "kernels/gen/implicit_grid.hpp"
#include "kernels/gen/resurface.hpp"
#include "kernels/gen/shapes.hpp"
#include "kernels/gen/synthetic.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/sdf/extraction_grid.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {
namespace {

namespace fs = std::filesystem;

struct Topo {
  Index components;
  long genus;
};

Topo topology(const MeshData& m) {
  SurfaceMesh s = to_surface_mesh(m);
  s.validate(true);
  return {connected_components(s), genus(s)};
}

Vec3 pos(const MeshData& m, std::size_t i) { return Vec3(m.positions[i][0], m.positions[i][1], m.positions[i][2]); }

fs::path temp_dir(const std::string& name) {
  fs::path d = fs::path(TOPOTRACK_BINARY_DIR) / "test_output" / name;
  fs::remove_all(d);
  return d;
}

TEST(Gen, ShapesAreSignedDistances) {
  using namespace sdf_shapes;
  EXPECT_NEAR(sphere(Vec3(2, 0, 0), Vec3::Zero(), 0.5), 1.5, 1e-12);
  EXPECT_NEAR(capsule(Vec3(0.5, 1, 0), Vec3::Zero(), Vec3(1, 0, 0), 0.25), 0.75, 1e-12);
  EXPECT_NEAR(capsule(Vec3(-1, 0, 0), Vec3::Zero(), Vec3(1, 0, 0), 0.25), 0.75, 1e-12);
  EXPECT_NEAR(torus_z(Vec3(1, 0, 0), Vec3::Zero(), 1.0, 0.3), -0.3, 1e-12);
  EXPECT_NEAR(torus_z(Vec3(0, 0, 0), Vec3::Zero(), 1.0, 0.3), 0.7, 1e-12);
  EXPECT_NEAR(smooth_min(0.0, 5.0, 0.2), 0.0, 1e-12);
  EXPECT_LT(smooth_min(0.1, 0.1, 0.2), 0.1);
}

TEST(Gen, SampleImplicitSphere) {
  const BoundingBox box{Vec3::Constant(-1.0), Vec3::Constant(1.0)};
  const double h = 0.04;
  auto f = [](const Vec3& p) { return p.norm() - 0.8; };
  const MeshData m = mesh_implicit(f, box, h);
  const Topo t = topology(m);
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(t.genus, 0);
  for (std::size_t i = 0; i < m.vertex_count(); ++i) EXPECT_NEAR(pos(m, i).norm(), 0.8, 0.1 * h);
  EXPECT_THROW(sample_implicit(f, box, 0.0), InvalidInput);
  EXPECT_THROW(sample_implicit(f, box, h, 0.0), InvalidInput);
  EXPECT_THROW(sample_implicit(f, BoundingBox{}, h), InvalidInput);
  EXPECT_THROW(sample_implicit(f, box, 1e-9), InvalidInput);
}

TEST(Gen, BlobsFramesAndGroundTruthRotation) {
  SyntheticParams p;
  p.kind = SyntheticKind::kBlobs;
  p.frames = 8;
  const SyntheticScene scene(p);
  const double h = scene.voxel_size();
  const MeshData first = scene.frame_mesh(1);
  EXPECT_GE(first.vertex_count(), 10000u);
  EXPECT_LE(first.vertex_count(), 20000u);
  const Topo t1 = topology(first);
  EXPECT_EQ(t1.components, 1u);
  EXPECT_EQ(t1.genus, 0);
  for (int n : {3, 6}) {
    const MeshData m = scene.frame_mesh(n);
    const Topo t = topology(m);
    EXPECT_EQ(t.components, 1u);
    EXPECT_EQ(t.genus, 0);
    EXPECT_NE(m.vertex_count(), first.vertex_count());  // new connectivity every frame
    const RigidMotion g = scene.blobs_motion(n);
    // The frame-1 surface moved by the ground truth lies on the frame-n field's zero set...
    for (std::size_t i = 0; i < first.vertex_count(); ++i) {
      const Vec3 x = g.rotation * (pos(first, i) - g.center) + g.center;
      ASSERT_LT(std::abs(scene.field(n, x)), 0.5 * h) << "frame " << n << " vertex " << i;
    }
    // ...and close to the frame-n mesh itself (nearest vertex within a voxel), on a sample of vertices.
    for (std::size_t i = 0; i < first.vertex_count(); i += 97) {
      const Vec3 x = g.rotation * (pos(first, i) - g.center) + g.center;
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t j = 0; j < m.vertex_count(); ++j) best = std::min(best, (pos(m, j) - x).squaredNorm());
      ASSERT_LT(std::sqrt(best), h) << "frame " << n << " vertex " << i;
    }
  }
  // A full turn over the sequence; the ground truth says so.
  const RigidMotion quarter = scene.blobs_motion(3);
  EXPECT_NEAR(Eigen::AngleAxisd(quarter.rotation).angle(), 2 * M_PI * 2 / 8, 1e-12);
  const nlohmann::json truth = scene.ground_truth();
  ASSERT_EQ(truth["frames"].size(), 8u);
  EXPECT_EQ(truth["frames"][2]["frame"], 3);
  EXPECT_NEAR(truth["frames"][2]["rotation"][1][0].get<double>(), quarter.rotation(1, 0), 1e-15);
}

TEST(Gen, MorphChangesGenusAndComponents) {
  SyntheticParams p;
  p.kind = SyntheticKind::kMorph;
  p.frames = 5;
  const SyntheticScene scene(p);
  const Topo a = topology(scene.frame_mesh(1)), b = topology(scene.frame_mesh(3)), c = topology(scene.frame_mesh(5));
  EXPECT_EQ(a.components, 1u);
  EXPECT_EQ(a.genus, 1);
  EXPECT_EQ(b.components, 2u);
  EXPECT_EQ(b.genus, 0);
  EXPECT_EQ(c.components, 1u);
  EXPECT_EQ(c.genus, 0);
  EXPECT_THROW(scene.frame_mesh(0), InvalidInput);
  EXPECT_THROW(scene.frame_mesh(6), InvalidInput);
}

TEST(Gen, MetaballsSplitAndMerge) {
  SyntheticParams p;
  p.kind = SyntheticKind::kMetaballs;
  p.frames = 9;
  p.seed = 7;
  const SyntheticScene scene(p);
  std::vector<Index> comps;
  for (int n = 1; n <= 9; ++n) {
    const MeshData m = scene.frame_mesh(n);
    const Topo t = topology(m);
    EXPECT_EQ(t.genus, 0) << n;
    comps.push_back(t.components);
  }
  EXPECT_EQ(comps.front(), 1u);
  EXPECT_EQ(comps[4], 4u);
  EXPECT_EQ(comps.back(), 1u);
  EXPECT_EQ(scene.metaballs(5).size(), 4u);
}

TEST(Gen, DeterministicAcrossThreadCounts) {
  SyntheticParams p;
  p.kind = SyntheticKind::kMetaballs;
  p.frames = 3;
  const SyntheticScene scene(p);
  MeshData one, two;
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
    one = scene.frame_mesh(2);
  }
  {
    tbb::global_control c(tbb::global_control::max_allowed_parallelism, 2);
    two = scene.frame_mesh(2);
  }
  EXPECT_EQ(one.positions, two.positions);
  EXPECT_EQ(one.triangles, two.triangles);
}

TEST(Gen, BadParameters) {
  SyntheticParams p;
  p.frames = 0;
  EXPECT_THROW(SyntheticScene{p}, InvalidInput);
  p.frames = 3;
  p.resolution = 4;
  EXPECT_THROW(SyntheticScene{p}, InvalidInput);
  EXPECT_THROW(synthetic_kind_from_name("cubes"), UsageError);
  GenParams g;
  g.kind = "cubes";
  EXPECT_THROW(generate_sequence(g, temp_dir("bad_kind")), UsageError);
  g.kind = "resurface";
  EXPECT_THROW(generate_sequence(g, temp_dir("bad_source")), UsageError);
  g.source = (fs::path(TOPOTRACK_BINARY_DIR) / "no_such_folder").string();
  EXPECT_THROW(generate_sequence(g, temp_dir("bad_source")), InvalidInput);
  EXPECT_THROW(resurface(MeshData{}, {0.0}), InvalidInput);
  g.grid_offset = {0.25, 1.0, 0};  // in [0, 1) voxels
  EXPECT_THROW(generate_sequence(g, temp_dir("bad_offset")), InvalidInput);
  g.kind = "blobs";
  g.grid_offset = {0.25, 0, 0};  // the synthetic kinds have no such option
  EXPECT_THROW(generate_sequence(g, temp_dir("bad_offset_kind")), UsageError);
}

TEST(Gen, WritesSyntheticSequence) {
  const fs::path dir = temp_dir("gen_morph");
  GenParams g;
  g.kind = "morph";
  g.frames = 3;
  g.resolution = 48;
  int calls = 0;
  g.progress = [&](const GenFrameReport& r, int total) {
    ++calls;
    EXPECT_EQ(total, 3);
    EXPECT_EQ(r.frame, calls);
  };
  const GenReport report = generate_sequence(g, dir);
  EXPECT_EQ(calls, 3);
  ASSERT_EQ(report.frames.size(), 3u);
  for (int n = 1; n <= 3; ++n) {
    const fs::path f = dir / ("morph.000" + std::to_string(n) + ".ply");
    ASSERT_TRUE(fs::exists(f)) << f;
    const MeshData m = read_mesh(f);
    EXPECT_EQ(m.vertex_count(), report.frames[n - 1].vertices);
    EXPECT_NO_THROW(topology(m));
  }
  std::ifstream in(dir / "gen.json");
  const nlohmann::json info = nlohmann::json::parse(in);
  EXPECT_EQ(info["kind"], "morph");
  EXPECT_EQ(info["frame_count"], 3);
  EXPECT_EQ(info["frames"][0]["genus"], 1);
  EXPECT_EQ(info["frames"][1]["components"], 2);
  EXPECT_TRUE(fs::exists(dir / "ground_truth.json"));
}

// --last writes the first frames of the long sequence (the Table 1 harness), identical to those of a full run.
TEST(Gen, LastFrameWritesTheFirstFramesOfTheFullSequence) {
  GenParams g;
  g.kind = "blobs";
  g.frames = 12;
  g.resolution = 32;
  const fs::path full = temp_dir("gen_last_full"), part = temp_dir("gen_last_part");
  generate_sequence(g, full);
  g.last_frame = 2;
  const GenReport report = generate_sequence(g, part);
  ASSERT_EQ(report.frames.size(), 2u);
  EXPECT_FALSE(fs::exists(part / "blobs.0003.ply"));
  for (const char* name : {"blobs.0001.ply", "blobs.0002.ply"}) {
    const MeshData a = read_mesh(full / name), b = read_mesh(part / name);
    EXPECT_EQ(a.positions, b.positions) << name;
    EXPECT_EQ(a.triangles, b.triangles) << name;
  }
  g.last_frame = -1;
  EXPECT_THROW(generate_sequence(g, temp_dir("gen_last_bad")), InvalidInput);
}

// Trilinear |signed distance| of `grid` at p.
double grid_distance(const openvdb::FloatGrid& grid, const Vec3& p) {
  openvdb::tools::GridSampler<openvdb::FloatGrid, openvdb::tools::BoxSampler> s(grid);
  return std::abs(double(s.wsSample(openvdb::Vec3d(p.x(), p.y(), p.z()))));
}

TEST(Gen, ResurfaceSambaKeepsTheSurface) {
  const fs::path samba = fs::path(TOPOTRACK_SHARED_DIR) / "data" / "samba";
  if (!fs::exists(samba)) GTEST_SKIP() << samba << " not present";
  const fs::path dir = temp_dir("gen_resurface");
  GenParams g;
  g.kind = "resurface";
  g.source = samba.string();
  g.frames = 3;
  g.start = 10;
  g.every = 5;
  const GenReport report = generate_sequence(g, dir);
  ASSERT_EQ(report.frames.size(), 3u);
  const double h = report.voxel_size;
  std::vector<std::size_t> counts;
  for (int n = 1; n <= 3; ++n) {
    const GenFrameReport& r = report.frames[n - 1];
    EXPECT_EQ(fs::path(r.source_file).filename().string(), "samba.00" + std::to_string(10 + 5 * (n - 1)) + ".ply");
    const fs::path truth = dir / "ground_truth" / ("samba.000" + std::to_string(n) + ".ply");
    ASSERT_TRUE(fs::exists(truth)) << truth;
    EXPECT_EQ(fs::file_size(truth), fs::file_size(r.source_file));
    const MeshData out = read_mesh(dir / r.file), src = read_mesh(truth);
    EXPECT_GT(out.vertex_count(), 5000u);
    EXPECT_LT(out.vertex_count(), 60000u);
    counts.push_back(out.vertex_count());
    // A closed 2-manifold; thin parts (fingers) may come apart at this voxel size, as the data README says.
    EXPECT_LE(topology(out).components, 4u);
    // Every new vertex within a voxel of the source surface.
    std::vector<Vec3> sp;
    std::vector<std::array<Index, 3>> st;
    for (std::size_t i = 0; i < src.vertex_count(); ++i) sp.push_back(pos(src, i));
    for (const auto& t : src.triangles) st.push_back({Index(t[0]), Index(t[1]), Index(t[2])});
    // Exact signs (winding number) within the band: OpenVDB's own sign is wrong at a few voxels next to the
    // surface, which would misreport the distance there.
    SignedDistanceParams exact;
    exact.voxel_size = h;
    exact.exact_sign_band_voxels = 3;
    exact.sign_method = SignMethod::kWindingNumber;
    auto src_sdf = signed_distance(sp, st, exact);
    for (std::size_t i = 0; i < out.vertex_count(); ++i)
      ASSERT_LT(grid_distance(*src_sdf, pos(out, i)), h) << "frame " << n << " vertex " << i;
  }
  EXPECT_NE(counts[0], counts[1]);

  // On a grid through another origin (--grid-offset): the frame's vertices lie on that grid's edges, which
  // tracker.extraction_grid finds with its origin.
  g.frames = 1;
  g.grid_offset = {0.37, 0.5, 0.0};
  const fs::path moved = temp_dir("gen_resurface_offset");
  const GenReport off = generate_sequence(g, moved);
  ASSERT_EQ(off.frames.size(), 1u);
  const MeshData m = read_mesh(moved / off.frames[0].file);
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < m.vertex_count(); ++i) points.push_back(pos(m, i));
  const auto grid = extraction_grid(points, 0.0);
  ASSERT_TRUE(grid);
  EXPECT_NEAR(grid->spacing, h, 1e-6 * h);
  for (int a = 0; a < 3; ++a) {
    const double t = grid->origin[a] / h - g.grid_offset[a];
    EXPECT_NEAR(t, std::round(t), 1e-4) << "axis " << a;
  }
}


// A ball of radius 1 with a sealed cavity of radius 0.5, a speck of radius 0.2 floating in the cavity and a
// separate ball of radius 0.4 outside: four components, two of which (the cavity wall, inside out, and the
// speck) lie inside the first ball.
double hollow_scene(const Vec3& p) {
  using namespace sdf_shapes;
  const double shell = std::max(sphere(p, Vec3::Zero(), 1.0), -sphere(p, Vec3::Zero(), 0.5));
  return std::min({shell, sphere(p, Vec3::Zero(), 0.2), sphere(p, Vec3(2.5, 0, 0), 0.4)});
}

TEST(Gen, FillVoidsRemovesCavitiesAndWhatFloatsInThem) {
  const BoundingBox box{Vec3(-1.2, -1.2, -1.2), Vec3(3.1, 1.2, 1.2)};
  const double h = 0.05;
  MeshData m = mesh_implicit(hollow_scene, box, h);
  ASSERT_EQ(topology(m).components, 4u);
  m.ids.emplace();
  VertexAttribute x{"x", 1, {}};
  for (std::size_t i = 0; i < m.vertex_count(); ++i) {
    m.ids->push_back(std::int64_t(1000 + i));
    x.values.push_back(float(m.positions[i][0]));
  }
  m.attributes.push_back(x);
  FillVoidsReport r;
  const MeshData out = fill_voids(m, &r);
  EXPECT_EQ(r.components, 4u);
  EXPECT_EQ(r.voids_filled, 1u);
  EXPECT_EQ(r.islands_removed, 1u);
  EXPECT_EQ(r.vertices_removed + out.vertex_count(), m.vertex_count());
  EXPECT_EQ(r.triangles_removed + out.triangle_count(), m.triangle_count());
  const Topo t = topology(out);
  EXPECT_EQ(t.components, 2u);
  EXPECT_EQ(t.genus, 0);
  ASSERT_TRUE(out.ids.has_value());
  ASSERT_EQ(out.ids->size(), out.vertex_count());
  ASSERT_EQ(out.attributes.size(), 1u);
  ASSERT_EQ(out.attributes[0].values.size(), out.vertex_count());
  std::size_t outer = 0, small = 0;
  for (std::size_t i = 0; i < out.vertex_count(); ++i) {
    const Vec3 p = pos(out, i);
    const std::size_t source = std::size_t((*out.ids)[i] - 1000);
    EXPECT_EQ(m.positions[source], out.positions[i]);
    EXPECT_EQ(out.attributes[0].values[i], float(p.x()));
    if (std::abs(p.norm() - 1.0) < 0.2 * h) ++outer;
    else if (std::abs((p - Vec3(2.5, 0, 0)).norm() - 0.4) < 0.2 * h) ++small;
    else ADD_FAILURE() << "vertex " << i << " at " << p.transpose() << " is on no outer surface";
  }
  EXPECT_GT(outer, 1000u);
  EXPECT_GT(small, 100u);
  // Nothing enclosed: unchanged.
  FillVoidsReport none;
  const MeshData again = fill_voids(out, &none);
  EXPECT_EQ(none.components, 2u);
  EXPECT_EQ(none.voids_filled + none.islands_removed, 0u);
  EXPECT_EQ(again.positions, out.positions);
  EXPECT_EQ(again.triangles, out.triangles);
  {  // the same with one thread
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const MeshData serial = fill_voids(m);
    EXPECT_EQ(serial.positions, out.positions);
    EXPECT_EQ(serial.triangles, out.triangles);
  }
  MeshData bad = out;
  bad.triangles[0][1] = std::int64_t(bad.vertex_count());
  EXPECT_THROW(fill_voids(bad), InvalidInput);
  bad = out;
  bad.positions[0][2] = std::nan("");
  EXPECT_THROW(fill_voids(bad), InvalidInput);
}

TEST(Gen, ResurfaceOfAHollowBallIsSolid) {
  const BoundingBox box{Vec3(-1.2, -1.2, -1.2), Vec3(3.1, 1.2, 1.2)};
  const MeshData source = mesh_implicit(hollow_scene, box, 0.03);
  ASSERT_EQ(topology(source).components, 4u);
  ResurfaceParams p;
  p.voxel_size = 0.05;
  const MeshData out = resurface(source, p);
  EXPECT_EQ(topology(out).components, 2u);
  for (std::size_t i = 0; i < out.vertex_count(); ++i) {
    const Vec3 q = pos(out, i);
    EXPECT_TRUE(std::abs(q.norm() - 1.0) < 0.5 * p.voxel_size ||
                std::abs((q - Vec3(2.5, 0, 0)).norm() - 0.4) < 0.5 * p.voxel_size)
        << "vertex " << i << " at " << q.transpose();
  }
}

// pcow.0081 of /work/shared/data, resurfaced as `gen resurface` does (voxel: 1/128 of the largest side of
// frame 1's box): the winding number's union and the thickening seal two thin gaps of the
// self-intersecting capture into cavities.
TEST(Gen, ResurfacePcowFillsItsCavities) {
  const fs::path path = fs::path(TOPOTRACK_SHARED_DIR) / "data/pcow/pcow.0081.ply";
  if (!fs::exists(path)) GTEST_SKIP() << path << " not present";
  const MeshData source = read_mesh(path), first = read_mesh(path.parent_path() / "pcow.0001.ply");
  BoundingBox box;
  for (std::size_t i = 0; i < first.vertex_count(); ++i) box.extend(pos(first, i));
  ResurfaceParams p;
  p.voxel_size = (box.max - box.min).maxCoeff() / 128;
  p.fill_voids = false;
  ResurfaceReport r;
  const MeshData hollow = resurface(source, p, &r);
  EXPECT_EQ(topology(hollow).components, 3u);
  EXPECT_EQ(r.voids_filled + r.islands_removed, 0u);
  p.fill_voids = true;
  const MeshData solid = resurface(source, p, &r);
  EXPECT_EQ(topology(solid).components, 1u);
  EXPECT_EQ(r.voids_filled, 2u);
  EXPECT_EQ(r.islands_removed, 0u);
  // The outer surface is untouched: the first vertices and triangles of the hollow mesh, renumbered.
  EXPECT_LT(solid.vertex_count(), hollow.vertex_count());
  std::size_t matched = 0;
  for (std::size_t i = 0, j = 0; i < solid.vertex_count() && j < hollow.vertex_count(); ++j)
    if (solid.positions[i] == hollow.positions[j]) ++i, ++matched;
  EXPECT_EQ(matched, solid.vertex_count());
}

}  // namespace
}  // namespace topotrack
