#include "kernels/mesh/surface_mesh.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

namespace topotrack {
namespace {

// from_triangles' work arrays, kept per thread from one call to the next: at 100k vertices, first touching
// fresh pages (page faults) cost more than the grouping itself. Released above kKeepBytes.
struct Slot {
  Index b, corner;  // the edge's larger vertex, the corner
  bool operator<(const Slot& o) const { return b != o.b ? b < o.b : corner < o.corner; }
};
struct BuildScratch {
  static constexpr std::size_t kKeepBytes = std::size_t(64) << 20;
  std::vector<std::uint32_t> first;
  std::vector<Slot> slots;
  std::vector<Halfedge> corner_he;
  void release_if_large() {
    if (first.capacity() * 4 + slots.capacity() * sizeof(Slot) + corner_he.capacity() * sizeof(Halfedge) > kKeepBytes)
      *this = BuildScratch();
  }
};
thread_local BuildScratch build_scratch;

}  // namespace

SurfaceMesh SurfaceMesh::clone() const {
  SurfaceMesh m;
  m.vpos_ = vpos_;
  m.vid_ = vid_;
  m.vhe_ = vhe_;
  m.vdel_ = vdel_;
  m.hto_ = hto_;
  m.hnext_ = hnext_;
  m.hprev_ = hprev_;
  m.hface_ = hface_;
  m.edel_ = edel_;
  m.fhe_ = fhe_;
  m.fdel_ = fdel_;
  m.deleted_vertices_ = deleted_vertices_;
  m.deleted_edges_ = deleted_edges_;
  m.deleted_faces_ = deleted_faces_;
  m.next_id_ = next_id_;
  for (const auto& p : props_) m.props_.push_back(p->clone());
  return m;
}

SurfaceMesh SurfaceMesh::from_triangles(std::span<const Vec3> positions,
                                        std::span<const std::array<Index, 3>> triangles,
                                        std::span<const VertexId> ids, bool require_closed) {
  const std::size_t nv = positions.size(), nf = triangles.size();
  if (!ids.empty() && ids.size() != nv)
    TT_THROW(InvalidInput, ids.size() << " vertex ids for " << nv << " vertices");
  if (3 * nf >= std::size_t(kInvalidIndex)) TT_THROW(InvalidInput, nf << " triangles: too many");
  SurfaceMesh m;
  m.vpos_.assign(positions.begin(), positions.end());
  m.vhe_.assign(nv, Halfedge());
  m.vdel_.assign(nv, 0);
  if (ids.empty()) {
    m.vid_.resize(nv);
    std::iota(m.vid_.begin(), m.vid_.end(), VertexId(0));
    m.next_id_ = nv;
  } else {
    m.vid_.assign(ids.begin(), ids.end());
    m.next_id_ = nv ? *std::max_element(ids.begin(), ids.end()) + 1 : 0;
  }
  for (std::size_t f = 0; f < nf; ++f) {
    const auto& t = triangles[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] >= nv) TT_THROW(InvalidInput, "triangle " << f << ": vertex index " << t[k] << " out of range");
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0])
      TT_THROW(InvalidInput, "triangle " << f << " is degenerate (repeated vertex " << (t[0] == t[1] ? t[0] : t[2]) << ")");
  }
  auto from_of = [&](Index c) { return triangles[c / 3][c % 3]; };
  auto to_of = [&](Index c) { return triangles[c / 3][(c % 3 + 1) % 3]; };
  // Group the 3 nf corners (corner 3 f + k: the edge from t[k] to t[k+1]) by undirected edge (a, b), a < b:
  // a counting sort by a, then each vertex's few corners by (b, corner). Edges are numbered in (a, b) order.
  // Linear, where a comparison sort of all corners took ~2/3 of this function at 100k vertices.
  BuildScratch& scratch = build_scratch;
  std::vector<std::uint32_t>& first = scratch.first;  // after the scatter: corners of a in [first[a], first[a+1])
  first.assign(nv + 1, 0);
  for (std::size_t f = 0; f < nf; ++f)
    for (int k = 0; k < 3; ++k) ++first[std::min(triangles[f][k], triangles[f][(k + 1) % 3])];
  std::partial_sum(first.begin(), first.end(), first.begin());
  std::vector<Slot>& slots = scratch.slots;
  slots.resize(3 * nf);
  for (std::size_t f = nf; f-- > 0;)  // backwards, so that each vertex's corners come out ascending
    for (int k = 3; k-- > 0;) {
      const Index u = triangles[f][k], v = triangles[f][(k + 1) % 3];
      slots[--first[std::min(u, v)]] = Slot{std::max(u, v), Index(3 * f + k)};
    }
  std::vector<Halfedge>& corner_he = scratch.corner_he;
  corner_he.resize(3 * nf);
  std::size_t ne = 0;
  for (Index a = 0; a < nv; ++a) {
    Slot* const lo = slots.data() + first[a];
    Slot* const hi = slots.data() + first[a + 1];
    if (hi - lo > 32) {
      std::sort(lo, hi);
    } else {  // corners went in ascending, so sorting by b alone, stably, gives (b, corner) order
      for (Slot* i = lo + 1; i < hi; ++i)
        for (Slot* j = i; j > lo && j->b < (j - 1)->b; --j) std::swap(*j, *(j - 1));
    }
    for (const Slot* i = lo; i < hi;) {
      const Slot* j = i;
      while (j < hi && j->b == i->b) ++j;
      const std::ptrdiff_t n = j - i;
      if (n > 2)
        TT_THROW(InvalidInput, "non-manifold edge (" << a << ", " << i->b << ") shared by " << n << " triangles ("
                                                     << i[0].corner / 3 << ", " << i[1].corner / 3 << ", "
                                                     << i[2].corner / 3 << ")");
      if (n == 2 && from_of(i[0].corner) == from_of(i[1].corner)) {
        const Index f0 = i[0].corner / 3, f1 = i[1].corner / 3;
        auto sorted = [&](Index f) {
          auto t = triangles[f];
          std::sort(t.begin(), t.end());
          return t;
        };
        if (sorted(f0) == sorted(f1)) TT_THROW(InvalidInput, "triangles " << f0 << " and " << f1 << " are duplicates");
        TT_THROW(InvalidInput, "inconsistent orientation: triangles " << f0 << " and " << f1 << " traverse edge ("
                                                                     << a << ", " << i->b << ") in the same direction");
      }
      if (n == 1 && require_closed)
        TT_THROW(InvalidInput, "boundary edge (" << a << ", " << i->b << ") of triangle " << i->corner / 3
                                                 << " in a mesh required closed");
      const Index e = Index(ne++);
      corner_he[i[0].corner] = Halfedge(2 * e);
      if (n == 2) corner_he[i[1].corner] = Halfedge(2 * e + 1);
      i = j;
    }
  }
  m.hto_.resize(2 * ne);
  m.hnext_.resize(2 * ne);
  m.hprev_.resize(2 * ne);
  m.hface_.assign(2 * ne, Face());
  m.edel_.assign(ne, 0);
  m.fhe_.resize(nf);
  m.fdel_.assign(nf, 0);
  for (std::size_t c = 0; c < 3 * nf; ++c) {
    const Halfedge h = corner_he[c];
    m.hto_[h.idx] = Vertex(to_of(Index(c)));
    m.hto_[h.idx ^ 1u] = Vertex(from_of(Index(c)));
    m.hface_[h.idx] = Face(Index(c / 3));
  }
  auto used = [&](Index h) { return m.hface_[h].is_valid(); };
  for (std::size_t f = 0; f < nf; ++f) {
    m.fhe_[f] = corner_he[3 * f];
    for (int k = 0; k < 3; ++k) m.set_next(corner_he[3 * f + k], corner_he[3 * f + (k + 1) % 3]);
  }
  // Outgoing halfedges; boundary ones take precedence and must be unique per vertex.
  for (Index h = 0; h < 2 * ne; ++h) {
    const Vertex from = m.hto_[h ^ 1u];
    if (!used(h)) {
      if (m.vhe_[from.idx].is_valid() && m.is_boundary(m.vhe_[from.idx]))
        TT_THROW(InvalidInput, "non-manifold vertex " << from.idx << ": several boundary fans meet there");
      m.vhe_[from.idx] = Halfedge(h);
    } else if (!m.vhe_[from.idx].is_valid()) {
      m.vhe_[from.idx] = Halfedge(h);
    }
  }
  if (require_closed)
    for (Index v = 0; v < nv; ++v)
      if (!m.vhe_[v].is_valid()) TT_THROW(InvalidInput, "vertex " << v << " is in no triangle of a mesh required closed");
  // Link boundary halfedges: next of boundary h (a->b) is the boundary halfedge leaving b.
  for (Index h = 0; h < 2 * ne; ++h)
    if (!used(h)) m.set_next(Halfedge(h), m.vhe_[m.hto_[h].idx]);
  // Every incident halfedge must be reachable by rotation (one fan per vertex); in parallel, the smallest
  // failing vertex reported.
  std::vector<std::uint32_t>& degree = scratch.first;
  degree.assign(nv, 0);
  for (Index h = 0; h < 2 * ne; ++h) ++degree[m.hto_[h ^ 1u].idx];
  constexpr std::size_t kChunk = 8192;
  std::vector<Index> bad((nv + kChunk - 1) / kChunk, kInvalidIndex);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, bad.size()), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t chunk = r.begin(); chunk != r.end(); ++chunk)
      for (Index v = Index(chunk * kChunk); v < std::min(nv, (chunk + 1) * kChunk) && bad[chunk] == kInvalidIndex; ++v) {
        const Halfedge h0 = m.vhe_[v];
        if (!h0.is_valid()) continue;
        Halfedge h = h0;
        Index count = 0;
        do {
          ++count;
          h = m.ccw_rotated(h);
        } while (h != h0 && count <= degree[v]);
        if (count != degree[v]) bad[chunk] = v;
      }
  });
  for (Index v : bad)
    if (v != kInvalidIndex)
      TT_THROW(InvalidInput, "non-manifold vertex " << v << ": " << degree[v] << " edges in more than one fan");
  m.resize_properties();
  scratch.release_if_large();
  return m;
}

