#include "kernels/topology/replace.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <unordered_map>

#include "kernels/sdf/cube_table.hpp"
#include "kernels/sdf/marching_cubes.hpp"

namespace topotrack::topology {
namespace {

openvdb::Coord floor_cell(const Vec3& p) {
  return openvdb::Coord(int(std::floor(p.x())), int(std::floor(p.y())), int(std::floor(p.z())));
}

struct Builder {
  const SurfaceMesh& mesh;
  const LatticeCut& cut;
  const CellIndex& index;
  const std::vector<std::uint64_t>& region;
  const openvdb::FloatGrid& theta;
  Assembly& out;
  std::string& why;

  std::vector<Index> old_to_out;
  std::unordered_map<PointKey, Index, PointKeyHash> derived_of;
  std::unordered_map<std::uint64_t, Index> lattice_of;
  std::vector<Vec3> index_pos;  // positions in the cut's frame (index space plus kShift, snapped) of all output vertices

  bool complex(std::uint64_t cell) const { return std::binary_search(region.begin(), region.end(), cell); }
  bool complex(const openvdb::Coord& c) const { return complex(cell_key(c)); }

  Index new_vertex(const Vec3& index_p) {
    out.positions.emplace_back(Vec3::Zero());
    index_pos.push_back(index_p);
    return Index(out.positions.size() - 1);
  }

  // Output vertex of a subdivision point of M; created on first use only while `create`.
  Index point(const PointKey& k, bool create) {
    if (kind(k) == PointKind::Vertex) return old_to_out[key_element(k)];
    const auto it = derived_of.find(k);
    if (it != derived_of.end()) return it->second;
    if (!create) return kInvalidIndex;
    const Index i = new_vertex(point_position(mesh, cut.P, k));
    out.derived.push_back(k);
    derived_of.emplace(k, i);
    return i;
  }

  // The plane crossings of mesh edge e, ordered from `from` to the other end.
  void edge_points(Edge e, Vertex from, std::vector<std::pair<double, PointKey>>& pts) const {
    pts.clear();
    const Vertex u = mesh.vertex(e, 0), v = mesh.vertex(e, 1);
    const Vec3& pu = cut.P[u.idx];
    const Vec3& pv = cut.P[v.idx];
    for (int a = 0; a < 3; ++a) {
      const int lo = int(std::floor(std::min(pu[a], pv[a]))), hi = int(std::floor(std::max(pu[a], pv[a])));
      for (int p = lo + 1; p <= hi; ++p) {
        const double t = (p - pu[a]) / (pv[a] - pu[a]);
        pts.emplace_back(from == u ? t : 1.0 - t, edge_point_key(e.idx, a, p));
      }
    }
    std::sort(pts.begin(), pts.end());
  }

  void fan(const std::vector<Index>& Q, std::size_t apex) {
    const std::size_t n = Q.size();
    for (std::size_t k = 1; k + 1 < n; ++k) out.triangles.push_back({Q[apex], Q[(apex + k) % n], Q[(apex + k + 1) % n]});
  }

  // The fan apex of a convex piece whose smallest triangle is largest: where a mesh edge passes close to a
  // lattice line, three corners of the piece nearly meet, and a fan from one of them makes a needless sliver.
  std::size_t widest_apex(const std::vector<Index>& Q) const {
    const std::size_t n = Q.size();
    if (n <= 3) return 0;
    std::size_t best = 0;
    double best_area = -1;
    for (std::size_t a = 0; a < n; ++a) {
      double lo = std::numeric_limits<double>::infinity();
      const Vec3& p = index_pos[Q[a]];
      for (std::size_t k = 1; k + 1 < n; ++k)
        lo = std::min(lo, (index_pos[Q[(a + k) % n]] - p).cross(index_pos[Q[(a + k + 1) % n]] - p).squaredNorm());
      if (lo > best_area) best_area = lo, best = a;
    }
    return best;
  }

  void centroid_fan(const std::vector<Index>& Q, const PointKey* derived_key, const Vec3* at = nullptr) {
    Vec3 c = Vec3::Zero();
    for (Index q : Q) c += index_pos[q];
    c /= double(Q.size());
    if (at) c = *at;
    const Index ci = new_vertex(c);
    if (derived_key) {
      out.derived.push_back(*derived_key);
    } else {
      ++out.n_patch;
    }
    for (std::size_t k = 0; k < Q.size(); ++k) out.triangles.push_back({ci, Q[k], Q[(k + 1) % Q.size()]});
  }

