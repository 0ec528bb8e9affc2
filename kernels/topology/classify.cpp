#include "kernels/topology/classify.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <numeric>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include "kernels/mesh/radix_sort.hpp"
#include "kernels/sdf/cube_table.hpp"
#include "kernels/topology/classify_fast.hpp"
#include "kernels/topology/simple_point.hpp"

namespace topotrack::topology {
namespace {

// A directed piece edge between cell-local vertex ids, with the cube face it lies on (or kOnMeshEdge).
struct DirEdge {
  std::uint32_t from, to;
  std::uint8_t tag = kOnMeshEdge;
  bool operator<(const DirEdge& o) const { return from != o.from ? from < o.from : to < o.to; }
};

struct Scratch {
  std::vector<DirEdge> edges, boundary;
  std::vector<PointKey> verts;
  std::vector<std::uint32_t> corner, parent;
  std::vector<std::uint8_t> used;
  std::vector<int> loop;
  std::vector<std::uint32_t> loop_root;
  std::vector<std::array<double, 4>> seg;  // 2D segments on one face
  std::vector<std::array<std::uint32_t, 2>> seg_id;
};

// Whether two of M's cut curves cross on a face of the cell (Wojtan et al. 2009 face test; a crossing
// means two sheets of M intersect there, which the loop matching cannot see).
bool curves_cross(const SurfaceMesh& mesh, const LatticeCut& cut, Scratch& s) {
  for (int f = 0; f < 6; ++f) {
    // Only faces holding two segments that are not one chain can have a crossing.
    int n = 0;
    const DirEdge* first = nullptr;
    bool needed = false;
    for (const DirEdge& e : s.boundary) {
      if (e.tag != f) continue;
      if (++n == 1) first = &e;
      else if (n > 2 || (e.from != first->to && e.to != first->from)) needed = true;
    }
    if (!needed) continue;
    const int axis = f >> 1, ua = axis == 0 ? 1 : 0, va = axis == 2 ? 1 : 2;
    s.seg.clear();
    s.seg_id.clear();
    for (const DirEdge& e : s.boundary) {
      if (e.tag != f) continue;
      const Vec3 a = point_position(mesh, cut.P, s.verts[e.from]), b = point_position(mesh, cut.P, s.verts[e.to]);
      s.seg.push_back({a[ua], a[va], b[ua], b[va]});
      s.seg_id.push_back({e.from, e.to});
    }
    for (std::size_t i = 0; i < s.seg.size(); ++i)
      for (std::size_t j = i + 1; j < s.seg.size(); ++j) {
        const auto& ki = s.seg_id[i];
        const auto& kj = s.seg_id[j];
        if (ki[0] == kj[0] || ki[0] == kj[1] || ki[1] == kj[0] || ki[1] == kj[1]) continue;
        if (segments_cross(s.seg[i].data(), s.seg[j].data())) return true;
      }
  }
  return false;
}

std::uint32_t find(std::vector<std::uint32_t>& p, std::uint32_t x) {
  while (p[x] != x) x = p[x] = p[p[x]];
  return x;
}

// The cube edge of cell `c` that a face point lies on, or -1.
int cube_edge_of(const PointKey& k, const openvdb::Coord& c) {
  const int line = key_axis(k);
  const int ua = line == 0 ? 1 : 0, va = line == 2 ? 1 : 2;
  const int bu = key_plane_u(k) - c[ua], bv = key_plane_v(k) - c[va];
  if ((bu != 0 && bu != 1) || (bv != 0 && bv != 1)) return -1;
  return 4 * line + bu + 2 * bv;
}

bool same_cycle(const std::vector<int>& loop, std::span<const std::uint8_t> poly) {
  const std::size_t n = poly.size();
  if (loop.size() != n) return false;
  std::size_t s = 0;
  while (s < n && poly[s] != loop[0]) ++s;
  if (s == n) return false;
  for (std::size_t i = 0; i < n; ++i)
    if (poly[(s + i) % n] != loop[i]) return false;
  return true;
}

CellVerdict classify_cell(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index, std::size_t ci,
                          std::uint8_t mask, Scratch& s) {
  using enum CellVerdict;
  const std::uint32_t pb = index.piece_begin[ci], pe = index.piece_begin[ci + 1];
  if (pb == pe) return mask != 0 && mask != 255 ? kMissed : kSimple;
  const openvdb::Coord C = cell_from_key(index.cells[ci]);
  // Cell-local vertex ids.
  s.verts.clear();
  for (std::uint32_t k = pb; k < pe; ++k) {
    const Piece& pc = cut.pieces[index.piece_order[k]];
    s.verts.insert(s.verts.end(), cut.keys.begin() + pc.begin, cut.keys.begin() + pc.begin + pc.size);
  }
  s.corner.resize(s.verts.size());
  std::sort(s.verts.begin(), s.verts.end());
  s.verts.erase(std::unique(s.verts.begin(), s.verts.end()), s.verts.end());
  const std::size_t V = s.verts.size();
  s.edges.clear();
  {
    std::size_t c = 0;
    for (std::uint32_t k = pb; k < pe; ++k) {
      const Piece& pc = cut.pieces[index.piece_order[k]];
      const std::size_t c0 = c;
      for (int i = 0; i < pc.size; ++i)
        s.corner[c++] = std::uint32_t(std::lower_bound(s.verts.begin(), s.verts.end(), cut.keys[pc.begin + i]) -
                                      s.verts.begin());
      for (int i = 0; i < pc.size; ++i)
        s.edges.push_back({s.corner[c0 + i], s.corner[c0 + (i + 1) % pc.size], cut.tags[pc.begin + i]});
    }
  }
  std::sort(s.edges.begin(), s.edges.end());
  for (std::size_t i = 1; i < s.edges.size(); ++i)
    if (s.edges[i].from == s.edges[i - 1].from && s.edges[i].to == s.edges[i - 1].to) return kDuplicateEdge;
  s.parent.resize(V);
  std::iota(s.parent.begin(), s.parent.end(), 0u);
  s.boundary.clear();
  std::size_t components = V;
  for (const DirEdge& e : s.edges) {
    const std::uint32_t a = find(s.parent, e.from), b = find(s.parent, e.to);
    if (a != b) {
      s.parent[std::max(a, b)] = std::min(a, b);
      --components;
    }
    if (!std::binary_search(s.edges.begin(), s.edges.end(), DirEdge{e.to, e.from, 0})) s.boundary.push_back(e);
  }
  const std::size_t E = (s.edges.size() + s.boundary.size()) / 2;
  const long chi = long(V) - long(E) + long(pe - pb);
  // Boundary loops; s.boundary is sorted by `from`. A vertex with two outgoing boundary edges is a pinch.
  for (std::size_t i = 1; i < s.boundary.size(); ++i)
    if (s.boundary[i].from == s.boundary[i - 1].from) return kPinch;
  const cube::CubePolygons& polys = cube::cube_polygons(mask);
  s.used.assign(s.boundary.size() + polys.count, 0);
  std::uint8_t* poly_used = s.used.data() + s.boundary.size();
  s.loop_root.clear();
  for (std::size_t start = 0; start < s.boundary.size(); ++start) {
    if (s.used[start]) continue;
    s.loop.clear();
    std::size_t cur = start;
    for (std::size_t steps = 0;; ++steps) {
      if (s.used[cur] || steps > s.boundary.size()) return kBrokenLoop;
      s.used[cur] = 1;
      if (s.boundary[cur].tag == kOnMeshEdge) return kMeshBoundary;
      const PointKey& k = s.verts[s.boundary[cur].from];
      if (kind(k) == PointKind::FacePoint) {
        const int e = cube_edge_of(k, C);
        if (e < 0) return kBrokenLoop;
        s.loop.push_back(e);
      }
      const auto it = std::lower_bound(s.boundary.begin(), s.boundary.end(), DirEdge{s.boundary[cur].to, 0, 0});
      if (it == s.boundary.end() || it->from != s.boundary[cur].to) return kBrokenLoop;  // open chain
      cur = std::size_t(it - s.boundary.begin());
      if (cur == start) break;
    }
    if (s.loop.empty()) return kLoopInFace;
    int match = -1;
    for (int p = 0; p < polys.count && match < 0; ++p)
      if (!poly_used[p] && same_cycle(s.loop, polys.polygon(p))) match = p;
    if (match < 0) return crosses_an_edge_twice(std::span<const int>(s.loop)) ? kEdgeCrossedTwice : kUnmatchedLoop;
    poly_used[match] = 1;
    s.loop_root.push_back(find(s.parent, s.boundary[start].from));
  }
  if (s.loop_root.size() != polys.count) return kMissed;
  // One loop per component and every component a disk.
  std::sort(s.loop_root.begin(), s.loop_root.end());
  if (std::adjacent_find(s.loop_root.begin(), s.loop_root.end()) != s.loop_root.end()) return kNotDisk;
  if (components != s.loop_root.size()) return kNotDisk;
  if (chi != long(s.loop_root.size())) return kNotDisk;
  return s.boundary.size() > 2 && curves_cross(mesh, cut, s) ? kCurvesCross : kSimple;
}

}  // namespace

std::pair<std::uint32_t, std::uint32_t> CellIndex::pieces_of(std::uint64_t cell) const {
  const auto it = std::lower_bound(cells.begin(), cells.end(), cell);
  if (it == cells.end() || *it != cell) return {0, 0};
  const std::size_t i = std::size_t(it - cells.begin());
  return {piece_begin[i], piece_begin[i + 1]};
}

bool CellIndex::is_flipped(const openvdb::Coord& node) const {
  return !flipped.empty() && std::binary_search(flipped.begin(), flipped.end(), cell_key(node));
}

float node_value(const openvdb::FloatGrid::ConstAccessor& acc, const CellIndex& index, const openvdb::Coord& node) {
  const float v = acc.getValue(node);
  if (!index.is_flipped(node)) return v;
  return v < 0.f ? -v : (v > 0.f ? -v : -std::numeric_limits<float>::min());
}

std::uint8_t theta_mask(const openvdb::FloatGrid::ConstAccessor& acc, const CellIndex& index, const openvdb::Coord& cell) {
  std::uint8_t m = 0;
  for (int c = 0; c < 8; ++c)
    if (node_value(acc, index, cell.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1)) < 0.f) m |= std::uint8_t(1u << c);
  return m;
}