void SurfaceMesh::set_id(Vertex v, VertexId id) {
  vid_[v.idx] = id;
  if (id >= next_id_) next_id_ = id + 1;
}

Halfedge SurfaceMesh::find_halfedge(Vertex a, Vertex b) const {
  const Halfedge h0 = vhe_[a.idx];
  if (!h0.is_valid()) return {};
  Halfedge h = h0;
  do {
    if (hto_[h.idx] == b) return h;
    h = ccw_rotated(h);
  } while (h != h0);
  return {};
}

std::size_t SurfaceMesh::valence(Vertex v) const {
  const Halfedge h0 = vhe_[v.idx];
  if (!h0.is_valid()) return 0;
  std::size_t n = 0;
  Halfedge h = h0;
  do {
    ++n;
    h = ccw_rotated(h);
  } while (h != h0);
  return n;
}

std::array<Vertex, 3> SurfaceMesh::vertices(Face f) const {
  const Halfedge h = fhe_[f.idx];
  return {hto_[hprev_[h.idx].idx], hto_[h.idx], hto_[hnext_[h.idx].idx]};
}

void SurfaceMesh::one_ring(Vertex v, std::vector<Vertex>& out) const {
  out.clear();
  const Halfedge h0 = vhe_[v.idx];
  if (!h0.is_valid()) return;
  Halfedge h = h0;
  do {
    out.push_back(hto_[h.idx]);
    h = ccw_rotated(h);
  } while (h != h0);
}