  bool run() {
    const std::size_t nv = mesh.vertices_size(), nf = mesh.faces_size();
    // Which faces reach a complex cell (these are re-triangulated from their pieces).
    std::vector<std::uint8_t> split(nf, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t f = r.begin(); f != r.end(); ++f)
        for (std::uint32_t p = cut.face_pieces[f]; p < cut.face_pieces[f + 1] && !split[f]; ++p)
          split[f] = complex(cut.pieces[p].cell);
    });
    for (Index f : cut.bad_faces) split[f] = 1;
    std::vector<std::uint8_t> split_edge(mesh.edges_size(), 0);
    for (std::size_t e = 0; e < mesh.edges_size(); ++e) {
      if (mesh.is_deleted(Edge(Index(e)))) continue;
      for (int i = 0; i < 2; ++i) {
        const Face f = mesh.face(mesh.halfedge(Edge(Index(e)), i));
        if (f.is_valid() && split[f.idx]) split_edge[e] = 1;
      }
    }
    // Kept vertices that the re-triangulation touches take the position the cut used (snapped, see kSnap).
    std::vector<std::uint8_t> touched(nv, 0);
    for (std::size_t e = 0; e < split_edge.size(); ++e)
      if (split_edge[e]) touched[mesh.vertex(Edge(Index(e)), 0).idx] = touched[mesh.vertex(Edge(Index(e)), 1).idx] = 1;
    // Kept vertices of M, in handle order. Room for all of M and some more: growing these arrays copies
    // them into fresh pages, and at 100k vertices the page faults cost more than the copies.
    out.positions.reserve(nv + nv / 16);
    index_pos.reserve(nv + nv / 16);
    out.kept_old.reserve(nv);
    out.triangles.reserve(nf + nf / 16);
    out.tri_source.reserve(nf + nf / 16);
    old_to_out.assign(nv, kInvalidIndex);
    for (std::size_t v = 0; v < nv; ++v) {
      const Vertex vh(static_cast<Index>(v));
      if (mesh.is_deleted(vh) || mesh.is_isolated(vh)) continue;
      if (complex(floor_cell(cut.P[v]))) {
        out.deleted_old.push_back(Index(v));
        continue;
      }
      old_to_out[v] = Index(out.positions.size());
      out.kept_old.push_back(Index(v));
      out.positions.push_back(touched[v] && cut.snapped[v] ? cut_to_world(theta.transform(), cut.P[v]) : mesh.position(vh));
      index_pos.push_back(cut.P[v]);
    }
    // M's triangles and kept pieces.
    std::vector<Index> Q;
    std::vector<std::pair<double, PointKey>> pts;
    for (std::size_t f = 0; f < nf; ++f) {
      const Face fh(static_cast<Index>(f));
      if (mesh.is_deleted(fh)) continue;
      ++out.live_faces;
      if (!split[f]) {
        Q.clear();
        Halfedge h = mesh.halfedge(fh);
        int split_sides = 0;
        for (int i = 0; i < 3; ++i, h = mesh.next(h)) {
          const Vertex a = mesh.from_vertex(h);
          Q.push_back(old_to_out[a.idx]);
          if (Q.back() == kInvalidIndex) return fail("kept face " + std::to_string(f) + " has a removed vertex");
          const Edge e = SurfaceMesh::edge(h);
          if (!split_edge[e.idx]) continue;
          edge_points(e, a, pts);
          if (pts.empty()) continue;
          ++split_sides;
          for (const auto& tp : pts) Q.push_back(point(tp.second, true));
        }
        if (split_sides == 0) {
          out.triangles.push_back({Q[0], Q[1], Q[2]});
          tag(Assembly::kIntact);
          ++out.faces_kept;
        } else if (split_sides == 1) {
          fan(Q, opposite_corner(Q));
          tag(Assembly::kFaceSource | f);
        } else {
          const PointKey ck = other_key(f, 0);
          const Vec3 c = (cut.P[mesh.from_vertex(mesh.halfedge(fh)).idx] + cut.P[mesh.to_vertex(mesh.halfedge(fh)).idx] +
                          cut.P[mesh.to_vertex(mesh.next(mesh.halfedge(fh))).idx]) / 3.0;
          centroid_fan(Q, &ck, &c);
          tag(Assembly::kFaceSource | f);
        }
        continue;
      }
      for (std::uint32_t p = cut.face_pieces[f]; p < cut.face_pieces[f + 1]; ++p) {
        const Piece& pc = cut.pieces[p];
        if (complex(pc.cell)) continue;
        Q.clear();
        for (int i = 0; i < pc.size; ++i) {
          Q.push_back(point(cut.keys[pc.begin + i], true));
          if (Q.back() == kInvalidIndex) return fail("kept piece with a removed vertex");
        }
        fan(Q, widest_apex(Q));
        tag(pc.cell);
      }
    }
    return patch();
  }

