// improve_mesh (§4.1) on resurfaced real frames: a level set of a samba / elephant frame re-meshed by
// marching cubes (what the tracker sees), improved: the §4.1 targets hold away from parts thinner than a
// few voxels, where only a topology change (§4.3) could remove the last short edges and creases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
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
  EXPECT_NO_THROW(out.validate());
  EXPECT_EQ(genus(out), genus(in));
  EXPECT_EQ(connected_components(out), connected_components(in));
  const QualityStats q0 = quality_stats(in), q = quality_stats(out);
  const double diag = bounding_box(in).diagonal();
  const double hd = test::hausdorff_distance(in, out, 0.01 * diag);
  std::printf("%s  hausdorff %.5f diag  below 2deg %zu  folds %zu -> %zu\n", test::describe(name, in, out, rep).c_str(),
              hd / diag, q.below_2deg, q0.dihedral_below_45deg, q.dihedral_below_45deg);
  EXPECT_LE(hd, 0.002 * diag);
  EXPECT_LE(q.share_below_10deg, 0.005);
  EXPECT_LE(q.edge_length.max, rep.max_edge_length * (1 + 1e-9));
  // Where a part is thinner than a few voxels the level set's mesh wraps it with a few triangles: there a
  // short edge or a crease cannot go without changing the topology (link condition), which is §4.3's
  // business, not §4.1's. Those spots are rare: at most 0.05% of the triangles keep an angle below 2°,
  // folds do not grow in number, and edges below L_min are at most 2% (the elephant's ears are thin
  // sheets: 1.4% there, mostly refused by the link condition; samba: none).
  EXPECT_LE(double(q.below_2deg), 5e-4 * double(out.n_faces()));
  EXPECT_EQ(q.near_degenerate, 0u);
  // Most of those are in the hundreds of specks that the level set of a self-intersecting input leaves
  // (elephant: 507 closed specks of 6 vertices and up, a voxel long and a tenth of one thick): any closed
  // triangulation of such a sliver has needles. On the parts at least L_min thick they are a handful.
  std::vector<Index> label;
  const Index n_components = connected_components(out, &label);
  std::vector<BoundingBox> box(n_components);
  for (Index v = 0; v < out.vertices_size(); ++v) box[label[v]].extend(out.position(Vertex(v)));
  std::size_t below_2deg_thick = 0;
  for (Index f = 0; f < out.faces_size(); ++f) {
    const auto a = face_angles_deg(out, Face(f));
    const BoundingBox& b = box[label[out.vertices(Face(f))[0].idx]];
    below_2deg_thick += std::min({a[0], a[1], a[2]}) < 2.0 && (b.max - b.min).minCoeff() >= rep.min_edge_length;
  }
  std::printf("  below 2deg on parts at least L_min thick: %zu (of %u components)\n", below_2deg_thick, n_components);
  EXPECT_LE(double(below_2deg_thick), 1e-4 * double(out.n_faces()));
  EXPECT_LE(q.dihedral_below_45deg, q0.dihedral_below_45deg);
  std::size_t short_edges = 0;
  for (Index e = 0; e < out.edges_size(); ++e)
    short_edges += (out.position(out.vertex(Edge(e), 0)) - out.position(out.vertex(Edge(e), 1))).norm() <
                   rep.min_edge_length * (1 - 1e-9);
  EXPECT_LE(double(short_edges), 2e-2 * double(out.n_edges()));
}

TEST(ImproveData, ResurfacedElephantFrame) { check_frame("elephant/elephant.0001.ply", 300); }
TEST(ImproveData, ResurfacedSambaFrame) { check_frame("samba/samba.0001.ply", 300); }

}  // namespace
}  // namespace topotrack