void SurfaceMesh::outgoing(Vertex v, std::vector<Halfedge>& out) const {
  out.clear();
  const Halfedge h0 = vhe_[v.idx];
  if (!h0.is_valid()) return;
  Halfedge h = h0;
  do {
    out.push_back(h);
    h = ccw_rotated(h);
  } while (h != h0);
}

// Editing ------------------------------------------------------------------------------------------

Vertex SurfaceMesh::add_vertex(const Vec3& p) {
  vpos_.push_back(p);
  vid_.push_back(next_id_++);
  vhe_.push_back(Halfedge());
  vdel_.push_back(0);
  for (auto& prop : props_) prop->resize(vpos_.size());
  return Vertex(Index(vpos_.size() - 1));
}

Halfedge SurfaceMesh::new_edge(Vertex from, Vertex to) {
  const Index h = Index(hto_.size());
  hto_.push_back(to);
  hto_.push_back(from);
  hnext_.resize(h + 2);
  hprev_.resize(h + 2);
  hface_.resize(h + 2);
  edel_.push_back(0);
  return Halfedge(h);
}

Face SurfaceMesh::new_face(Halfedge h) {
  fhe_.push_back(h);
  fdel_.push_back(0);
  return Face(Index(fhe_.size() - 1));
}

void SurfaceMesh::adjust_outgoing_halfedge(Vertex v) {
  const Halfedge h0 = vhe_[v.idx];
  if (!h0.is_valid()) return;
  Halfedge h = h0;
  do {
    if (is_boundary(h)) {
      vhe_[v.idx] = h;
      return;
    }
    h = ccw_rotated(h);
  } while (h != h0);
}

