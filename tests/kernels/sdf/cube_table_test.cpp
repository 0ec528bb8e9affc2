#include "kernels/sdf/cube_table.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <set>
#include <vector>

#include "kernels/sdf/marching_cubes.hpp"

namespace topotrack {
namespace {

Eigen::Vector3d corner_pos(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }

TEST(CubeTable, Conventions) {
  // Edge numbering as documented.
  const int ends[12][2] = {{0, 1}, {2, 3}, {4, 5}, {6, 7}, {0, 2}, {1, 3}, {4, 6}, {5, 7}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  for (int e = 0; e < 12; ++e) {
    EXPECT_EQ(cube::edge_corner(e, 0), ends[e][0]) << e;
    EXPECT_EQ(cube::edge_corner(e, 1), ends[e][1]) << e;
    for (int f : cube::edge_faces(e)) {
      const auto fe = cube::face_edges(f);
      EXPECT_NE(std::find(fe.begin(), fe.end(), e), fe.end()) << "edge " << e << " face " << f;
    }
  }
  for (int f = 0; f < 6; ++f) {
    const auto q = cube::face_corners(f);
    for (int c : q) EXPECT_EQ(cube::corner_bit(c, f >> 1), f & 1);
    // Counter-clockwise seen from outside: the Newell normal points along the outward axis.
    Eigen::Vector3d n = (corner_pos(q[1]) - corner_pos(q[0])).cross(corner_pos(q[2]) - corner_pos(q[0]));
    EXPECT_GT(n[f >> 1] * ((f & 1) ? 1 : -1), 0) << f;
  }
}

TEST(CubeTable, EveryCrossedEdgeOnceAndCyclesAlongFaces) {
  for (int mask = 0; mask < 256; ++mask) {
    const auto& P = cube::cube_polygons(std::uint8_t(mask));
    std::vector<int> count(12, 0);
    for (int p = 0; p < P.count; ++p) {
      const auto poly = P.polygon(p);
      ASSERT_GE(poly.size(), 3u);
      for (std::size_t i = 0; i < poly.size(); ++i) {
        ++count[poly[i]];
        EXPECT_TRUE(cube::edges_share_face(poly[i], poly[(i + 1) % poly.size()])) << mask;
      }
      // Outward orientation: the polygon's normal agrees with the inside -> outside direction.
      Eigen::Vector3d newell = Eigen::Vector3d::Zero(), grad = Eigen::Vector3d::Zero();
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const int e = poly[i], f = poly[(i + 1) % poly.size()];
        const Eigen::Vector3d a = 0.5 * (corner_pos(cube::edge_corner(e, 0)) + corner_pos(cube::edge_corner(e, 1)));
        const Eigen::Vector3d b = 0.5 * (corner_pos(cube::edge_corner(f, 0)) + corner_pos(cube::edge_corner(f, 1)));
        newell += a.cross(b);
        const bool in0 = (mask >> cube::edge_corner(e, 0)) & 1;
        Eigen::Vector3d d = Eigen::Vector3d::Zero();
        d[cube::edge_axis(e)] = in0 ? 1 : -1;
        grad += d;
      }
      EXPECT_GT(newell.dot(grad), 0) << "mask " << mask << " polygon " << p;
    }
    for (int e = 0; e < 12; ++e) {
      const bool crossed = ((mask >> cube::edge_corner(e, 0)) & 1) != ((mask >> cube::edge_corner(e, 1)) & 1);
      EXPECT_EQ(count[e], crossed ? 1 : 0) << "mask " << mask << " edge " << e;
    }
  }
  EXPECT_EQ(cube::cube_polygons(0).count, 0);
  EXPECT_EQ(cube::cube_polygons(255).count, 0);
  EXPECT_EQ(cube::cube_polygons(1).count, 1);
  EXPECT_EQ(cube::cube_polygons(0x69).count, 4);  // four isolated corners
}

// For the two cells sharing a face (cell A below, cell B above along `axis`), whenever the four shared
// corners have the same signs, both make the same segments on that face, in opposite directions.
TEST(CubeTable, SharedFacesAgreeForAllMaskPairs) {
  const openvdb::Coord A(0, 0, 0);
  for (int axis = 0; axis < 3; ++axis) {
    openvdb::Coord B(0, 0, 0);
    B[axis] = 1;
    const int fa = 2 * axis + 1, fb = 2 * axis;
    int checked = 0;
    for (int ma = 0; ma < 256; ++ma) {
      std::array<std::array<int, 2>, 2> sa{};
      const int na = cube::face_segments(std::uint8_t(ma), fa, sa);
      std::set<std::pair<std::uint64_t, std::uint64_t>> seg_a;
      for (int i = 0; i < na; ++i)
        seg_a.insert({lattice_edge_key(cell_edge(A, sa[i][1])), lattice_edge_key(cell_edge(A, sa[i][0]))});
      for (int mb = 0; mb < 256; ++mb) {
        bool same = true;
        for (int c = 0; c < 8 && same; ++c)
          if (cube::corner_bit(c, axis) == 0)
            same = ((mb >> c) & 1) == ((ma >> (c | (1 << axis))) & 1);
        if (!same) continue;
        ++checked;
        std::array<std::array<int, 2>, 2> sb{};
        const int nb = cube::face_segments(std::uint8_t(mb), fb, sb);
        ASSERT_EQ(na, nb) << ma << " " << mb;
        std::set<std::pair<std::uint64_t, std::uint64_t>> seg_b;
        for (int i = 0; i < nb; ++i)
          seg_b.insert({lattice_edge_key(cell_edge(B, sb[i][0])), lattice_edge_key(cell_edge(B, sb[i][1]))});
        ASSERT_EQ(seg_a, seg_b) << "axis " << axis << " masks " << ma << " " << mb;
      }
    }
    EXPECT_EQ(checked, 256 * 16);
  }
}

}  // namespace
}  // namespace topotrack