namespace {

// The number of M's crossings of the six lattice edges at each node of `near` (sorted keys): entry 6 i + s
// for node near[i] and the edge to its neighbour along axis s / 2, downwards when s is even. A crossing is a
// face point of a piece: one pass over the pieces (in order, cache-friendly), each face point looked up in a
// hash table of the near nodes, then the distinct (edge, face) pairs counted.
std::vector<std::uint32_t> near_edge_crossings(const LatticeCut& cut, const std::vector<std::uint64_t>& near) {
  std::vector<std::uint32_t> count(near.size() * 6, 0);
  if (near.empty()) return count;
  int bits = 4;
  while ((std::size_t(1) << bits) < 4 * near.size()) ++bits;
  const std::uint64_t mask = (std::uint64_t(1) << bits) - 1, empty = ~std::uint64_t(0);
  std::vector<std::uint64_t> table_key(mask + 1, empty);
  std::vector<std::uint32_t> table_index(mask + 1, 0);
  auto slot = [&](std::uint64_t k) { return (k * 0x9E3779B97F4A7C15ull) >> (64 - bits); };
  for (std::size_t i = 0; i < near.size(); ++i) {
    std::uint64_t h = slot(near[i]);
    while (table_key[h] != empty) h = (h + 1) & mask;
    table_key[h] = near[i];
    table_index[h] = std::uint32_t(i);
  }
  auto find_near = [&](std::uint64_t k) -> std::int64_t {
    for (std::uint64_t h = slot(k);; h = (h + 1) & mask) {
      if (table_key[h] == k) return table_index[h];
      if (table_key[h] == empty) return -1;
    }
  };
  constexpr std::size_t kChunk = 16384;
  const std::size_t np = cut.pieces.size(), n_chunks = (np + kChunk - 1) / kChunk;
  std::vector<std::vector<std::uint64_t>> found(n_chunks);  // (edge slot << 32) | face
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c)
      for (std::size_t p = c * kChunk; p < std::min(np, (c + 1) * kChunk); ++p) {
        const Piece& pc = cut.pieces[p];
        for (int i = 0; i < pc.size; ++i) {
          const PointKey& k = cut.keys[pc.begin + i];
          if (kind(k) != PointKind::FacePoint) continue;
          // On the lattice edge along L from node lo (the piece's cell's own coordinate along L) to lo + 1.
          const int L = key_axis(k), ua = L == 0 ? 1 : 0, va = L == 2 ? 1 : 2;
          openvdb::Coord lo = cell_from_key(pc.cell);
          lo[ua] = key_plane_u(k);
          lo[va] = key_plane_v(k);
          openvdb::Coord hi = lo;
          hi[L] += 1;
          if (const std::int64_t a = find_near(cell_key(lo)); a >= 0)
            found[c].push_back(std::uint64_t(6 * a + 2 * L + 1) << 32 | key_element(k));
          if (const std::int64_t b = find_near(cell_key(hi)); b >= 0)
            found[c].push_back(std::uint64_t(6 * b + 2 * L) << 32 | key_element(k));
        }
      }
  });
  std::vector<std::uint64_t> all;
  for (const auto& f : found) all.insert(all.end(), f.begin(), f.end());
  tbb::parallel_sort(all.begin(), all.end());
  all.erase(std::unique(all.begin(), all.end()), all.end());
  for (std::uint64_t e : all) ++count[e >> 32];
  return count;
}

