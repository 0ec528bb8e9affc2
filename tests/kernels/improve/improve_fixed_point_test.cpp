// improve_mesh (§4.1) leaves its own output alone: improving an improved mesh again with the same target
// edge length records no event and moves no vertex (issue 3: "a mesh already within bounds is left
// unchanged"; Algorithm 1 improves every frame, and on a still surface it must not resample). On a
// 100k-vertex marching-cubes mesh, a marching-tetrahedra mesh and resurfaced real frames.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>

#include "io/mesh_reader.hpp"
#include "kernels/gen/implicit_grid.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"
#include "tests/kernels/improve/implicit_mesh.hpp"

namespace topotrack {
namespace {

//! Improve `mesh` once, then again with the same L: the second call must be a no-op.
void expect_fixed_point(const std::string& name, SurfaceMesh mesh) {
  SCOPED_TRACE(name);
  const std::size_t n_in = mesh.n_vertices();
  const ImproveReport first = improve_mesh(mesh);
  ImproveParams params;
  params.target_edge_length = std::sqrt(first.min_edge_length * first.max_edge_length);
  const std::vector<Vec3> positions = mesh.positions();
  const std::vector<VertexId> ids = mesh.ids();
  const std::size_t n_faces = mesh.n_faces();
  EventList events;
  const ImproveReport again = improve_mesh(mesh, params, &events);
  std::printf("%-26s V %6zu -> %6zu (%zu events, %d rounds); again: %zu events, %zu relaxations, %d rounds\n",
              name.c_str(), n_in, mesh.n_vertices(), first.splits + first.collapses, first.iterations, events.size(),
              again.relaxations, again.iterations);
  EXPECT_EQ(events.size(), 0u);
  EXPECT_EQ(again.splits + again.collapses + again.flips + again.relaxations, 0u);
  EXPECT_EQ(mesh.n_faces(), n_faces);
  EXPECT_EQ(mesh.ids(), ids);
  EXPECT_TRUE(mesh.positions() == positions) << "a vertex moved";
}

TEST(ImproveFixedPoint, MarchingCubesTorus100k) {
  const auto torus = [](const Vec3& p) {
    const double q = std::sqrt(p.x() * p.x() + p.y() * p.y()) - 1.0;
    return std::sqrt(q * q + p.z() * p.z()) - 0.4;
  };
  SurfaceMesh mc = to_surface_mesh(mesh_implicit(torus, {Vec3(-1.5, -1.5, -0.5), Vec3(1.5, 1.5, 0.5)}, 0.0165));
  ASSERT_GT(mc.n_vertices(), 95000u);
  expect_fixed_point("marching-cubes torus", std::move(mc));
}

TEST(ImproveFixedPoint, MarchingTetrahedraTorus100k) {
  expect_fixed_point("marching-tetrahedra torus", test::mt_torus(116).mesh());
}

//! A real frame re-meshed through its signed distance at voxel size diag / 300 (as the tracker sees it).
void expect_fixed_point_on_frame(const std::string& name) {
  const std::filesystem::path path = std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / name;
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not present";
  const SurfaceMesh frame = to_surface_mesh(read_mesh(path));
  const double voxel = bounding_box(frame).diagonal() / 300;
  expect_fixed_point(name, to_surface_mesh(marching_cubes(*signed_distance(frame, voxel))));
}

TEST(ImproveFixedPoint, ResurfacedSambaFrame) { expect_fixed_point_on_frame("samba/samba.0001.ply"); }
TEST(ImproveFixedPoint, ResurfacedPcowFrame) { expect_fixed_point_on_frame("pcow/pcow.0001.ply"); }

}  // namespace
}  // namespace topotrack
