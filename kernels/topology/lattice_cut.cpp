#include "kernels/topology/lattice_cut.hpp"

#include <algorithm>
#include <cmath>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "io/error.hpp"

namespace topotrack::topology {
namespace {

constexpr std::uint64_t kPlaneBias = std::uint64_t(1) << 31;
constexpr std::int64_t kCellBias = std::int64_t(1) << 20;

// The carrier of a polygon edge: a mesh edge (axis < 0, value = edge index) or a lattice plane inside
// the face (axis, value = plane).
struct Carrier {
  int axis = -1;
  int value = 0;
};
struct PV {
  PointKey key;
  Vec3 p;
  Carrier c;  // of the edge from this corner to the next
};
// A clipped polygon in place (no allocation): a triangle cut by the planes of its cells has at most 9
// corners; kCapacity leaves room, and an overflow is reported as a bad face like any inconsistency.
struct Poly {
  static constexpr int kCapacity = 16;
  std::array<PV, kCapacity> v;
  int n = 0;
  Poly() = default;
  Poly(const Poly& o) { *this = o; }
  Poly& operator=(const Poly& o) {
    n = o.n;
    std::copy(o.v.begin(), o.v.begin() + n, v.begin());
    return *this;
  }
  void swap(Poly& o) {
    for (int i = 0, m = std::max(n, o.n); i < m; ++i) std::swap(v[std::size_t(i)], o.v[std::size_t(i)]);
    std::swap(n, o.n);
  }
  void clear() { n = 0; }
  bool empty() const { return n == 0; }
  std::size_t size() const { return std::size_t(n); }
  const PV& operator[](std::size_t i) const { return v[i]; }
  const PV* begin() const { return v.data(); }
  const PV* end() const { return v.data() + n; }
  bool push_back(const PV& x) {
    if (n == kCapacity) return false;
    v[std::size_t(n++)] = x;
    return true;
  }
};

// The position of an edge point on the edge from pu to pv (the mesh edge's own vertex order) and of a face
// point in the triangle A, B, C (SurfaceMesh::vertices order): the one canonical arithmetic, shared by the
// clipper and point_position so that every caller gets bit-identical positions.
Vec3 edge_point_at(const Vec3& pu, const Vec3& pv, int axis, double plane, double* t_out) {
  double t = (plane - pu[axis]) / (pv[axis] - pu[axis]);
  if (!std::isfinite(t)) t = 0.5;
  t = std::clamp(t, 0.0, 1.0);
  Vec3 x = pu + t * (pv - pu);
  x[axis] = plane;
  if (t_out) *t_out = t;
  return x;
}
Vec3 face_point_at(const Vec3& A, const Vec3& B, const Vec3& C, const PointKey& key, std::array<double, 3>* w_out) {
  const int line = key_axis(key);
  const int ua = line == 0 ? 1 : 0, va = line == 2 ? 1 : 2;
  const double qu = key_plane_u(key), qv = key_plane_v(key);
  const double b1u = B[ua] - A[ua], b1v = B[va] - A[va], c1u = C[ua] - A[ua], c1v = C[va] - A[va];
  const double du = qu - A[ua], dv = qv - A[va];
  const double det = b1u * c1v - c1u * b1v;
  double s = 1.0 / 3, r = 1.0 / 3;
  if (std::abs(det) > 1e-300) {
    s = (du * c1v - c1u * dv) / det;
    r = (b1u * dv - du * b1v) / det;
  }
  if (!std::isfinite(s) || !std::isfinite(r)) s = r = 1.0 / 3;
  std::array<double, 3> w{1.0 - s - r, s, r};
  double sum = 0;
  for (double& x : w) sum += (x = std::max(0.0, x));
  for (double& x : w) x = sum > 0 ? x / sum : 1.0 / 3;
  Vec3 x = w[0] * A + w[1] * B + w[2] * C;
  x[ua] = qu;
  x[va] = qv;
  if (w_out) *w_out = w;
  return x;
}

struct Clipper {
  const SurfaceMesh& mesh;
  const std::vector<Vec3>& P;
  Index face;
  std::array<Index, 3> fv;  // the face's vertices, SurfaceMesh::vertices order
  bool bad = false;

