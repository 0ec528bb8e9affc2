// improve_mesh (§4.1) on resurfaced real frames: a level set of a samba / elephant frame re-meshed by
// marching cubes (what the tracker sees), improved to the §4.1 targets.
#include <gtest/gtest.h>

#include <filesystem>

#include "io/mesh_reader.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "tests/kernels/improve/improve_targets.hpp"

namespace topotrack {
namespace {

//! The frame re-meshed through its signed distance at voxel size diag / `cells`.
SurfaceMesh resurfaced(const std::filesystem::path& path, double cells) {
  const SurfaceMesh frame = to_surface_mesh(read_mesh(path));
  const double voxel = bounding_box(frame).diagonal() / cells;
  return to_surface_mesh(marching_cubes(*signed_distance(frame, voxel)));
}

void check_frame(const std::string& name, double cells) {
  const std::filesystem::path path = std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / name;
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const SurfaceMesh in = resurfaced(path, cells);
  ASSERT_GT(in.n_vertices(), 20000u);
  SurfaceMesh out = in.clone();
  EventList events;
  const ImproveReport rep = improve_mesh(out, {}, &events);
  EXPECT_EQ(events.size(), rep.splits + rep.collapses);
  test::expect_targets(in, out, rep, name);
}

TEST(ImproveData, ResurfacedElephantFrameMeetsTargets) { check_frame("elephant/elephant.0001.ply", 300); }
TEST(ImproveData, ResurfacedSambaFrameMeetsTargets) { check_frame("samba/samba.0001.ply", 300); }

}  // namespace
}  // namespace topotrack