Vertex SurfaceMesh::split(Edge e, const Vec3& p, double alpha) {
  const Vertex va = vertex(e, 1), vb = vertex(e, 0);  // halfedge(e,0) runs va -> vb
  const Vertex v = add_vertex(p);
  for (auto& prop : props_) prop->interpolate(v.idx, vb.idx, alpha, va.idx, 1.0 - alpha);
  // Note: vertex(e,0) = to_vertex(halfedge(e,0)) = vb receives weight alpha.
  const Halfedge h0 = halfedge(e, 0), o0 = halfedge(e, 1);
  const Vertex v2 = to_vertex(o0);
  const Halfedge e1 = new_edge(v, v2), t1 = opposite(e1);
  const Face f0 = face(h0), f3 = face(o0);
  vhe_[v.idx] = h0;
  hto_[o0.idx] = v;
  // Cut one triangle (x, x1, x2 then closing, x starting at v) by the spoke s from v to its far corner into
  // P = (x, x1, -s) and Q = (s, x2, closing); the new face is P or Q, the other keeps `old_face`.
  auto split_side = [&](Halfedge x, Halfedge x1, Halfedge closing, Face old_face, bool new_is_p) {
    const Halfedge x2 = next(x1);
    const Halfedge s = new_edge(v, to_vertex(x1)), ts = opposite(s);
    const Face fn = new_face(new_is_p ? x1 : x2);
    const Face fp = new_is_p ? fn : old_face, fq = new_is_p ? old_face : fn;
    fhe_[old_face.idx] = new_is_p ? closing : x;
    hface_[x.idx] = hface_[x1.idx] = hface_[ts.idx] = fp;
    hface_[s.idx] = hface_[x2.idx] = hface_[closing.idx] = fq;
    set_next(x, x1);
    set_next(x1, ts);
    set_next(ts, x);
    set_next(s, x2);
    set_next(x2, closing);
    set_next(closing, s);
  };
  if (!is_boundary(h0)) {
    split_side(h0, next(h0), t1, f0, false);
  } else {
    set_next(prev(h0), t1);
    set_next(t1, h0);
  }
  if (!is_boundary(o0)) {
    split_side(e1, next(o0), o0, f3, true);
  } else {
    set_next(e1, next(o0));
    set_next(o0, e1);
    vhe_[v.idx] = e1;
  }
  if (vhe_[v2.idx] == h0) vhe_[v2.idx] = t1;
  return v;
}