  PV crossing(const Carrier& c, int axis, int plane) const {
    PV x;
    if (c.axis < 0) {
      const Edge e{Index(c.value)};
      x.key = edge_point_key(e.idx, axis, plane);
      x.p = edge_point_at(P[mesh.vertex(e, 0).idx], P[mesh.vertex(e, 1).idx], axis, plane, nullptr);
    } else {
      const int line = 3 - c.axis - axis;
      const int a0 = std::min(c.axis, axis);
      const int pu = a0 == c.axis ? c.value : plane, pv = a0 == c.axis ? plane : c.value;
      x.key = face_point_key(face, line, pu, pv);
      x.p = face_point_at(P[fv[0]], P[fv[1]], P[fv[2]], x.key, nullptr);
    }
    return x;
  }
  void push(Poly& poly, const PV& x) { bad = !poly.push_back(x) || bad; }

  // Split `in` by the plane into the part below (coordinate < plane) and the part above.
  void split(const Poly& in, int axis, int plane, Poly& below, Poly& above) {
    below.clear();
    above.clear();
    const std::size_t n = in.size();
    int changes = 0;
    for (std::size_t i = 0; i < n; ++i)
      changes += (in[i].p[axis] >= plane) != (in[(i + 1) % n].p[axis] >= plane);
    if (changes == 0) {
      (in[0].p[axis] >= plane ? above : below) = in;
      return;
    }
    if (changes != 2) {
      bad = true;
      return;
    }
    for (std::size_t i = 0; i < n; ++i) {
      const PV& a = in[i];
      const PV& b = in[(i + 1) % n];
      const bool sa = a.p[axis] >= plane, sb = b.p[axis] >= plane;
      push(sa ? above : below, a);
      if (sa != sb) {
        PV x = crossing(a.c, axis, plane);
        PV xa = x, xb = x;
        xa.c = Carrier{axis, plane};  // on a's side the cut runs along the plane to the other crossing
        xb.c = a.c;                   // on b's side the rest of a's edge follows
        push(sa ? above : below, xa);
        push(sb ? above : below, xb);
      }
    }
  }
};

// Reused buffers of one chunk's clipping (no allocation per face once warm).
struct ClipScratch {
  Poly tri, below, above, rest;
  std::vector<Poly> xs, ys;  // slabs and bars, first nx / ny used
  std::vector<int> xc, yc;
};

// A chunk writes its corners straight into its own range of the cut's arrays (`key_cap` entries from
// `keys` / `tags`), so that they need no copying afterwards; corners beyond that range go to `spill_*`, and
// the cut then concatenates (never seen: the range allows 20 corners per face, about 18 are used).
struct Chunk {
  ClipScratch scratch;
  HugeVector<Piece> pieces;  // Piece::begin relative to the chunk's first corner
  std::vector<std::uint32_t> face_count;  // pieces per face of the chunk
  PointKey* keys = nullptr;
  std::uint8_t* tags = nullptr;
  std::size_t key_cap = 0, n_keys = 0;
  HugeVector<PointKey> spill_keys;
  HugeVector<std::uint8_t> spill_tags;
  std::vector<Index> bad_faces;
  std::vector<std::array<openvdb::Coord, 2>> bad_boxes;