  // The source of the triangles added since the last call (see Assembly::tri_source).
  void tag(std::uint64_t source) { out.tri_source.resize(out.triangles.size(), source); }

  bool is_corner(Index q) const { return q < out.kept_old.size(); }
  // In a triangle with one subdivided side, the corner opposite that side: both its neighbours in Q are
  // corners.
  std::size_t opposite_corner(const std::vector<Index>& Q) const {
    const std::size_t n = Q.size();
    for (std::size_t i = 0; i < n; ++i) {
      if (!is_corner(Q[i])) continue;
      if (is_corner(Q[(i + n - 1) % n]) && is_corner(Q[(i + 1) % n])) return i;
    }
    return 0;
  }

  bool fail(std::string w) {
    why = std::move(w);
    return false;
  }

  bool patch() {
    auto acc = theta.getConstAccessor();
    const auto& xform = theta.transform();
    struct TagEdge {
      std::uint8_t tag;
      PointKey from, to;
      bool operator<(const TagEdge& o) const { return tag != o.tag ? tag < o.tag : from < o.from; }
    };
    std::vector<TagEdge> tagged;
    std::vector<PointKey> fpts;
    std::vector<Index> Q;
    std::array<Index, 12> vert;
    std::array<PointKey, 12> vkey;
    std::array<bool, 12> on_boundary;
    for (std::uint64_t ck : region) {
      const openvdb::Coord C = cell_from_key(ck);
      std::array<float, 8> val;
      for (int c = 0; c < 8; ++c) val[c] = node_value(acc, index, C.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1));
      std::uint8_t mask = 0;
      for (int c = 0; c < 8; ++c)
        if (val[c] < 0.f) mask |= std::uint8_t(1u << c);
      const cube::CubePolygons& polys = cube::cube_polygons(mask);
      if (polys.count == 0) continue;
      const auto [pb, pe] = index.pieces_of(ck);
      tagged.clear();
      fpts.clear();
      for (std::uint32_t k = pb; k < pe; ++k) {
        const Piece& pc = cut.pieces[index.piece_order[k]];
        for (int i = 0; i < pc.size; ++i) {
          const PointKey& a = cut.keys[pc.begin + i];
          if (kind(a) == PointKind::FacePoint) fpts.push_back(a);
          if (cut.tags[pc.begin + i] != kOnMeshEdge)
            tagged.push_back({cut.tags[pc.begin + i], a, cut.keys[pc.begin + (i + 1) % pc.size]});
        }
      }
      std::sort(tagged.begin(), tagged.end());
      std::sort(fpts.begin(), fpts.end());
      fpts.erase(std::unique(fpts.begin(), fpts.end()), fpts.end());
      for (int p = 0; p < polys.count; ++p) {
        const auto poly = polys.polygon(p);
        const int n = int(poly.size());
        // Vertices: M's crossing on lattice edges that touch a simple cell, else a new marching-cubes vertex.
        for (int i = 0; i < n; ++i) {
          const int e = poly[i];
          const LatticeEdge le = cell_edge(C, e);
          const int L = le.axis, ua = L == 0 ? 1 : 0, va = L == 2 ? 1 : 2;
          bool touches_simple = false;
          for (int du = 0; du < 2 && !touches_simple; ++du)
            for (int dv = 0; dv < 2 && !touches_simple; ++dv) {
              openvdb::Coord c = le.origin;
              c[ua] -= du;
              c[va] -= dv;
              touches_simple = !complex(c);
            }
          on_boundary[i] = touches_simple;
          if (touches_simple) {
            int found = 0;
            for (const PointKey& k : fpts)
              if (key_axis(k) == L && key_plane_u(k) == le.origin[ua] && key_plane_v(k) == le.origin[va]) {
                vkey[i] = k;
                ++found;
              }
            if (found != 1)
              return fail("lattice edge next to a simple cell crossed " + std::to_string(found) + " times by M");
            vert[i] = point(vkey[i], false);
            if (vert[i] == kInvalidIndex) return fail("crossing point not on the kept part");
          } else {
            const std::uint64_t lk = lattice_edge_key(le);
            const auto it = lattice_of.find(lk);
            if (it != lattice_of.end()) vert[i] = it->second;
            else {
              // Kept kSnap away from the lattice nodes, like M's own vertices: no sliver around a node.
              openvdb::Vec3d q = edge_point_index(le, val[cube::edge_corner(e, 0)], val[cube::edge_corner(e, 1)], 0.0);
              q[L] = le.origin[L] + std::clamp(q[L] - le.origin[L], kSnap, 1.0 - kSnap);
              vert[i] = new_vertex(Vec3(q.x() + kShift[0], q.y() + kShift[1], q.z() + kShift[2]));
              ++out.n_patch;
              lattice_of.emplace(lk, vert[i]);
            }
          }
        }
        // Follow M's cut curve along faces shared with simple cells.
        Q.clear();
        bool curved = false;
        for (int i = 0; i < n; ++i) {
          Q.push_back(vert[i]);
          const int e0 = poly[i], e1 = poly[(i + 1) % n];
          const auto f0 = cube::edge_faces(e0), f1 = cube::edge_faces(e1);
          const int face = (f0[0] == f1[0] || f0[0] == f1[1]) ? f0[0] : f0[1];
          openvdb::Coord nb = C;
          nb[face >> 1] += (face & 1) ? 1 : -1;
          if (complex(nb)) continue;
          if (!on_boundary[i] || !on_boundary[(i + 1) % n]) return fail("face segment next to a simple cell");
          PointKey k = vkey[i];
          for (std::size_t steps = 0;; ++steps) {
            const auto it = std::lower_bound(tagged.begin(), tagged.end(), TagEdge{std::uint8_t(face), k, PointKey{}});
            if (it == tagged.end() || it->tag != face || it->from != k || steps > tagged.size())
              return fail("cut curve breaks off");
            k = it->to;
            if (kind(k) == PointKind::FacePoint) break;
            const Index q = point(k, false);
            if (q == kInvalidIndex) return fail("cut curve point not on the kept part");
            Q.push_back(q);
            curved = true;
          }
          if (k != vkey[(i + 1) % n]) return fail("cut curve ends at another crossing than the face segment");
        }
        if (!curved && n == 3) {
          out.triangles.push_back({Q[0], Q[1], Q[2]});
        } else if (!curved && n == 4 && (((polys.quad_diagonals >> p) & 1) || ((polys.quad_diagonals >> (p + 4)) & 1))) {
          const bool d02 = (polys.quad_diagonals >> p) & 1, d13 = (polys.quad_diagonals >> (p + 4)) & 1;
          bool use02 = d02;
          if (d02 && d13)
            use02 = (index_pos[Q[0]] - index_pos[Q[2]]).squaredNorm() <= (index_pos[Q[1]] - index_pos[Q[3]]).squaredNorm();
          if (use02) {
            out.triangles.push_back({Q[0], Q[1], Q[2]});
            out.triangles.push_back({Q[0], Q[2], Q[3]});
          } else {
            out.triangles.push_back({Q[1], Q[2], Q[3]});
            out.triangles.push_back({Q[1], Q[3], Q[0]});
          }
        } else {
          centroid_fan(Q, nullptr);
        }
        tag(ck);
      }
    }
    // World positions of everything not kept.
    const std::size_t nk = out.kept_old.size();
    tbb::parallel_for(tbb::blocked_range<std::size_t>(nk, out.positions.size(), 4096),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i != r.end(); ++i)
                          out.positions[i] = cut_to_world(xform, index_pos[i]);
                      });
    return true;
  }
};

}  // namespace