Vertex SurfaceMesh::split(Face f, const Vec3& p, const std::array<double, 3>& bary) {
  const Halfedge h0 = fhe_[f.idx], h1 = next(h0), h2 = next(h1);
  const std::array<Vertex, 3> c = {to_vertex(h2), to_vertex(h0), to_vertex(h1)};  // c[k] = from_vertex(h_k)
  const Vertex v = add_vertex(p);
  for (auto& prop : props_) {
    const double w01 = bary[0] + bary[1];
    prop->interpolate(v.idx, c[0].idx, w01 > 0 ? bary[0] / w01 : 0.5, c[1].idx, w01 > 0 ? bary[1] / w01 : 0.5);
    prop->interpolate(v.idx, v.idx, w01, c[2].idx, bary[2]);
  }
  // Spokes s_k from v to c[k]; triangles (c[k], c[k+1], v) with halfedges h_k, c[k+1]->v, v->c[k].
  std::array<Halfedge, 3> spoke;  // v -> c[k]
  for (int k = 0; k < 3; ++k) spoke[k] = new_edge(v, c[k]);
  const std::array<Halfedge, 3> hs = {h0, h1, h2};
  const std::array<Face, 3> faces = {f, new_face(h1), new_face(h2)};
  for (int k = 0; k < 3; ++k) {
    const Halfedge in = opposite(spoke[(k + 1) % 3]);  // c[k+1] -> v
    const Halfedge out = spoke[k];                      // v -> c[k]
    set_next(hs[k], in);
    set_next(in, out);
    set_next(out, hs[k]);
    hface_[hs[k].idx] = hface_[in.idx] = hface_[out.idx] = faces[k];
    fhe_[faces[k].idx] = hs[k];
  }
  vhe_[v.idx] = spoke[0];
  return v;
}

bool SurfaceMesh::is_collapse_ok(Halfedge v0v1) const {
  const Halfedge v1v0 = opposite(v0v1);
  const Vertex v0 = to_vertex(v1v0), v1 = to_vertex(v0v1);
  Vertex vl, vr;
  if (!is_boundary(v0v1)) {
    const Halfedge h1 = next(v0v1), h2 = next(h1);
    vl = to_vertex(h1);
    if (is_boundary(opposite(h1)) && is_boundary(opposite(h2))) return false;
    if (valence(vl) <= 3) return false;
  }
  if (!is_boundary(v1v0)) {
    const Halfedge h1 = next(v1v0), h2 = next(h1);
    vr = to_vertex(h1);
    if (is_boundary(opposite(h1)) && is_boundary(opposite(h2))) return false;
    if (valence(vr) <= 3) return false;
  }
  if (vl == vr) return false;
  if (is_boundary(v0) && is_boundary(v1) && !is_boundary(v0v1) && !is_boundary(v1v0)) return false;
  // Link condition: the one-rings of v0 and v1 share only vl and vr.
  const Halfedge s0 = vhe_[v0.idx];
  Halfedge h = s0;
  do {
    const Vertex vv = to_vertex(h);
    if (vv != v1 && vv != vl && vv != vr && find_halfedge(vv, v1).is_valid()) return false;
    h = ccw_rotated(h);
  } while (h != s0);
  // The merged vertex keeps valence >= 3.
  const std::size_t shared = std::size_t(vl.is_valid()) + std::size_t(vr.is_valid());
  if (valence(v0) + valence(v1) < 5 + shared) return false;
  return true;
}

