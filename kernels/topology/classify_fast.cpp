#include "kernels/topology/classify_fast.hpp"

#include <algorithm>
#include <bit>

#include "kernels/sdf/cube_table.hpp"

namespace topotrack::topology {
namespace {

constexpr std::uint64_t kNoKey = ~std::uint64_t(0);

// The cell-local name of a piece corner of cell C: (kind, axis, element, plane bits), ordered like PointKey
// (kind, axis and element are PointKey::a; the plane bits order like PointKey::b). kNoKey when a plane is
// not one of the cell's own (never for the cut's pieces; the reference then decides).
std::uint64_t local_key(const PointKey& k, const openvdb::Coord& C) {
  const std::uint64_t head = (k.a >> 60) << 32 | (k.a & 0xffffffffu);  // kind, axis, element
  switch (kind(k)) {
    case PointKind::Vertex:
      return head << 2;
    case PointKind::EdgePoint: {
      const int bit = key_plane(k) - C[key_axis(k)];
      return (bit == 0 || bit == 1) ? head << 2 | std::uint64_t(bit) : kNoKey;
    }
    case PointKind::FacePoint: {
      const int line = key_axis(k), ua = line == 0 ? 1 : 0, va = line == 2 ? 1 : 2;
      const int bu = key_plane_u(k) - C[ua], bv = key_plane_v(k) - C[va];
      return ((bu == 0 || bu == 1) && (bv == 0 || bv == 1)) ? head << 2 | std::uint64_t(2 * bu + bv) : kNoKey;
    }
    default:
      return kNoKey;
  }
}

std::uint8_t find(std::uint8_t* p, std::uint8_t x) {
  while (p[x] != x) x = p[x] = p[p[x]];
  return x;
}

// The reference's face test (classify.cpp, curves_cross) over the boundary edges v -> out[v]: on each cube
// face holding two segments that are not one chain, or more than two, no two segments without a common
// end may cross.
bool curves_cross(const SurfaceMesh& mesh, const LatticeCut& cut, const FastCellScratch& s, int V) {
  constexpr int W = FastCellScratch::kMaxPoints;
  std::uint8_t tails[6][W];
  int count[6] = {0, 0, 0, 0, 0, 0};
  for (int v = 0; v < V; ++v) {
    if (s.out[v] < 0) continue;
    const std::uint8_t t = s.tag[v * W + s.out[v]];
    if (t < 6) tails[t][count[t]++] = std::uint8_t(v);
  }
  Vec3 pos[W];
  std::uint64_t have = 0;
  auto position = [&](int v) -> const Vec3& {
    if (!((have >> v) & 1)) {
      pos[v] = point_position(mesh, cut, cut.keys[s.point_key[v]]);
      have |= std::uint64_t(1) << v;
    }
    return pos[v];
  };
  struct Seg {
    double p[4];
    std::uint8_t a, b;
  };
  Seg seg[W];
  for (int f = 0; f < 6; ++f) {
    const int n = count[f];
    if (n < 2) continue;
    if (n == 2) {
      const int a0 = tails[f][0], b0 = s.out[a0], a1 = tails[f][1], b1 = s.out[a1];
      if (a1 == b0 || b1 == a0) continue;  // one chain of two segments
    }
    const int axis = f >> 1, ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
    for (int i = 0; i < n; ++i) {
      const int v = tails[f][i];
      const Vec3& a = position(v);
      const Vec3& b = position(s.out[v]);
      seg[i] = Seg{{a[ua], a[va], b[ua], b[va]}, std::uint8_t(v), std::uint8_t(s.out[v])};
    }
    for (int i = 0; i < n; ++i)
      for (int j = i + 1; j < n; ++j) {
        const Seg& P = seg[i];
        const Seg& Q = seg[j];
        if (P.a == Q.a || P.a == Q.b || P.b == Q.a || P.b == Q.b) continue;
        if (segments_cross(P.p, Q.p)) return true;
      }
  }
  return false;
}

bool same_cycle(const std::uint8_t* loop, int n, std::span<const std::uint8_t> poly) {
  if (std::size_t(n) != poly.size()) return false;
  int s = 0;
  while (s < n && poly[s] != loop[0]) ++s;
  if (s == n) return false;
  for (int i = 0; i < n; ++i)
    if (poly[(s + i) % n] != loop[i]) return false;
  return true;
}

}  // namespace

std::optional<CellVerdict> classify_cell_fast(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
                                              std::size_t ci, std::uint8_t mask, FastCellScratch& s) {
  using enum CellVerdict;
  constexpr int W = FastCellScratch::kMaxPoints;
  const std::uint32_t pb = index.piece_begin[ci], pe = index.piece_begin[ci + 1];
  if (pb == pe) return mask != 0 && mask != 255 ? kMissed : kSimple;
  const openvdb::Coord C = cell_from_key(index.cells[ci]);
  // Corners, with the next corner of the same piece.
  int n = 0;
  for (std::uint32_t k = pb; k < pe; ++k) {
    const Piece& pc = cut.pieces[index.piece_order[k]];
    if (n + pc.size > FastCellScratch::kMaxCorners) return std::nullopt;
    for (int i = 0; i < pc.size; ++i) {
      const std::uint64_t lk = local_key(cut.keys[pc.begin + i], C);
      if (lk == kNoKey) return std::nullopt;
      s.sorted[n + i] = lk << 8 | std::uint64_t(n + i);
      s.global[n + i] = pc.begin + i;
      s.next[n + i] = std::uint8_t(i + 1 < pc.size ? n + i + 1 : n);
    }
    n += pc.size;
  }
  // Insertion sort: a cell has ~25 corners, below what std::sort's introsort is fast for (2 % of the
  // tracker's ConstrainTopology time went to it); the order is the same (the keys are distinct).
  for (int i = 1; i < n; ++i) {
    const std::uint64_t x = s.sorted[i];
    int j = i;
    for (; j > 0 && s.sorted[j - 1] > x; --j) s.sorted[j] = s.sorted[j - 1];
    s.sorted[j] = x;
  }
  // Point ids: ranks of the distinct keys, as in the reference.
  int V = 0;
  for (int i = 0; i < n; ++i) {
    if (i == 0 || (s.sorted[i] >> 8) != (s.sorted[i - 1] >> 8)) {
      if (V == W) return std::nullopt;
      s.point_key[V++] = s.global[s.sorted[i] & 0xff];
    }
    s.id[s.sorted[i] & 0xff] = std::uint8_t(V - 1);
  }
  std::fill(s.adj, s.adj + V, 0);
  for (int j = 0; j < n; ++j) {
    const int f = s.id[j], t = s.id[s.next[j]];
    const std::uint64_t bit = std::uint64_t(1) << t;
    if (s.adj[f] & bit) return kDuplicateEdge;
    s.adj[f] |= bit;
    s.tag[f * W + t] = cut.tags[s.global[j]];
  }
  // Components, and the boundary edges (no reverse); a point with two outgoing boundary edges is a pinch.
  for (int v = 0; v < V; ++v) s.parent[v] = std::uint8_t(v);
  int components = V, boundary = 0;
  bool pinch = false;
  for (int f = 0; f < V; ++f) {
    s.out[f] = -1;
    for (std::uint64_t bits = s.adj[f]; bits; bits &= bits - 1) {
      const int t = std::countr_zero(bits);
      const std::uint8_t a = find(s.parent, std::uint8_t(f)), b = find(s.parent, std::uint8_t(t));
      if (a != b) {
        s.parent[std::max(a, b)] = std::min(a, b);
        --components;
      }
      if (!((s.adj[t] >> f) & 1)) {
        ++boundary;
        if (s.out[f] >= 0) pinch = true;
        else s.out[f] = std::int8_t(t);
      }
    }
  }
  if (pinch) return kPinch;
  const long E = (long(n) + boundary) / 2;
  const long chi = long(V) - E + long(pe - pb);
  // Boundary loops, started from the boundary edges in order of their tails (the reference's order).
  const cube::CubePolygons& polys = cube::cube_polygons(mask);
  std::uint8_t poly_used[4] = {0, 0, 0, 0};
  std::fill(s.used, s.used + V, 0);
  int loops = 0;
  for (int start = 0; start < V; ++start) {
    if (s.out[start] < 0 || s.used[start]) continue;
    int len = 0, cur = start;
    for (int steps = 0;; ++steps) {
      if (s.used[cur] || steps > boundary) return kBrokenLoop;
      s.used[cur] = 1;
      const int to = s.out[cur];
      if (s.tag[cur * W + to] == kOnMeshEdge) return kMeshBoundary;
      const PointKey& k = cut.keys[s.point_key[cur]];
      if (kind(k) == PointKind::FacePoint) {
        const int line = key_axis(k), ua = line == 0 ? 1 : 0, va = line == 2 ? 1 : 2;
        s.loop[len++] = std::uint8_t(4 * line + (key_plane_u(k) - C[ua]) + 2 * (key_plane_v(k) - C[va]));
      }
      if (s.out[to] < 0) return kBrokenLoop;  // open chain
      cur = to;
      if (cur == start) break;
    }
    if (len == 0) return kLoopInFace;
    int match = -1;
    for (int p = 0; p < polys.count && match < 0; ++p)
      if (!poly_used[p] && same_cycle(s.loop, len, polys.polygon(p))) match = p;
    if (match < 0)
      return crosses_an_edge_twice(std::span<const std::uint8_t>(s.loop, std::size_t(len))) ? kEdgeCrossedTwice
                                                                                           : kUnmatchedLoop;
    poly_used[match] = 1;
    s.loop_root[loops++] = find(s.parent, std::uint8_t(start));
  }
  if (loops != polys.count) return kMissed;
  std::sort(s.loop_root, s.loop_root + loops);
  if (std::adjacent_find(s.loop_root, s.loop_root + loops) != s.loop_root + loops) return kNotDisk;
  if (components != loops) return kNotDisk;
  if (chi != long(loops)) return kNotDisk;
  return boundary > 2 && curves_cross(mesh, cut, s, V) ? kCurvesCross : kSimple;
}

}  // namespace topotrack::topology
