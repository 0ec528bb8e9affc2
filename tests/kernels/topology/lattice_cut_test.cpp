// The lattice cut (lattice_cut.hpp): the pieces of every face tile it exactly, each inside its own cell, both
// when the corners fit the chunks' own ranges (voxel about the edge length) and when they spill over (voxel
// much smaller than the triangles: hundreds of pieces per face).
#include "kernels/topology/lattice_cut.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "kernels/sdf/signed_distance.hpp"
#include "tests/support/test_meshes.hpp"

namespace topotrack::topology {
namespace {

void expect_exact_tiling(const SurfaceMesh& m, double voxel) {
  ensure_openvdb_initialized();
  const auto xform = voxel_transform(voxel);
  const LatticeCut cut = cut_by_lattice(m, *xform);
  ASSERT_TRUE(cut.bad_faces.empty());
  ASSERT_EQ(cut.face_pieces.size(), m.faces_size() + 1);
  for (std::size_t f = 0; f < m.faces_size(); ++f) {
    const auto vs = m.vertices(Face(Index(f)));
    const Vec3 &A = cut.P[vs[0].idx], &B = cut.P[vs[1].idx], &C = cut.P[vs[2].idx];
    const Vec3 normal = (B - A).cross(C - A);  // twice the face's area, in voxels
    Vec3 sum = Vec3::Zero();
    for (std::uint32_t p = cut.face_pieces[f]; p < cut.face_pieces[f + 1]; ++p) {
      const Piece& pc = cut.pieces[p];
      ASSERT_EQ(pc.face, Index(f));
      ASSERT_GE(pc.size, 3);
      const openvdb::Coord cell = cell_from_key(pc.cell);
      const Vec3 o = point_position(m, cut, cut.keys[pc.begin]);
      for (int i = 0; i < pc.size; ++i) {
        const PointKey& k = cut.keys[pc.begin + i];
        ASSERT_NE(kind(k), PointKind::Other);
        const Vec3 x = point_position(m, cut, k);
        for (int a = 0; a < 3; ++a) {
          EXPECT_GE(x[a], cell[a] - 1e-9) << "face " << f << " piece " << p;
          EXPECT_LE(x[a], cell[a] + 1 + 1e-9) << "face " << f << " piece " << p;
        }
        if (i >= 1 && i + 1 < pc.size)
          sum += (x - o).cross(point_position(m, cut, cut.keys[pc.begin + i + 1]) - o);
      }
    }
    EXPECT_NEAR((sum - normal).norm(), 0.0, 1e-9 * (1 + normal.norm())) << "face " << f;
  }
}

TEST(LatticeCut, PiecesTileEachFace) {
  const SurfaceMesh m = test::icosphere(4, 1.0).mesh();
  expect_exact_tiling(m, 0.05);  // about the edge length
}

TEST(LatticeCut, ManyPiecesPerFaceSpillOver) {
  const SurfaceMesh m = test::icosphere(1, 1.0).mesh();  // 80 faces of about 0.6 across
  expect_exact_tiling(m, 0.02);                          // hundreds of cells per face
}

}  // namespace
}  // namespace topotrack::topology