void SurfaceMesh::remove_edge_helper(Halfedge h) {
  const Halfedge hn = next(h), hp = prev(h);
  const Halfedge o = opposite(h), on = next(o), op = prev(o);
  const Face fh = face(h), fo = face(o);
  const Vertex vh = to_vertex(h), vo = to_vertex(o);
  // Redirect every halfedge pointing at vo to vh.
  const Halfedge s = vhe_[vo.idx];
  Halfedge hc = s;
  do {
    hto_[opposite(hc).idx] = vh;
    hc = ccw_rotated(hc);
  } while (hc != s);
  set_next(hp, hn);
  set_next(op, on);
  if (fh.is_valid()) fhe_[fh.idx] = hn;
  if (fo.is_valid()) fhe_[fo.idx] = on;
  if (vhe_[vh.idx] == o) vhe_[vh.idx] = hn;
  adjust_outgoing_halfedge(vh);
  vhe_[vo.idx] = Halfedge();
  vdel_[vo.idx] = 1;
  ++deleted_vertices_;
  edel_[edge(h).idx] = 1;
  ++deleted_edges_;
}

void SurfaceMesh::remove_loop_helper(Halfedge h) {
  const Halfedge h0 = h, h1 = next(h0);
  const Halfedge o0 = opposite(h0), o1 = opposite(h1);
  const Vertex v0 = to_vertex(h0), v1 = to_vertex(h1);
  const Face fh = face(h0), fo = face(o0);
  set_next(h1, next(o0));
  set_next(prev(o0), h1);
  hface_[h1.idx] = fo;
  vhe_[v0.idx] = h1;
  adjust_outgoing_halfedge(v0);
  vhe_[v1.idx] = o1;
  adjust_outgoing_halfedge(v1);
  if (fo.is_valid() && fhe_[fo.idx] == o0) fhe_[fo.idx] = h1;
  if (fh.is_valid()) {
    fdel_[fh.idx] = 1;
    ++deleted_faces_;
  }
  edel_[edge(h).idx] = 1;
  ++deleted_edges_;
}

void SurfaceMesh::collapse(Halfedge h, const Vec3& p) {
  const Vertex kept = to_vertex(h), gone = from_vertex(h);
  for (auto& prop : props_) prop->interpolate(kept.idx, kept.idx, 0.5, gone.idx, 0.5);
  const Halfedge h0 = h, h1 = prev(h0), o0 = opposite(h0), o1 = next(o0);
  remove_edge_helper(h0);
  if (next(next(h1)) == h1) remove_loop_helper(h1);
  if (next(next(o1)) == o1) remove_loop_helper(o1);
  vpos_[kept.idx] = p;
}

bool SurfaceMesh::is_flip_ok(Edge e) const {
  if (is_boundary(e)) return false;
  const Halfedge h0 = halfedge(e, 0), h1 = halfedge(e, 1);
  const Vertex v0 = to_vertex(next(h0)), v1 = to_vertex(next(h1));
  if (v0 == v1) return false;
  if (find_halfedge(v0, v1).is_valid()) return false;
  if (valence(to_vertex(h0)) <= 3 || valence(to_vertex(h1)) <= 3) return false;
  return true;
}

void SurfaceMesh::flip(Edge e) {
  const Halfedge a0 = halfedge(e, 0), b0 = halfedge(e, 1);
  const Halfedge a1 = next(a0), a2 = next(a1), b1 = next(b0), b2 = next(b1);
  const Vertex va0 = to_vertex(a0), va1 = to_vertex(a1), vb0 = to_vertex(b0), vb1 = to_vertex(b1);
  const Face fa = face(a0), fb = face(b0);
  hto_[a0.idx] = va1;
  hto_[b0.idx] = vb1;
  set_next(a0, a2);
  set_next(a2, b1);
  set_next(b1, a0);
  set_next(b0, b2);
  set_next(b2, a1);
  set_next(a1, b0);
  hface_[a1.idx] = fb;
  hface_[b1.idx] = fa;
  fhe_[fa.idx] = a0;
  fhe_[fb.idx] = b0;
  if (vhe_[va0.idx] == b0) vhe_[va0.idx] = a1;
  if (vhe_[vb0.idx] == a0) vhe_[vb0.idx] = b1;
}

