// improve_mesh (§4.1) on resurfaced real frames, the tracker's input: frames 1-3 of each capture in
// ../shared/data re-meshed through a level set exactly as `topotrack gen resurface DIR --frames 3` does
// (kernels/gen resurface: winding-number signs, thin parts thickened, marching cubes; voxel size from frame 1
// at 128 voxels across its largest side). The targets are asserted on every frame: at most 0.5% of
// the triangles below 10°, none below 2°, no dihedral angle below 45°, every edge within [L_min, L_max], a
// closed 2-manifold of the same genus and components, Hausdorff distance to the input at most 0.2% of the
// diagonal, and improving the result again changes nothing. Where a target cannot hold without a topology
// change (§4.3's business, not §4.1's) the exemption is checked, not assumed: see `pinched`.
// Skipped when ../shared/data is absent.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "io/mesh_reader.hpp"
#include "kernels/gen/resurface.hpp"
#include "kernels/improve/improve.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "tests/kernels/improve/improve_targets.hpp"

namespace topotrack {
namespace {

std::filesystem::path frame_path(const std::string& capture, int frame) {
  char name[64];
  std::snprintf(name, sizeof name, "%s.%04d.ply", capture.c_str(), frame);
  return std::filesystem::path(TOPOTRACK_SHARED_DIR) / "data" / capture / name;
}

//! Whether edge e lies on a 3-cycle of edges that is not a face, with the edge below L_min: the surface
//! there is a handle or tube thinner than L_min (marching cubes wraps a sub-voxel tunnel with three edges);
//! no collapse may remove the edge (link condition) and no move can make it long without tearing the tube.
bool pinched(const SurfaceMesh& m, Edge e) {
  const Vertex a = m.vertex(e, 0), b = m.vertex(e, 1);
  const Halfedge h = m.halfedge(e, 0);
  const Vertex c = m.to_vertex(m.next(h)), d = m.to_vertex(m.next(SurfaceMesh::opposite(h)));
  const Halfedge g0 = m.halfedge(a);
  Halfedge g = g0;
  do {
    const Vertex w = m.to_vertex(g);
    if (w != b && w != c && w != d && m.find_halfedge(w, b).is_valid()) return true;
    g = m.ccw_rotated(g);
  } while (g != g0);
  return false;
}

void check(const std::string& capture, int frame, double voxel) {
  SCOPED_TRACE(capture + " frame " + std::to_string(frame));
  const SurfaceMesh in = to_surface_mesh(resurface(read_mesh(frame_path(capture, frame)), {voxel, 2.0}));
  ASSERT_GT(in.n_vertices(), 10000u);
  SurfaceMesh out = in.clone();
  EventList events;
  const ImproveReport rep = improve_mesh(out, {}, &events);
  EXPECT_EQ(events.size(), rep.splits + rep.collapses);
  EXPECT_NO_THROW(out.validate());
  EXPECT_EQ(genus(out), genus(in));
  EXPECT_EQ(connected_components(out), connected_components(in));
  const QualityStats q = quality_stats(out);
  EXPECT_LE(q.share_below_10deg, 0.005);
  EXPECT_EQ(q.dihedral_below_45deg, 0u);
  EXPECT_LE(q.edge_length.max, rep.max_edge_length * (1 + 1e-9));

  // Edges below L_min and triangles below 2°: only on handles thinner than L_min (pinched), and a few
  // short edges whose collapse would crease the surface into a fold and that no move can lengthen.
  std::size_t short_edges = 0, short_pinched = 0, below_2deg = 0, below_2deg_pinched = 0;
  for (Index i = 0; i < out.edges_size(); ++i) {
    const Edge e(i);
    const double l = (out.position(out.vertex(e, 0)) - out.position(out.vertex(e, 1))).norm();
    if (l >= rep.min_edge_length * (1 - 1e-9)) continue;
    ++short_edges;
    short_pinched += pinched(out, e);
  }
  for (Index i = 0; i < out.faces_size(); ++i) {
    const Face f(i);
    const auto a = face_angles_deg(out, f);
    if (std::min({a[0], a[1], a[2]}) >= 2.0) continue;
    ++below_2deg;
    Halfedge h = out.halfedge(f);
    bool p = false;
    for (int k = 0; k < 3; ++k, h = out.next(h)) p = p || pinched(out, SurfaceMesh::edge(h));
    below_2deg_pinched += p;
  }
  const double diag = bounding_box(in).diagonal();
  const double hd = test::hausdorff_distance(in, out, 0.01 * diag);
  std::printf("%s  hausdorff %.5f diag  short edges %zu (%zu pinched)  below 2deg %zu (%zu pinched)\n",
              test::describe(capture + "." + std::to_string(frame), in, out, rep).c_str(), hd / diag,
              short_edges, short_pinched, below_2deg, below_2deg_pinched);
  EXPECT_EQ(below_2deg, below_2deg_pinched);
  EXPECT_LE(double(short_edges - short_pinched), 2e-4 * double(out.n_edges()));
  // pcow intersects itself along its plane of symmetry: its level set has knife-edge creases (dihedral
  // angles down to 20°) that no triangle of edges >= L_min can follow; their removal is the largest move
  // (fold_pass, prepare_knife_edge: frame 3 0.24 L, 0.0013 of the diagonal; 0.2% of it is 0.36 L).
  EXPECT_LE(hd, 0.002 * diag);

  // Fixed point: improving the improved frame again with the same L changes nothing.
  ImproveParams again;
  again.target_edge_length = std::sqrt(rep.min_edge_length * rep.max_edge_length);
  const std::vector<Vec3> positions = out.positions();
  EventList events2;
  const ImproveReport rep2 = improve_mesh(out, again, &events2);
  EXPECT_EQ(events2.size(), 0u);
  EXPECT_EQ(rep2.flips + rep2.relaxations, 0u);
  EXPECT_TRUE(out.positions() == positions) << "a vertex moved";
}

class ImproveResurfaced : public ::testing::TestWithParam<std::string> {};

TEST_P(ImproveResurfaced, GenResurfaceFrames1To3MeetTargets) {
  const std::string capture = GetParam();
  if (!std::filesystem::exists(frame_path(capture, 1)))
    GTEST_SKIP() << frame_path(capture, 1) << " not present";
  // As gen resurface: the voxel size of the first frame (128 across its largest side) for every frame.
  const BoundingBox box = bounding_box(to_surface_mesh(read_mesh(frame_path(capture, 1))));
  const double voxel = (box.max - box.min).maxCoeff() / 128;
  for (int frame = 1; frame <= 3; ++frame) check(capture, frame, voxel);
}

INSTANTIATE_TEST_SUITE_P(Captures, ImproveResurfaced, ::testing::Values("elephant", "samba", "pcow"),
                         [](const ::testing::TestParamInfo<std::string>& p) { return p.param; });

}  // namespace
}  // namespace topotrack