// Whether node `n` (|Θ| < kSignTolerance voxels) is inside, from its lattice-edge neighbours farther from
// the zero set and the parity of M's crossings of the edges to them (`crossings`, see near_edge_crossings
// and kSignTolerance); `raw` when they disagree or there is none.
bool resolve_node_sign(const openvdb::FloatGrid::ConstAccessor& acc, const openvdb::Coord& n, float tol, bool raw,
                       const std::uint32_t* crossings) {
  int votes[2] = {0, 0};
  for (int s = 0; s < 6; ++s) {
    const int L = s >> 1;
    openvdb::Coord m = n;
    m[L] += (s & 1) ? 1 : -1;
    const float vm = acc.getValue(m);
    if (!(std::abs(vm) >= tol)) continue;
    ++votes[int((vm < 0.f) != (crossings[s] % 2 == 1))];
  }
  if (votes[0] > 0 && votes[1] == 0) return false;
  if (votes[1] > 0 && votes[0] == 0) return true;
  return raw;
}

struct CellPiece {
  std::uint64_t first;   // cell key
  std::uint32_t second;  // piece
  bool operator<(const CellPiece& o) const { return first != o.first ? first < o.first : second < o.second; }
};

// The (cell, piece) pairs of the cut sorted. When the cells' extent allows, each pair is packed into one
// 64-bit word (cell coordinates relative to their minimum, in as many bits as their range needs, then the
// piece index), which sorts about twice as fast as the 16-byte pairs; the order is the same.
HugeVector<CellPiece> pieces_by_cell(const LatticeCut& cut) {
  const std::size_t np = cut.pieces.size();
  HugeVector<CellPiece> out(np);
  constexpr std::uint64_t kField = (std::uint64_t(1) << 21) - 1;
  constexpr int kShiftOf[3] = {42, 21, 0};
  using Range = std::array<std::uint64_t, 6>;  // lo x, y, z, hi x, y, z of the key fields
  const Range range = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, np, 16384), Range{kField, kField, kField, 0, 0, 0},
      [&](const tbb::blocked_range<std::size_t>& r, Range acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i)
          for (int a = 0; a < 3; ++a) {
            const std::uint64_t f = (cut.pieces[i].cell >> kShiftOf[a]) & kField;
            acc[a] = std::min(acc[a], f);
            acc[3 + a] = std::max(acc[3 + a], f);
          }
        return acc;
      },
      [](Range x, const Range& y) {
        for (int a = 0; a < 3; ++a) x[a] = std::min(x[a], y[a]), x[3 + a] = std::max(x[3 + a], y[3 + a]);
        return x;
      });
  auto width = [](std::uint64_t v) { return v == 0 ? 0 : 64 - std::countl_zero(v); };
  int w[3] = {0, 0, 0};
  for (int a = 0; a < 3; ++a) w[a] = np ? width(range[3 + a] - range[a]) : 0;
  const int wp = np ? width(np - 1) : 0;
  if (w[0] + w[1] + w[2] + wp > 64) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = {cut.pieces[i].cell, std::uint32_t(i)};
    });
    tbb::parallel_sort(out.begin(), out.end());
    return out;
  }
  const int sp = wp, sz = sp + w[2], sy = sz + w[1];
  auto shl = [](std::uint64_t v, int shift) { return shift >= 64 ? std::uint64_t(0) : v << shift; };
  HugeVector<std::uint64_t> packed(np);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint64_t k = cut.pieces[i].cell;
      packed[i] = shl(((k >> 42) & kField) - range[0], sy) | shl(((k >> 21) & kField) - range[1], sz) |
                  shl((k & kField) - range[2], sp) | std::uint64_t(i);
    }
  });
  {
    HugeVector<std::uint64_t> scratch(np);
    radix_sort(packed, scratch);
  }
  const std::uint64_t piece_mask = wp == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << wp) - 1;
  auto field = [](std::uint64_t v, int shift, int bits) {
    return bits == 0 || shift >= 64 ? std::uint64_t(0) : (v >> shift) & ((std::uint64_t(1) << bits) - 1);
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, np, 8192), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint64_t v = packed[i];
      const std::uint64_t cell = (field(v, sy, w[0]) + range[0]) << 42 | (field(v, sz, w[1]) + range[1]) << 21 |
                                 (field(v, sp, w[2]) + range[2]);
      out[i] = {cell, std::uint32_t(v & piece_mask)};
    }
  });
  return out;
}

}  // namespace