CompactMaps SurfaceMesh::compact() {
  CompactMaps maps;
  auto build = [](const std::vector<std::uint8_t>& del, std::vector<Index>& old_to_new, std::vector<Index>& new_to_old) {
    old_to_new.assign(del.size(), kInvalidIndex);
    new_to_old.clear();
    for (Index i = 0; i < del.size(); ++i)
      if (!del[i]) {
        old_to_new[i] = Index(new_to_old.size());
        new_to_old.push_back(i);
      }
  };
  std::vector<Index> v_keep, e_keep, f_keep;
  build(vdel_, maps.vertices, v_keep);
  build(edel_, maps.edges, e_keep);
  build(fdel_, maps.faces, f_keep);
  auto map_h = [&](Halfedge h) {
    return h.is_valid() ? Halfedge(2 * maps.edges[h.idx >> 1] + (h.idx & 1u)) : h;
  };
  // Vertices.
  {
    std::vector<Vec3> pos(v_keep.size());
    std::vector<VertexId> ids(v_keep.size());
    std::vector<Halfedge> he(v_keep.size());
    for (std::size_t i = 0; i < v_keep.size(); ++i) {
      pos[i] = vpos_[v_keep[i]];
      ids[i] = vid_[v_keep[i]];
      he[i] = map_h(vhe_[v_keep[i]]);
    }
    vpos_.swap(pos);
    vid_.swap(ids);
    vhe_.swap(he);
    vdel_.assign(v_keep.size(), 0);
    for (auto& prop : props_) prop->gather(v_keep);
  }
  // Halfedges.
  {
    const std::size_t nh = 2 * e_keep.size();
    std::vector<Vertex> to(nh);
    std::vector<Halfedge> nx(nh), pv(nh);
    std::vector<Face> fc(nh);
    for (std::size_t i = 0; i < e_keep.size(); ++i)
      for (Index s = 0; s < 2; ++s) {
        const Index o = 2 * e_keep[i] + s, n = Index(2 * i + s);
        to[n] = Vertex(maps.vertices[hto_[o].idx]);
        nx[n] = map_h(hnext_[o]);
        pv[n] = map_h(hprev_[o]);
        fc[n] = hface_[o].is_valid() ? Face(maps.faces[hface_[o].idx]) : Face();
      }
    hto_.swap(to);
    hnext_.swap(nx);
    hprev_.swap(pv);
    hface_.swap(fc);
    edel_.assign(e_keep.size(), 0);
  }
  // Faces.
  {
    std::vector<Halfedge> he(f_keep.size());
    for (std::size_t i = 0; i < f_keep.size(); ++i) he[i] = map_h(fhe_[f_keep[i]]);
    fhe_.swap(he);
    fdel_.assign(f_keep.size(), 0);
  }
  deleted_vertices_ = deleted_edges_ = deleted_faces_ = 0;
  return maps;
}