bool assemble(const SurfaceMesh& mesh, const LatticeCut& cut, const CellIndex& index,
              const std::vector<std::uint64_t>& region, const openvdb::FloatGrid& theta, Assembly& out,
              std::string& why) {
  out = Assembly();
  Builder b{mesh, cut, index, region, theta, out, why, {}, {}, {}, {}};
  return b.run();
}

std::size_t absorb_sliver_pieces(const SurfaceMesh& mesh, const LatticeCut& cut, std::vector<std::uint64_t>& region) {
  const std::size_t n0 = region.size(), nf = mesh.faces_size();
  std::vector<std::uint64_t> add;
  for (int round = 0; round < 16; ++round) {
    auto in_region = [&](std::uint64_t c) { return std::binary_search(region.begin(), region.end(), c); };
    std::vector<std::vector<std::uint64_t>> found(nf ? (nf + 4095) / 4096 : 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, found.size()), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t chunk = r.begin(); chunk != r.end(); ++chunk)
        for (std::size_t f = chunk * 4096; f < std::min(nf, (chunk + 1) * 4096); ++f) {
          const std::uint32_t pb = cut.face_pieces[f], pe = cut.face_pieces[f + 1];
          if (pe - pb < 2) continue;
          bool reaches = false;
          for (std::uint32_t p = pb; p < pe && !reaches; ++p) reaches = in_region(cut.pieces[p].cell);
          if (!reaches) continue;
          for (std::uint32_t p = pb; p < pe; ++p) {
            const Piece& pc = cut.pieces[p];
            if (in_region(pc.cell)) continue;
            const Vec3 o = point_position(mesh, cut.P, cut.keys[pc.begin]);
            Vec3 n = Vec3::Zero();
            for (int i = 1; i + 1 < pc.size; ++i)
              n += (point_position(mesh, cut.P, cut.keys[pc.begin + i]) - o)
                       .cross(point_position(mesh, cut.P, cut.keys[pc.begin + i + 1]) - o);
            if (0.5 * n.norm() < kMinKeptPieceArea) found[chunk].push_back(pc.cell);
          }
        }
    });
    add.clear();
    for (const auto& v : found) add.insert(add.end(), v.begin(), v.end());
    if (add.empty()) break;
    region.insert(region.end(), add.begin(), add.end());
    std::sort(region.begin(), region.end());
    region.erase(std::unique(region.begin(), region.end()), region.end());
  }
  return region.size() - n0;
}