CellIndex index_cells(const LatticeCut& cut, const openvdb::FloatGrid& theta, bool flips_keep_topology,
                      const openvdb::MaskGrid* only) {
  CellIndex idx;
  HugeVector<CellPiece> by_cell = pieces_by_cell(cut);
  if (only) {
    auto acc = only->getConstAccessor();
    std::size_t kept = 0;
    for (std::size_t i = 0; i < by_cell.size(); ++i)
      if (acc.isValueOn(cell_from_key(by_cell[i].first))) by_cell[kept++] = by_cell[i];
    by_cell.resize(kept);
  }
  const std::size_t np = by_cell.size();

  // Θ's sign-change cells and the nodes near its zero set, per leaf node.
  std::vector<const openvdb::FloatTree::LeafNodeType*> leaves;
  theta.tree().getNodes(leaves);
  std::vector<std::vector<std::uint64_t>> leaf_cells(leaves.size()), leaf_near(leaves.size());
  const float tol = float(kSignTolerance * theta.voxelSize()[0]);
  const CellIndex raw;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    auto acc = theta.getConstAccessor();
    // Offsets of the eight corners of a cell within a leaf (x * 64 + y * 8 + z), in corner order.
    constexpr int kCornerOffset[8] = {0, 64, 8, 72, 1, 65, 9, 73};
    // A cell whose minimum corner is inactive is not visited below, yet it can change sign: Θ need not be a
    // distance (the tracker's agree_near_surface gives nodes of φ_S φ_M's value, up to several voxels from
    // their neighbours' distances). Left out, such a cell counts as simple without ever being examined, and
    // the replacement next to it fails for want of M's crossing on its lattice edge (the complex region
    // then grows by whole layers). So every lattice edge with an active end whose ends differ in sign adds
    // the cells around it that have an inactive minimum corner.
    // `leaf`, `off`: a's leaf and offset in it when a is in the leaf being visited (its nodes' activity is read
    // from the leaf's mask, which is most of them), else null.
    constexpr int kStride[3] = {64, 8, 1};
    auto add_cells_around = [&](std::vector<std::uint64_t>& out, openvdb::Coord a, int L,
                                const openvdb::FloatTree::LeafNodeType* leaf, openvdb::Index off) {
      const int ua = L == 0 ? 1 : 0, va = L == 2 ? 1 : 2;
      const openvdb::Coord local = leaf ? a - leaf->origin() : openvdb::Coord();
      for (int d = 1; d < 4; ++d) {  // d = 0 is the cell with minimum corner a
        openvdb::Coord p = a;
        p[ua] -= d & 1;
        p[va] -= d >> 1;
        const bool in_leaf = leaf && local[ua] >= (d & 1) && local[va] >= (d >> 1);
        const bool on = in_leaf ? leaf->isValueOn(off - (d & 1) * kStride[ua] - (d >> 1) * kStride[va])
                                : acc.isValueOn(p);
        if (!on) out.push_back(cell_key(p));
      }
      if (!leaf && !acc.isValueOn(a)) out.push_back(cell_key(a));
    };
    for (std::size_t l = r.begin(); l != r.end(); ++l) {
      // A leaf none of whose cells (nor the cells just below it, which its nodes are corners of) is to be
      // indexed: skipped.
      if (only && !box_touches(only->tree(), leaves[l]->origin().offsetBy(-1), leaves[l]->origin().offsetBy(7)))
        continue;
      const float* buf = leaves[l]->buffer().data();
      for (auto it = leaves[l]->cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        bool in_range = true;
        for (int a = 0; a < 3; ++a) in_range = in_range && std::abs(c[a]) < kCellRange - 4;
        if (!in_range) continue;
        const float v = *it;
        if (std::abs(v) < tol) leaf_near[l].push_back(cell_key(c));
        // The cell's corners from the leaf's own buffer when they are all in it (getValue reads the same).
        const auto off = it.pos();
        std::uint8_t m = 0;
        if ((off >> 6) < 7 && ((off >> 3) & 7) < 7 && (off & 7) < 7) {
          for (int k = 0; k < 8; ++k)
            if (buf[off + kCornerOffset[k]] < 0.f) m |= std::uint8_t(1u << k);
        } else {
          m = theta_mask(acc, raw, c);
        }
        if (m != 0 && m != 255) leaf_cells[l].push_back(cell_key(c));
        // Corners 1, 2 and 4 are the neighbours along x, y and z: the edges upwards from c.
        const bool in = v < 0.f;
        for (int L = 0; L < 3; ++L) {
          if (bool(m & (1u << (1 << L))) != in) add_cells_around(leaf_cells[l], c, L, leaves[l], off);
          // The node below along L: from the leaf itself when it is in it (most are).
          const int local = L == 0 ? int(off >> 6) : L == 1 ? int((off >> 3) & 7) : int(off & 7);
          openvdb::Coord below = c;
          below[L] -= 1;
          const bool on = local > 0 ? leaves[l]->isValueOn(off - kStride[L]) : acc.isValueOn(below);
          if (on) continue;
          const float vb = local > 0 ? buf[off - kStride[L]] : acc.getValue(below);
          if ((vb < 0.f) != in) add_cells_around(leaf_cells[l], below, L, nullptr, 0);
        }
      }
    }
  });
  std::vector<std::uint64_t> near;
  for (const auto& v : leaf_near) near.insert(near.end(), v.begin(), v.end());
  std::sort(near.begin(), near.end());
  std::vector<std::uint8_t> flip(near.size(), 0);
  const std::vector<std::uint32_t> crossings = near_edge_crossings(cut, near);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, near.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    auto acc = theta.getConstAccessor();
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const openvdb::Coord n = cell_from_key(near[i]);
      const bool inside = acc.getValue(n) < 0.f;
      flip[i] = resolve_node_sign(acc, n, tol, inside, crossings.data() + 6 * i) != inside;
    }
  });
  // Only flips that keep Θ's topology (simple_point.hpp), taken in key order so the result does not depend
  // on the thread count: a node within kSignTolerance of a thin gap or a thin sheet of Θ, where M still
  // runs across (M has not split yet), would otherwise take M's side, close the gap, and keep M from taking
  // Θ's topology (resurfaced pcow, capture profile, the first 28 frames: in 31 of 56 calls of
  // ConstrainTopology(M, φ_S) M came out with another topology than φ_S's marching-cubes surface that way;
  // in none since). A flip left out leaves the cells around the node complex, and M is resampled there.
  // There are a few hundred candidates a call: sequential is simplest.
  {
    auto acc = theta.getConstAccessor();
    for (std::size_t i = 0; i < near.size(); ++i) {
      if (!flip[i]) continue;
      const openvdb::Coord n = cell_from_key(near[i]);
      NodeBlock inside;
      for (int a = 0; a < 27; ++a) {
        const openvdb::Coord q = n.offsetBy(a % 3 - 1, a / 3 % 3 - 1, a / 9 - 1);
        // idx.flipped holds the flips taken so far, in key order: sorted.
        const bool flipped = std::binary_search(idx.flipped.begin(), idx.flipped.end(), cell_key(q));
        inside[a] = (acc.getValue(q) < 0.f) != flipped;
      }
      if (!flips_keep_topology || simple_node(inside)) idx.flipped.push_back(near[i]);
      else flip[i] = 0;
    }
  }
  std::vector<std::uint64_t> sign_cells;
  for (const auto& v : leaf_cells) sign_cells.insert(sign_cells.end(), v.begin(), v.end());
  for (std::size_t i = 0; i < near.size(); ++i) {
    if (!flip[i]) continue;
    const openvdb::Coord n = cell_from_key(near[i]);
    for (int d = 0; d < 8; ++d) sign_cells.push_back(cell_key(n.offsetBy(-(d & 1), -((d >> 1) & 1), -((d >> 2) & 1))));
  }
  {
    HugeVector<std::uint64_t> scratch(sign_cells.size());
    radix_sort(sign_cells, scratch);
  }
  sign_cells.erase(std::unique(sign_cells.begin(), sign_cells.end()), sign_cells.end());
  if (only) {
    auto acc = only->getConstAccessor();
    std::erase_if(sign_cells, [&](std::uint64_t c) { return !acc.isValueOn(cell_from_key(c)); });
  }

  idx.cells.reserve(sign_cells.size() + np / 2);
  idx.piece_order.resize(np);
  idx.piece_begin.reserve(sign_cells.size() + np / 2 + 1);
  std::size_t i = 0, j = 0;
  while (i < np || j < sign_cells.size()) {
    const auto& by = by_cell;
    const std::uint64_t c = (j == sign_cells.size() || (i < np && by[i].first <= sign_cells[j])) ? by[i].first
                                                                                                  : sign_cells[j];
    idx.cells.push_back(c);
    idx.piece_begin.push_back(std::uint32_t(i));
    while (i < np && by[i].first == c) {
      idx.piece_order[i] = by[i].second;
      ++i;
    }
    while (j < sign_cells.size() && sign_cells[j] == c) ++j;
  }
  idx.piece_begin.push_back(std::uint32_t(np));
  return idx;
}

