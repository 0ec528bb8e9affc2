#include "kernels/sdf/cube_table.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <stdexcept>

namespace topotrack::cube {
namespace {

// The two axes other than a, in increasing order.
std::array<int, 2> other_axes(int a) { return a == 0 ? std::array{1, 2} : a == 1 ? std::array{0, 2} : std::array{0, 1}; }

Eigen::Vector3d corner_pos(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }
Eigen::Vector3d edge_mid(int e) { return 0.5 * (corner_pos(edge_corner(e, 0)) + corner_pos(edge_corner(e, 1))); }

// The corner shared by two edges, or -1.
int shared_corner(int e0, int e1) {
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j)
      if (edge_corner(e0, i) == edge_corner(e1, j)) return edge_corner(e0, i);
  return -1;
}

// Build the table: per face the segments of the "inside separated" rule, oriented so that the polygon
// normal points from inside corners to outside corners, then chained into cycles.
std::array<CubePolygons, 256> build_table() {
  std::array<CubePolygons, 256> table{};
  for (int mask = 0; mask < 256; ++mask) {
    auto inside = [&](int c) { return ((mask >> c) & 1) != 0; };
    std::array<int, 12> next;
    next.fill(-1);
    for (int f = 0; f < kFaces; ++f) {
      const auto q = face_corners(f);
      const auto E = face_edges(f);
      int crossed = 0;
      for (int i = 0; i < 4; ++i) crossed += inside(q[i]) != inside(q[(i + 1) % 4]);
      std::array<std::array<int, 2>, 2> pairs{};
      int n_pairs = 0;
      if (crossed == 2) {
        int k = 0;
        for (int i = 0; i < 4; ++i)
          if (inside(q[i]) != inside(q[(i + 1) % 4])) pairs[0][k++] = E[i];
        n_pairs = 1;
      } else if (crossed == 4) {
        // Ambiguous face: cut off each inside corner (edges E[i-1] and E[i] meet at corner q[i]).
        for (int i = 0; i < 4; ++i)
          if (inside(q[i])) pairs[n_pairs++] = {E[(i + 3) % 4], E[i]};
      }
      const int axis = f >> 1;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = (f & 1) ? 1.0 : -1.0;
      for (int p = 0; p < n_pairs; ++p) {
        const int e1 = pairs[p][0], e2 = pairs[p][1];
        const Eigen::Vector3d m1 = edge_mid(e1), m2 = edge_mid(e2), m = 0.5 * (m1 + m2);
        Eigen::Vector3d N;  // in the face plane, from the inside side of the segment to the outside side
        const int c = shared_corner(e1, e2);
        if (c >= 0) {
          N = inside(c) ? Eigen::Vector3d(m - corner_pos(c)) : Eigen::Vector3d(corner_pos(c) - m);
        } else {
          Eigen::Vector3d in = Eigen::Vector3d::Zero(), out = Eigen::Vector3d::Zero();
          for (int i = 0; i < 4; ++i) (inside(q[i]) ? in : out) += corner_pos(q[i]);
          N = out - in;
        }
        // A counter-clockwise boundary (about N) has the polygon, which lies on the -n side of the face,
        // to its left: direction d with d . (N x n) > 0.
        const bool forward = (m2 - m1).dot(N.cross(n)) > 0;
        const int from = forward ? e1 : e2, to = forward ? e2 : e1;
        if (next[from] != -1) throw std::logic_error("cube table: edge with two outgoing segments");
        next[from] = to;
      }
    }
    CubePolygons& P = table[mask];
    std::array<bool, 12> used{};
    int k = 0;
    for (int e = 0; e < kEdges; ++e) {
      if (next[e] < 0 || used[e]) continue;
      P.offset[P.count] = std::uint8_t(k);
      for (int x = e; !used[x]; x = next[x]) {
        if (next[x] < 0) throw std::logic_error("cube table: open polygon");
        used[x] = true;
        P.edges[k++] = std::uint8_t(x);
      }
      ++P.count;
    }
    P.offset[P.count] = std::uint8_t(k);
    for (int p = 0; p < P.count; ++p) {
      if (P.size(p) != 4) continue;
      const auto poly = P.polygon(p);
      if (!edges_share_face(poly[0], poly[2])) P.quad_diagonals |= std::uint8_t(1u << p);
      if (!edges_share_face(poly[1], poly[3])) P.quad_diagonals |= std::uint8_t(1u << (p + 4));
    }
  }
  return table;
}

}  // namespace

int edge_corner(int e, int i) {
  const int a = edge_axis(e), k = e & 3;
  const auto uv = other_axes(a);
  return ((k & 1) << uv[0]) | (((k >> 1) & 1) << uv[1]) | (i << a);
}

std::array<int, 2> edge_faces(int e) {
  const int a = edge_axis(e), k = e & 3;
  const auto uv = other_axes(a);
  return {2 * uv[0] + (k & 1), 2 * uv[1] + ((k >> 1) & 1)};
}

std::array<int, 4> face_corners(int f) {
  const int a = f >> 1, s = f & 1;
  const auto uv = other_axes(a);
  auto corner = [&](int bu, int bv) { return (s << a) | (bu << uv[0]) | (bv << uv[1]); };
  // (u, v) = (0,0), (1,0), (1,1), (0,1) turns about e_u x e_v, which is +x, -y, +z for a = 0, 1, 2.
  const int natural = a == 1 ? -1 : 1, outward = s ? 1 : -1;
  if (natural == outward) return {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
  return {corner(0, 0), corner(0, 1), corner(1, 1), corner(1, 0)};
}

std::array<int, 4> face_edges(int f) {
  const auto q = face_corners(f);
  std::array<int, 4> out{};
  for (int i = 0; i < 4; ++i) {
    const int c0 = q[i], c1 = q[(i + 1) % 4], diff = c0 ^ c1;
    const int a = diff == 1 ? 0 : diff == 2 ? 1 : 2;
    const int lo = c0 & ~diff;
    const auto uv = other_axes(a);
    out[i] = 4 * a + ((lo >> uv[0]) & 1) + 2 * ((lo >> uv[1]) & 1);
  }
  return out;
}

bool edges_share_face(int e0, int e1) {
  const auto f0 = edge_faces(e0), f1 = edge_faces(e1);
  return f0[0] == f1[0] || f0[0] == f1[1] || f0[1] == f1[0] || f0[1] == f1[1];
}

const CubePolygons& cube_polygons(std::uint8_t inside_mask) {
  static const std::array<CubePolygons, 256> table = build_table();
  return table[inside_mask];
}

int face_segments(std::uint8_t inside_mask, int f, std::array<std::array<int, 2>, 2>& out) {
  const CubePolygons& P = cube_polygons(inside_mask);
  int n = 0;
  for (int p = 0; p < P.count; ++p) {
    const auto poly = P.polygon(p);
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const int a = poly[i], b = poly[(i + 1) % poly.size()];
      const auto fa = edge_faces(a);
      const auto fb = edge_faces(b);
      const bool on_f = (fa[0] == f || fa[1] == f) && (fb[0] == f || fb[1] == f);
      if (on_f) out[n++] = {a, b};
    }
  }
  return n;
}

}  // namespace topotrack::cube