  void push(const PointKey& k, std::uint8_t tag) {
    if (n_keys < key_cap) {
      keys[n_keys] = k;
      tags[n_keys] = tag;
    } else {
      spill_keys.push_back(k);
      spill_tags.push_back(tag);
    }
    ++n_keys;
  }
  void truncate(std::size_t n) {
    n_keys = n;
    const std::size_t spilled = n > key_cap ? n - key_cap : 0;
    spill_keys.resize(spilled);
    spill_tags.resize(spilled);
  }
};

int cell_of(double x) { return int(std::floor(x)); }

void emit(Chunk& out, Index f, const openvdb::Coord& cell, const Poly& poly) {
  Piece pc;
  pc.cell = cell_key(cell);
  pc.face = f;
  pc.begin = std::uint32_t(out.n_keys);
  pc.size = std::uint8_t(poly.size());
  for (const PV& v : poly)
    out.push(v.key, v.c.axis < 0 ? kOnMeshEdge : std::uint8_t(2 * v.c.axis + (v.c.value - cell[v.c.axis])));
  out.pieces.push_back(pc);
}

// Clip one face into its cell pieces, axis by axis, planes in increasing order.
void clip_face(const SurfaceMesh& mesh, const std::vector<Vec3>& P, Index f, Chunk& out, std::array<Index, 3>& fv) {
  Poly& tri = out.scratch.tri;
  tri.clear();
  Halfedge h = mesh.halfedge(Face(f));
  for (int i = 0; i < 3; ++i, h = mesh.next(h)) {
    const Vertex v = mesh.from_vertex(h);
    fv[std::size_t(i)] = v.idx;
    tri.push_back(PV{vertex_key(v.idx), P[v.idx], Carrier{-1, int(SurfaceMesh::edge(h).idx)}});
  }
  std::array<int, 3> lo, hi;
  for (int a = 0; a < 3; ++a) {
    lo[a] = hi[a] = cell_of(tri[0].p[a]);
    for (int i = 1; i < 3; ++i) {
      lo[a] = std::min(lo[a], cell_of(tri[i].p[a]));
      hi[a] = std::max(hi[a], cell_of(tri[i].p[a]));
    }
  }
  const std::size_t first_piece = out.pieces.size(), first_key = out.n_keys;
  if (lo == hi) {
    emit(out, f, openvdb::Coord(lo[0], lo[1], lo[2]), tri);
    out.face_count.push_back(1);
    return;
  }
  Clipper clip{mesh, P, f, fv};
  ClipScratch& S = out.scratch;
  Poly &below = S.below, &above = S.above, &rest = S.rest;
  std::size_t nx = 0;
  auto push_slab = [](std::vector<Poly>& pool, std::vector<int>& cells, std::size_t& n, int cell, const Poly& p) {
    if (pool.size() <= n) pool.emplace_back(), cells.emplace_back();
    pool[n] = p;
    cells[n] = cell;
    ++n;
  };
  rest = tri;
  for (int p = lo[0] + 1; p <= hi[0] && !clip.bad; ++p) {
    clip.split(rest, 0, p, below, above);
    if (!below.empty()) push_slab(S.xs, S.xc, nx, p - 1, below);
    rest.swap(above);
  }
  if (!rest.empty()) push_slab(S.xs, S.xc, nx, hi[0], rest);
  for (std::size_t ix = 0; ix < nx && !clip.bad; ++ix) {
    const Poly& slab = S.xs[ix];
    const int cx = S.xc[ix];
    int ylo = cell_of(slab[0].p[1]), yhi = ylo;
    for (const PV& v : slab) ylo = std::min(ylo, cell_of(v.p[1])), yhi = std::max(yhi, cell_of(v.p[1]));
    std::size_t ny = 0;
    rest = slab;
    for (int p = ylo + 1; p <= yhi && !clip.bad; ++p) {
      clip.split(rest, 1, p, below, above);
      if (!below.empty()) push_slab(S.ys, S.yc, ny, p - 1, below);
      rest.swap(above);
    }
    if (!rest.empty()) push_slab(S.ys, S.yc, ny, yhi, rest);
    for (std::size_t iy = 0; iy < ny && !clip.bad; ++iy) {
      const Poly& bar = S.ys[iy];
      const int cy = S.yc[iy];
      int zlo = cell_of(bar[0].p[2]), zhi = zlo;
      for (const PV& v : bar) zlo = std::min(zlo, cell_of(v.p[2])), zhi = std::max(zhi, cell_of(v.p[2]));
      rest = bar;
      for (int p = zlo + 1; p <= zhi && !clip.bad; ++p) {
        clip.split(rest, 2, p, below, above);
        if (!below.empty()) emit(out, f, openvdb::Coord(cx, cy, p - 1), below);
        rest.swap(above);
      }
      if (!clip.bad && !rest.empty()) emit(out, f, openvdb::Coord(cx, cy, zhi), rest);
    }
  }
  if (clip.bad) {
    out.pieces.resize(first_piece);
    out.truncate(first_key);
    out.bad_faces.push_back(f);
    out.bad_boxes.push_back({openvdb::Coord(lo[0], lo[1], lo[2]), openvdb::Coord(hi[0], hi[1], hi[2])});
  }
  out.face_count.push_back(std::uint32_t(out.pieces.size() - first_piece));
}

// Whether face f's box of cells (from its cut positions P) holds an active voxel of `cells`.
bool spans_cells(const SurfaceMesh& mesh, const std::vector<Vec3>& P, Index f, const openvdb::MaskTree& cells) {
  const auto v = mesh.vertices(Face(f));
  openvdb::Coord lo, hi;
  for (int a = 0; a < 3; ++a) {
    const double x = P[v[0].idx][a], y = P[v[1].idx][a], z = P[v[2].idx][a];
    lo[a] = int(std::floor(std::min({x, y, z})));
    hi[a] = int(std::floor(std::max({x, y, z})));
  }
  return box_touches(cells, lo, hi);
}

}  // namespace

PointKey vertex_key(Index v) { return {std::uint64_t(v), 0}; }
PointKey edge_point_key(Index edge, int axis, int plane) {
  return {(std::uint64_t(1) << 62) | (std::uint64_t(axis) << 60) | edge, std::uint64_t(std::int64_t(plane) + kPlaneBias)};
}
PointKey face_point_key(Index face, int line_axis, int plane_u, int plane_v) {
  return {(std::uint64_t(2) << 62) | (std::uint64_t(line_axis) << 60) | face,
          (std::uint64_t(std::int64_t(plane_u) + kPlaneBias) << 32) | std::uint64_t(std::int64_t(plane_v) + kPlaneBias)};
}
PointKey other_key(std::uint64_t a, std::uint64_t b) {
  return {(std::uint64_t(3) << 62) | (a & ((std::uint64_t(1) << 62) - 1)), b};
}

std::uint64_t cell_key(const openvdb::Coord& c) {
  return (std::uint64_t(c.x() + kCellBias) << 42) | (std::uint64_t(c.y() + kCellBias) << 21) |
         std::uint64_t(c.z() + kCellBias);
}
openvdb::Coord cell_from_key(std::uint64_t k) {
  const std::uint64_t m = (std::uint64_t(1) << 21) - 1;
  return openvdb::Coord(int(std::int64_t((k >> 42) & m) - kCellBias), int(std::int64_t((k >> 21) & m) - kCellBias),
                        int(std::int64_t(k & m) - kCellBias));
}

Vec3 point_position(const SurfaceMesh& mesh, const std::vector<Vec3>& P, const PointKey& key, PointWeights* wts) {
  switch (kind(key)) {
    case PointKind::Vertex: {
      const Index v = key_element(key);
      if (wts) *wts = PointWeights{1, {Vertex(v)}, {1.0}};
      return P[v];
    }
    case PointKind::EdgePoint: {
      const Edge e(key_element(key));
      const Vertex u = mesh.vertex(e, 0), v = mesh.vertex(e, 1);
      double t = 0;
      const Vec3 x = edge_point_at(P[u.idx], P[v.idx], key_axis(key), key_plane(key), &t);
      if (wts) *wts = PointWeights{2, {u, v}, {1.0 - t, t}};
      return x;
    }
    case PointKind::FacePoint: {
      const auto vs = mesh.vertices(Face(key_element(key)));
      std::array<double, 3> w{};
      const Vec3 x = face_point_at(P[vs[0].idx], P[vs[1].idx], P[vs[2].idx], key, &w);
      if (wts) *wts = PointWeights{3, vs, w};
      return x;
    }
    default:
      TT_THROW(Error, "point_position: not a mesh subdivision point");
  }
}

Vec3 point_position(const SurfaceMesh& mesh, const LatticeCut& cut, const PointKey& key) {
  if (kind(key) != PointKind::FacePoint) return point_position(mesh, cut.P, key);
  const auto& fv = cut.face_vertices[key_element(key)];
  return face_point_at(cut.P[fv[0]], cut.P[fv[1]], cut.P[fv[2]], key, nullptr);
}

Vec3 cut_to_world(const openvdb::math::Transform& xform, const Vec3& p) {
  const openvdb::Vec3d w = xform.indexToWorld(openvdb::Vec3d(p.x() - kShift[0], p.y() - kShift[1], p.z() - kShift[2]));
  return {w.x(), w.y(), w.z()};
}

bool box_touches(const openvdb::MaskTree& cells, const openvdb::Coord& lo, const openvdb::Coord& hi) {
  using Leaf = openvdb::MaskTree::LeafNodeType;
  constexpr int kDim = int(Leaf::DIM);
  const openvdb::Coord first = lo & ~(kDim - 1);
  for (int x = first.x(); x <= hi.x(); x += kDim)
    for (int y = first.y(); y <= hi.y(); y += kDim)
      for (int z = first.z(); z <= hi.z(); z += kDim) {
        const openvdb::Coord origin(x, y, z);
        const Leaf* leaf = cells.probeConstLeaf(origin);
        if (!leaf) {
          if (cells.isValueOn(origin)) return true;  // inside an active tile
          continue;
        }
        const openvdb::Coord a = openvdb::Coord::maxComponent(lo, origin);
        const openvdb::Coord b = openvdb::Coord::minComponent(hi, origin.offsetBy(kDim - 1));
        for (int i = a.x(); i <= b.x(); ++i)
          for (int j = a.y(); j <= b.y(); ++j)
            for (int k = a.z(); k <= b.z(); ++k)
              if (leaf->isValueOn(openvdb::Coord(i, j, k))) return true;
      }
  return false;
}

LatticeCut cut_by_lattice(const SurfaceMesh& mesh, const openvdb::math::Transform& xform, const openvdb::MaskGrid* only) {
  LatticeCut cut;
  const std::size_t nv = mesh.vertices_size(), nf = mesh.faces_size();
  cut.P.resize(nv);
  cut.snapped.assign(nv, 0);
  std::vector<std::uint8_t> fault(nv, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Vec3& w = mesh.positions()[i];
      const openvdb::Vec3d q = xform.worldToIndex(openvdb::Vec3d(w.x(), w.y(), w.z()));
      Vec3 p(q.x(), q.y(), q.z());
      for (int a = 0; a < 3; ++a) {
        if (mesh.is_deleted(Vertex(Index(i)))) break;
        if (!std::isfinite(p[a])) {
          fault[i] = 1;
          continue;
        }
        if (std::abs(p[a]) > kCellRange - 4) fault[i] = 2;
        p[a] += kShift[a];
        const double plane = std::floor(p[a]), frac = p[a] - plane;
        if (frac < 2 * kSnap) p[a] = plane + kSnap + 0.5 * frac;
        else if (frac > 1.0 - 2 * kSnap) p[a] = plane + 1.0 - kSnap - 0.5 * (1.0 - frac);
        else continue;
        cut.snapped[i] = 1;
      }
      cut.P[i] = p;
    }
  });
  for (std::size_t i = 0; i < nv; ++i) {
    if (fault[i] == 1) TT_THROW(InvalidInput, "constrain topology: vertex " << i << " has a non-finite coordinate");
    if (fault[i] == 2)
      TT_THROW(InvalidInput, "constrain topology: vertex " << i << " lies beyond " << (kCellRange - 4)
                                                           << " voxels from the grid origin");
  }
  cut.face_vertices.resize(nf);
  // Chunks of a fixed size for a given mesh (deterministic), big enough for huge-page buffers.
  const std::size_t kChunk = std::max<std::size_t>(2048, (nf + 23) / 24);
  const std::size_t n_chunks = (nf + kChunk - 1) / kChunk;
  std::vector<Chunk> chunks(n_chunks);
  // About 4 pieces of 4-5 corners per face when the voxel is the edge length (measured on metaballs).
  constexpr std::size_t kKeysPerFace = 20;
  std::vector<std::size_t> key_base(n_chunks + 1, 0);
  for (std::size_t c = 0; c < n_chunks; ++c)
    key_base[c + 1] = key_base[c] + kKeysPerFace * (std::min(nf, (c + 1) * kChunk) - c * kChunk);
  const bool in_place = key_base[n_chunks] <= std::size_t(UINT32_MAX);
  if (in_place) {
    cut.keys.resize(key_base[n_chunks]);  // left unwritten (HugePageAllocator): the chunks fill their ranges
    cut.tags.resize(key_base[n_chunks]);
  }
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      Chunk& out = chunks[c];
      const std::size_t end = std::min(nf, (c + 1) * kChunk);
      out.pieces.reserve(5 * (end - c * kChunk));
      if (in_place) {
        out.keys = cut.keys.data() + key_base[c];
        out.tags = cut.tags.data() + key_base[c];
        out.key_cap = key_base[c + 1] - key_base[c];
      }
      for (std::size_t f = c * kChunk; f < end; ++f) {
        if (mesh.is_deleted(Face(Index(f))) || (only && !spans_cells(mesh, cut.P, Index(f), only->tree())))
          out.face_count.push_back(0);
        else
          clip_face(mesh, cut.P, Index(f), out, cut.face_vertices[f]);
      }
    }
  });
  // Concatenate the chunks' pieces in order, in parallel (each chunk copies into its own range). The corners
  // stay where the chunks wrote them, unless one spilled over its range: then they are concatenated too.
  std::vector<std::size_t> piece_at(n_chunks + 1, 0), key_at(n_chunks + 1, 0), face_at(n_chunks + 1, 0);
  bool spilled = !in_place;
  for (std::size_t c = 0; c < n_chunks; ++c) {
    piece_at[c + 1] = piece_at[c] + chunks[c].pieces.size();
    key_at[c + 1] = key_at[c] + chunks[c].n_keys;
    face_at[c + 1] = face_at[c] + chunks[c].face_count.size();
    spilled = spilled || chunks[c].n_keys > chunks[c].key_cap;
  }
  if (key_at[n_chunks] > std::size_t(UINT32_MAX))
    TT_THROW(InvalidInput, "constrain topology: the cut has more than 2^32 piece corners");
  HugeVector<PointKey> keys;
  HugeVector<std::uint8_t> tags;
  if (spilled) {
    keys.resize(key_at[n_chunks]);
    tags.resize(key_at[n_chunks]);
  } else {
    key_at = key_base;
  }
  cut.pieces.resize(piece_at[n_chunks]);
  cut.face_pieces.assign(face_at[n_chunks] + 1, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n_chunks), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      Chunk& ch = chunks[c];
      const auto key_offset = std::uint32_t(key_at[c]);
      Piece* out = cut.pieces.data() + piece_at[c];
      for (std::size_t i = 0; i < ch.pieces.size(); ++i) {
        out[i] = ch.pieces[i];
        out[i].begin += key_offset;
      }
      if (spilled) {
        const std::size_t own = std::min(ch.n_keys, ch.key_cap);
        std::copy(ch.keys, ch.keys + own, keys.begin() + std::ptrdiff_t(key_at[c]));
        std::copy(ch.tags, ch.tags + own, tags.begin() + std::ptrdiff_t(key_at[c]));
        std::copy(ch.spill_keys.begin(), ch.spill_keys.end(), keys.begin() + std::ptrdiff_t(key_at[c] + own));
        std::copy(ch.spill_tags.begin(), ch.spill_tags.end(), tags.begin() + std::ptrdiff_t(key_at[c] + own));
      }
      // Piece offsets of the chunk's faces, relative to the chunk's first piece.
      std::uint32_t* fp = cut.face_pieces.data() + face_at[c] + 1;
      std::uint32_t acc = std::uint32_t(piece_at[c]);
      for (std::size_t i = 0; i < ch.face_count.size(); ++i) fp[i] = acc += ch.face_count[i];
      HugeVector<Piece>().swap(ch.pieces);  // free as we go
      HugeVector<PointKey>().swap(ch.spill_keys);
      HugeVector<std::uint8_t>().swap(ch.spill_tags);
    }
  });
  if (spilled) {
    cut.keys.swap(keys);
    cut.tags.swap(tags);
  }
  for (Chunk& c : chunks) {
    cut.bad_faces.insert(cut.bad_faces.end(), c.bad_faces.begin(), c.bad_faces.end());
    cut.bad_boxes.insert(cut.bad_boxes.end(), c.bad_boxes.begin(), c.bad_boxes.end());
  }
  return cut;
}

}  // namespace topotrack::topology