std::vector<CellVerdict> classify_cells(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
                                       const openvdb::FloatGrid& theta, ClassifyPath path) {
  const std::size_t n = index.cells.size();
  std::vector<CellVerdict> verdict(n, CellVerdict::kSimple);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    auto acc = theta.getConstAccessor();
    Scratch s;
    std::unique_ptr<FastCellScratch> fs;
    if (path == ClassifyPath::kFast) fs = std::make_unique<FastCellScratch>();
    // The pieces of a cell come from scattered faces: fetch them a few cells ahead (the test is bound by
    // these reads, not by its arithmetic).
    auto prefetch = [&](std::size_t j, bool keys) {
      if (j >= r.end()) return;
      for (std::uint32_t k = index.piece_begin[j]; k < index.piece_begin[j + 1]; ++k) {
        const Piece* pc = &cut.pieces[index.piece_order[k]];
        if (!keys) {
          __builtin_prefetch(pc);
          continue;
        }
        __builtin_prefetch(&cut.keys[pc->begin]);
        __builtin_prefetch(&cut.keys[pc->begin] + pc->size - 1);
        __builtin_prefetch(&cut.tags[pc->begin]);
      }
    };
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      if (fs) {
        prefetch(i + 8, false);
        prefetch(i + 4, true);
      }
      const std::uint8_t mask = theta_mask(acc, index, cell_from_key(index.cells[i]));
      std::optional<CellVerdict> v;
      if (fs) v = classify_cell_fast(mesh, cut, index, i, mask, *fs);
      verdict[i] = v ? *v : classify_cell(mesh, cut, index, i, mask, s);
    }
  });
  return verdict;
}

