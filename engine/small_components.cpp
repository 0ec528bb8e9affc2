#include "engine/small_components.hpp"

#include <algorithm>
#include <limits>
#include <numeric>
#include <optional>

#include <Eigen/Eigenvalues>

#include "kernels/eval/drift.hpp"
#include "kernels/mesh/mesh_convert.hpp"

namespace topotrack {
namespace {

using Soup = std::vector<std::array<Index, 3>>;

//! The small components of a triangle soup: each with its vertices (ascending), in the order of their smallest
//! vertex; `label` gets every vertex's component (kInvalidIndex for vertices of large ones or of none).
struct Components {
  std::vector<std::vector<Index>> vertices;
  std::vector<double> extent;  //!< bounding-box diagonal
  std::vector<Index> label;
};

Components small_components(std::span<const Vec3> pos, const Soup& tris, double max_extent) {
  // Union-find by hand: a few lines, and the soup need not become a SurfaceMesh.
  std::vector<Index> parent(pos.size());
  std::iota(parent.begin(), parent.end(), Index(0));
  const auto find = [&](Index v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const auto& t : tris)
    for (int k = 1; k < 3; ++k) {
      const Index a = find(t[0]), b = find(t[k]);
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the root is the smallest vertex
    }
  std::vector<char> used(pos.size(), 0);
  for (const auto& t : tris) used[t[0]] = used[t[1]] = used[t[2]] = 1;
  std::vector<BoundingBox> box(pos.size());
  for (std::size_t v = 0; v < pos.size(); ++v)
    if (used[v]) box[find(Index(v))].extend(pos[v]);
  Components c;
  c.label.assign(pos.size(), kInvalidIndex);
  std::vector<Index> slot(pos.size(), kInvalidIndex);
  for (std::size_t v = 0; v < pos.size(); ++v) {
    if (!used[v]) continue;
    const Index r = find(Index(v));
    if (box[r].diagonal() > max_extent) continue;
    if (slot[r] == kInvalidIndex) {
      slot[r] = Index(c.vertices.size());
      c.vertices.emplace_back();
      c.extent.push_back(box[r].diagonal());
    }
    c.label[v] = slot[r];
    c.vertices[slot[r]].push_back(Index(v));
  }
  return c;
}

Vec3 centroid(std::span<const Vec3> pos, const std::vector<Index>& vs) {
  Vec3 s = Vec3::Zero();
  for (Index v : vs) s += pos[v];
  return s / double(vs.size());
}

//! The surface point of `rest` closest to p as weights over its triangle's corners (ids): the material a
//! created component inherits and a removed one hands back (none when `rest` is empty).
std::vector<RuleTerm> closest_terms(const TargetSurface* rest, std::span<const VertexId> ids, const Vec3& p) {
  if (!rest) return {};
  const TargetSurface::Hit h = rest->closest_point(p);
  if (!h.hit) return {};
  const auto& t = rest->triangles()[h.face];
  const auto& pos = rest->positions();
  Eigen::Vector3d w = barycentric(h.point, pos[t[0]], pos[t[1]], pos[t[2]]).cwiseMax(0.0);
  if (!(w.sum() > 0)) w = Eigen::Vector3d::Constant(1.0);
  w /= w.sum();
  std::vector<RuleTerm> terms;
  for (int k = 0; k < 3; ++k)
    if (w[k] > 0) terms.push_back({ids[t[k]], w[k]});
  return terms;
}

//! A patch event (§4.4) for a whole component: its vertices, and the ids of `terms` as the ring.
void record(EventKind kind, std::span<const VertexId> patch, const std::vector<RuleTerm>& terms, EventList& events) {
  events.begin_event(kind);
  if (kind == EventKind::PatchDelete)
    for (VertexId v : patch) events.add_in(v);
  for (const RuleTerm& t : terms) events.add_in(t.source);
  for (const RuleTerm& t : terms) events.add_out(t.source);
  if (kind == EventKind::PatchCreate)
    for (VertexId v : patch) events.add_out(v);
  for (VertexId v : patch) {
    if (kind == EventKind::PatchCreate) events.add_forward_rule(v, terms);
    else events.add_backward_rule(v, terms);
  }
  events.end_event();
}

//! A component of S at most 2√2 L across becomes an octahedron on its principal axes: its triangles would
//! shrink under ImproveMesh (§4.1) to whatever tetrahedron the collapses leave, often a flat one (a fold). The
//! octahedron spans the component's extent along each axis, thickened to at least half the largest so that its
//! angles and dihedrals meet the quality bounds; its edges stay below L_max.
void append_octahedron(std::span<const Vec3> src, const std::vector<Index>& vs, std::vector<Vec3>& pos, Soup& tris) {
  const Vec3 c0 = centroid(src, vs);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (Index v : vs) cov += (src[v] - c0) * (src[v] - c0).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Matrix3d axes = eig.eigenvectors();
  if (axes.determinant() < 0) axes.col(0) = -axes.col(0);
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (Index v : vs) {
    const Vec3 q = axes.transpose() * (src[v] - c0);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const Vec3 mid = c0 + axes * (0.5 * (lo + hi));
  Vec3 half = 0.5 * (hi - lo);
  const double big = std::max(half.maxCoeff(), 1e-12 * (1.0 + c0.norm()));
  half = half.cwiseMax(0.5 * big);
  const Index base = Index(pos.size());
  for (int a = 0; a < 3; ++a)
    for (int s : {1, -1}) pos.push_back(mid + double(s) * half[a] * axes.col(a));
  // Vertex 2a is +axis a, 2a + 1 is -axis a. The face (±x, ±y, ±z) is counter-clockwise seen from outside when
  // the product of the signs is positive (axes right-handed).
  for (int sx : {0, 1})
    for (int sy : {0, 1})
      for (int sz : {0, 1}) {
        const Index x = base + Index(sx), y = base + 2 + Index(sy), z = base + 4 + Index(sz);
        if ((sx + sy + sz) % 2 == 0) tris.push_back({x, y, z});
        else tris.push_back({x, z, y});
      }
}

//! The part of a soup whose vertices pass `keep`, renumbered in order, with the ids and the scene (null when it
//! has no triangle).
struct Part {
  std::vector<Vec3> pos;
  std::vector<VertexId> ids;
  Soup tris;
  std::optional<TargetSurface> surface;
  const TargetSurface* scene() const { return surface ? &*surface : nullptr; }
};

template <class Keep>
Part part_of(const std::vector<Vec3>& pos, const Soup& tris, const std::vector<VertexId>& ids, Keep keep) {
  Part p;
  std::vector<Index> slot(pos.size(), kInvalidIndex);
  for (std::size_t v = 0; v < pos.size(); ++v)
    if (keep(v)) {
      slot[v] = Index(p.pos.size());
      p.pos.push_back(pos[v]);
      p.ids.push_back(ids[v]);
    }
  for (const auto& t : tris)
    if (slot[t[0]] != kInvalidIndex) p.tris.push_back({slot[t[0]], slot[t[1]], slot[t[2]]});
  if (!p.tris.empty()) p.surface.emplace(p.pos, p.tris);
  return p;
}

bool any_near(const TargetSurface* surface, std::span<const Vec3> pos, const std::vector<Index>& vs, double radius) {
  return surface && std::any_of(vs.begin(), vs.end(), [&](Index v) { return surface->closest_point(pos[v], radius).hit; });
}

bool all_near(const TargetSurface* surface, std::span<const Vec3> pos, const std::vector<Index>& vs, double radius) {
  return surface && std::all_of(vs.begin(), vs.end(), [&](Index v) { return surface->closest_point(pos[v], radius).hit; });
}

bool boxes_overlap(const BoundingBox& a, const BoundingBox& b) {
  return !((a.min.array() > b.max.array()).any() || (a.max.array() < b.min.array()).any());
}

//! Whether the small closed surface (`pos`, `tris`) lies apart from M's `rest`: no edge of either crosses a
//! triangle of the other (two closed triangle meshes that intersect always have such an edge), and it is not
//! inside M (the first surface of M that a ray from it meets faces away from the ray). `near`: the triangles
//! of `rest` whose boxes meet the region the surface may take (only those can be crossed).
bool lies_apart(const Part& rest, std::span<const Index> near, std::span<const Vec3> pos, const Soup& tris) {
  const TargetSurface& m = *rest.scene();
  BoundingBox box;
  for (const auto& t : tris)
    for (int k = 0; k < 3; ++k) {
      const Vec3 &a = pos[t[k]], &b = pos[t[(k + 1) % 3]];
      if (m.cast(a, b - a, (b - a).norm()).hit) return false;
      box.extend(a);
    }
  const TargetSurface piece(pos, tris);
  for (const Index f : near) {
    const auto& t = rest.tris[f];
    BoundingBox tb;
    for (Index v : t) tb.extend(rest.pos[v]);
    if (!boxes_overlap(tb, box)) continue;
    for (int k = 0; k < 3; ++k) {
      const Vec3 &a = rest.pos[t[k]], &b = rest.pos[t[(k + 1) % 3]];
      if (piece.cast(a, b - a, (b - a).norm()).hit) return false;
    }
  }
  const Vec3 dir = Vec3(1, 2, 3).normalized();  // any fixed direction: M is closed and oriented outwards
  const TargetSurface::Hit h = m.cast(pos[tris[0][0]], dir, std::numeric_limits<double>::infinity());
  return !h.hit || h.normal.dot(dir) < 0;
}

//! A component of S that comes within `radius` of M is still copied when its copy can lie apart from M, where
//! it is or moved straight away from M by a quarter, a half, three quarters or all of `max_shift` (the
//! tracker: one voxel). Resurfaced captures leave crumbs a hair's breadth from a larger part (samba frame 20:
//! 0.07 voxels away), which no lattice sees apart from that part and which the rule "no part of M within
//! `radius`" alone never copies. Moves `pos` to the place found; false when none is apart.
bool place_apart(const Part& rest, std::vector<Vec3>& pos, const Soup& tris, double max_shift) {
  Vec3 c = Vec3::Zero();
  BoundingBox reach;  // every place tried lies within max_shift of where the copy is
  for (const Vec3& p : pos) {
    c += p;
    reach.extend(p);
  }
  c /= double(pos.size());
  reach.min.array() -= max_shift;
  reach.max.array() += max_shift;
  std::vector<Index> near;  // one pass over M's triangles per component, not per place
  for (std::size_t f = 0; f < rest.tris.size(); ++f) {
    BoundingBox tb;
    for (Index v : rest.tris[f]) tb.extend(rest.pos[v]);
    if (boxes_overlap(tb, reach)) near.push_back(Index(f));
  }
  const TargetSurface::Hit h = rest.scene()->closest_point(c);
  Vec3 away = c - h.point;
  away = away.norm() > 0 ? Vec3(away.normalized()) : h.normal;
  std::vector<Vec3> moved(pos.size());
  for (int k = 0; k <= 4; ++k) {
    for (std::size_t i = 0; i < pos.size(); ++i) moved[i] = pos[i] + (0.25 * k * max_shift) * away;
    if (lies_apart(rest, near, moved, tris)) {
      pos = std::move(moved);
      return true;
    }
  }
  return false;
}

}  // namespace

SmallComponentReport match_small_components(SurfaceMesh& mesh, const TargetSurface& target, double radius,
                                            double max_extent, double edge_length, EventList* events) {
  SmallComponentReport report;
  std::vector<Vec3> pos;
  Soup tris;
  std::vector<Vertex> of;
  extract_triangles(mesh, pos, tris, &of);
  std::vector<VertexId> ids(pos.size());
  for (std::size_t i = 0; i < of.size(); ++i) ids[i] = mesh.id(of[i]);
  const Components m_small = small_components(pos, tris, max_extent);
  // The components of S up to twice the size are looked at for presence, so that a component straddling the
  // size limit is not removed from M; only those up to the limit are copied.
  const Components s_small = small_components(target.positions(), target.triangles(), 2 * max_extent);
  if (m_small.vertices.empty() && s_small.vertices.empty()) return report;

  // A small component of M that comes within `radius` of a small component of S stays and makes that one
  // present in M. One that comes near no part of S goes (the droplet it stood for is gone), and so does one
  // that lies within 2 radius of the large components of M (it merged into a larger part; the alignment has
  // laid it on that part's surface, where the lattice cannot see it either). Others stay: a piece of a larger
  // part of S that the lattice cut off in M still covers S there.
  std::vector<char> s_present(s_small.vertices.size(), 0), m_gone(m_small.vertices.size(), 0);
  std::optional<Part> large;
  for (std::size_t c = 0; c < m_small.vertices.size(); ++c) {
    bool near_small = false, near_any = false;
    for (Index v : m_small.vertices[c]) {
      const TargetSurface::Hit h = target.closest_point(pos[v], radius);
      if (!h.hit) continue;
      near_any = true;
      const Index s = s_small.label[target.triangles()[h.face][0]];
      if (s == kInvalidIndex) continue;
      near_small = true;
      s_present[s] = 1;
    }
    if (near_small) continue;
    if (!near_any) {
      m_gone[c] = 1;
      continue;
    }
    if (!large) large = part_of(pos, tris, ids, [&](std::size_t v) { return m_small.label[v] == kInvalidIndex; });
    m_gone[c] = all_near(large->scene(), pos, m_small.vertices[c], 2 * radius);
  }
  // Copy candidates: small components of S that no small component of M came near. Usually there are none (the
  // lattice saw every droplet, so ConstrainTopology made it), and M stays as it is.
  std::vector<std::size_t> candidates;
  for (std::size_t c = 0; c < s_small.vertices.size(); ++c)
    if (!s_present[c] && s_small.extent[c] <= max_extent) candidates.push_back(c);
  if (candidates.empty() && std::count(m_gone.begin(), m_gone.end(), 1) == 0) return report;
  large.reset();  // its scene is as large as M's; M can have ~360k vertices here after an L/8 lattice
  Part rest = part_of(pos, tris, ids, [&](std::size_t v) {
    return m_small.label[v] == kInvalidIndex || !m_gone[m_small.label[v]];
  });

  std::vector<VertexId> patch;
  for (std::size_t c = 0; c < m_small.vertices.size(); ++c) {
    if (!m_gone[c]) continue;
    patch.clear();
    for (Index v : m_small.vertices[c]) patch.push_back(ids[v]);
    if (events)
      record(EventKind::PatchDelete, patch, closest_terms(rest.scene(), rest.ids, centroid(pos, m_small.vertices[c])),
             *events);
    ++report.removed;
  }

  // A small component of S that no part of M comes within `radius` of is copied in, with fresh ids; one that
  // comes that near only if its copy can lie apart from M (place_apart).
  // The copies are gathered apart and appended to the rest once its scene is freed (resurfaced pcow, capture
  // profile, frame 21: M has 363k vertices after ConstrainTopology on the L/8 lattice; docs/results.md).
  const std::span<const Vec3> s_pos = target.positions();
  VertexId next = mesh.next_id();
  std::vector<Vec3> add_pos;
  std::vector<VertexId> add_ids;
  Soup add_tris;
  std::vector<Index> copy(s_pos.size(), kInvalidIndex);
  // One at most 2√2 L across becomes an octahedron; the triangles of the others are gathered in one pass (a
  // spray of thousands of droplets must not cost a pass each).
  const double octahedron_extent = 2 * std::sqrt(2.0) * edge_length;
  std::vector<Soup> candidate_tris(s_small.vertices.size());
  std::vector<char> copied_as_is(s_small.vertices.size(), 0);
  for (std::size_t c : candidates) copied_as_is[c] = s_small.extent[c] > octahedron_extent;
  for (const auto& t : target.triangles()) {
    const Index c = s_small.label[t[0]];
    if (c != kInvalidIndex && copied_as_is[c]) candidate_tris[c].push_back(t);
  }
  for (std::size_t c : candidates) {
    const std::vector<Index>& vs = s_small.vertices[c];
    std::vector<Vec3> piece_pos;
    Soup piece_tris;
    if (!copied_as_is[c]) {
      append_octahedron(s_pos, vs, piece_pos, piece_tris);
    } else {
      for (Index v : vs) {
        copy[v] = Index(piece_pos.size());
        piece_pos.push_back(s_pos[v]);
      }
      for (const auto& t : candidate_tris[c]) piece_tris.push_back({copy[t[0]], copy[t[1]], copy[t[2]]});
    }
    if (any_near(rest.scene(), s_pos, vs, radius) && !place_apart(rest, piece_pos, piece_tris, 2 * radius)) continue;
    const std::size_t first = rest.pos.size() + add_pos.size();
    add_pos.insert(add_pos.end(), piece_pos.begin(), piece_pos.end());
    for (const auto& t : piece_tris)
      add_tris.push_back({Index(first + t[0]), Index(first + t[1]), Index(first + t[2])});
    patch.clear();
    for (std::size_t i = 0; i < piece_pos.size(); ++i) {
      add_ids.push_back(next);
      patch.push_back(next++);
    }
    if (events) record(EventKind::PatchCreate, patch, closest_terms(rest.scene(), rest.ids, centroid(s_pos, vs)), *events);
    ++report.added;
  }
  if (report.added + report.removed == 0) return report;
  rest.surface.reset();
  std::vector<Vec3> out_pos = std::move(rest.pos);
  std::vector<VertexId> out_ids = std::move(rest.ids);
  Soup out_tris = std::move(rest.tris);
  out_pos.insert(out_pos.end(), add_pos.begin(), add_pos.end());
  out_ids.insert(out_ids.end(), add_ids.begin(), add_ids.end());
  out_tris.insert(out_tris.end(), add_tris.begin(), add_tris.end());
  mesh = SurfaceMesh::from_triangles(out_pos, out_tris, out_ids);
  mesh.set_next_id(next);
  return report;
}

}  // namespace topotrack