std::size_t absorb_sliver_triangles(const LatticeCut& cut, const Assembly& A,
                                    const openvdb::math::Transform& xform, std::vector<std::uint64_t>& region) {
  const double h = xform.voxelSize()[0];
  const double limit = 2.0 * kMinTriangleArea * h * h;  // |cross| = twice the area, in world units
  std::vector<std::uint64_t> add;
  for (std::size_t t = 0; t < A.triangles.size(); ++t) {
    const std::uint64_t src = A.tri_source[t];
    if (src == Assembly::kIntact) continue;
    const auto& T = A.triangles[t];
    const Vec3& p = A.positions[T[0]];
    if ((A.positions[T[1]] - p).cross(A.positions[T[2]] - p).norm() >= limit) continue;
    if (src & Assembly::kFaceSource) {
      const Index f = Index(src & ~Assembly::kFaceSource);
      for (std::uint32_t k = cut.face_pieces[f]; k < cut.face_pieces[f + 1]; ++k) add.push_back(cut.pieces[k].cell);
    } else {
      add.push_back(src);
    }
  }
  std::sort(add.begin(), add.end());
  add.erase(std::unique(add.begin(), add.end()), add.end());
  std::vector<std::uint64_t> merged;
  merged.reserve(region.size() + add.size());
  std::set_union(region.begin(), region.end(), add.begin(), add.end(), std::back_inserter(merged));
  const std::size_t added = merged.size() - region.size();
  region.swap(merged);
  return added;
}

std::vector<std::uint64_t> grow_region(const std::vector<std::uint64_t>& region) {
  std::vector<std::uint64_t> out;
  out.reserve(region.size() * 27);
  for (std::uint64_t k : region) {
    const openvdb::Coord c = cell_from_key(k);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) out.push_back(cell_key(c.offsetBy(dx, dy, dz)));
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace topotrack::topology