void SurfaceMesh::validate(bool require_closed) const {
  const std::size_t nv = vpos_.size(), nh = hto_.size(), nf = fhe_.size();
  auto h_ok = [&](Halfedge h) { return h.is_valid() && h.idx < nh && !edel_[h.idx >> 1]; };
  for (Index h = 0; h < nh; ++h) {
    if (edel_[h >> 1]) continue;
    const Halfedge H(h);
    if (!hto_[h].is_valid() || hto_[h].idx >= nv || vdel_[hto_[h].idx])
      TT_THROW(TopologyError, "halfedge " << h << " points to an invalid or deleted vertex");
    if (!h_ok(hnext_[h]) || !h_ok(hprev_[h])) TT_THROW(TopologyError, "halfedge " << h << ": invalid next/prev");
    if (hprev_[hnext_[h].idx] != H) TT_THROW(TopologyError, "halfedge " << h << ": prev(next(h)) != h");
    if (from_vertex(hnext_[h]) != hto_[h]) TT_THROW(TopologyError, "halfedge " << h << ": next does not start at its end");
    if (hto_[h] == hto_[h ^ 1u]) TT_THROW(TopologyError, "edge " << (h >> 1) << " is a loop");
    const Face f = hface_[h];
    if (f.is_valid()) {
      if (f.idx >= nf || fdel_[f.idx]) TT_THROW(TopologyError, "halfedge " << h << " in a deleted face");
      if (hface_[hnext_[h].idx] != f) TT_THROW(TopologyError, "halfedge " << h << ": next in another face");
      if (next(next(next(H))) != H) TT_THROW(TopologyError, "face " << f.idx << " is not a triangle");
    } else {
      if (require_closed) TT_THROW(TopologyError, "boundary edge " << (h >> 1) << " in a mesh required closed");
      if (!hface_[h ^ 1u].is_valid()) TT_THROW(TopologyError, "edge " << (h >> 1) << " has no face on either side");
    }
  }
  for (Index f = 0; f < nf; ++f) {
    if (fdel_[f]) continue;
    if (!h_ok(fhe_[f]) || hface_[fhe_[f].idx] != Face(f))
      TT_THROW(TopologyError, "face " << f << ": halfedge not in the face");
    const auto t = vertices(Face(f));
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) TT_THROW(TopologyError, "face " << f << " is degenerate");
  }
  std::vector<Index> degree(nv, 0);
  for (Index h = 0; h < nh; ++h)
    if (!edel_[h >> 1]) ++degree[hto_[h ^ 1u].idx];
  std::vector<Index> mark(nv, kInvalidIndex);
  for (Index v = 0; v < nv; ++v) {
    if (vdel_[v]) continue;
    const Halfedge h0 = vhe_[v];
    if (!h0.is_valid()) {
      if (require_closed || degree[v]) TT_THROW(TopologyError, "vertex " << v << " is isolated");
      continue;
    }
    if (!h_ok(h0) || from_vertex(h0) != Vertex(v)) TT_THROW(TopologyError, "vertex " << v << ": bad outgoing halfedge");
    Index count = 0, boundary = 0;
    Halfedge h = h0;
    do {
      if (from_vertex(h) != Vertex(v)) TT_THROW(TopologyError, "vertex " << v << ": broken fan");
      const Index w = hto_[h.idx].idx;
      if (mark[w] == v) TT_THROW(TopologyError, "duplicate edge between vertices " << v << " and " << w);
      mark[w] = v;
      boundary += is_boundary(h);
      ++count;
      h = ccw_rotated(h);
    } while (h != h0 && count <= degree[v]);
    if (count != degree[v]) TT_THROW(TopologyError, "non-manifold vertex " << v << " (several fans)");
    if (boundary > 1) TT_THROW(TopologyError, "non-manifold vertex " << v << " (several boundary fans)");
    if (boundary == 1 && !is_boundary(h0))
      TT_THROW(TopologyError, "vertex " << v << ": outgoing halfedge should be the boundary one");
    if (count < 2) TT_THROW(TopologyError, "vertex " << v << " has valence " << count);
  }
}

void SurfaceMesh::resize_properties() {
  for (auto& p : props_) p->resize(vpos_.size());
}

void SurfaceMesh::remove_vertex_property(const std::string& name) {
  std::erase_if(props_, [&](const auto& p) { return p->name() == name; });
}

std::vector<std::string> SurfaceMesh::vertex_property_names() const {
  std::vector<std::string> names;
  for (const auto& p : props_) names.push_back(p->name());
  return names;
}

BasePropertyArray* SurfaceMesh::find_property(const std::string& name) const {
  for (const auto& p : props_)
    if (p->name() == name) return p.get();
  return nullptr;
}

}  // namespace topotrack