const char* verdict_name(CellVerdict v) {
  static constexpr const char* kNames[kVerdictKinds] = {
      "simple",       "missed",         "duplicate_edge", "pinch",        "mesh_boundary",     "broken_loop",
      "loop_in_face", "unmatched_loop", "not_disk",       "curves_cross", "edge_crossed_twice"};
  const int i = int(v);
  return i >= 0 && i < kVerdictKinds ? kNames[i] : "unknown";
}

std::vector<std::uint64_t> complex_cells(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
                                         const openvdb::FloatGrid& theta, ClassifyPath path, VerdictCounts* by_verdict) {
  const std::vector<CellVerdict> verdict = classify_cells(mesh, cut, index, theta, path);
  if (by_verdict) {
    by_verdict->fill(0);
    for (const CellVerdict v : verdict) ++(*by_verdict)[int(v)];
  }
  std::vector<std::uint64_t> out;
  for (std::size_t i = 0; i < verdict.size(); ++i)
    if (verdict[i] != CellVerdict::kSimple) out.push_back(index.cells[i]);
  for (const auto& box : cut.bad_boxes)
    for (int x = box[0].x(); x <= box[1].x(); ++x)
      for (int y = box[0].y(); y <= box[1].y(); ++y)
        for (int z = box[0].z(); z <= box[1].z(); ++z) out.push_back(cell_key(openvdb::Coord(x, y, z)));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace topotrack::topology
