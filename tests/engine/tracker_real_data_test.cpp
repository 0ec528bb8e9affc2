// Algorithm 1 on resurfaced real frames (slow label; skipped without ../shared/data): what the lattice's
// voxel size does to parts about one edge length thick.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "engine/profile.hpp"
#include "engine/tracker.hpp"
#include "io/mesh_reader.hpp"
#include "kernels/eval/surface_distance.hpp"
#include "kernels/gen/gen_sequence.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack {
namespace {

// Resurfaced pcow, frames 1-2 as `gen resurface` makes them: a tip about one edge length thick grows by a few
// edge lengths between the frames. With the paper's voxels (one mean edge length) ConstrainTopology(M, φ_M)
// cuts the part of it the alignment brought along (the lattice does not see it), and the output falls short
// of the input by 1.36 % of the diagonal; with half-L voxels (profiles/capture.json) it stays.
TEST(TrackerRealData, HalfEdgeVoxelsKeepAThinTipThePapersLatticeCuts) {
  const std::filesystem::path source = std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / "pcow";
  if (!std::filesystem::exists(source / "pcow.0002.ply")) GTEST_SKIP() << "no pcow data";
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("topotrack_tracker_real_" + std::to_string(::getpid()));
  GenParams g;
  g.kind = "resurface";
  g.source = source.string();
  g.frames = 2;
  generate_sequence(g, dir);
  const SurfaceMesh f1 = to_surface_mesh(read_mesh(dir / "resurface.0001.ply"));
  const SurfaceMesh f2 = to_surface_mesh(read_mesh(dir / "resurface.0002.ply"));
  std::filesystem::remove_all(dir);
  const double diag = bounding_box(f2).diagonal();
  const auto hausdorff = [&](double voxel_size_factor) {
    TrackerParams p = load_profile("default");
    p.voxel_size_factor = voxel_size_factor;
    Tracker tracker(p);
    tracker.add_frame(f1);
    tracker.add_frame(f2);
    tracker.mesh().validate();
    return surface_distance(tracker.mesh(), f2).hausdorff() / diag;
  };
  const double at_l = hausdorff(1.0), at_half_l = hausdorff(0.5);
  std::printf("Hausdorff distance to frame 2, fraction of its diagonal: voxels L %.4f, L/2 %.4f\n", at_l, at_half_l);
  EXPECT_GT(at_l, 0.012);
  EXPECT_LT(at_half_l, 0.006);
  EXPECT_EQ(load_profile("capture").voxel_size_factor, 0.5);
}

}  // namespace
}  // namespace topotrack
