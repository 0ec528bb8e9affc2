#include "kernels/improve/improve.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <tuple>
#include <utility>

#include "kernels/improve/improve_geometry.hpp"
#include "kernels/mesh/mesh_queries.hpp"

namespace topotrack {
namespace {

using namespace improve_detail;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
// A new triangle whose smallest angle is below about 0.06° counts as degenerate whatever the old ones were.
constexpr double kDegenerateQuality = kNearDegenerateSin;
// A collapse of a short edge may leave edges up to this factor above L_max (the next round splits them):
// on iso-surface meshes short edges often sit next to nearly maximal ones, and refusing leaves them.
constexpr double kShortCollapseStretch = 1.25;
// ... and may create an angle below min_angle only above this fraction of it (or better than before).
constexpr double kShortCollapseAngleFloor = 0.2;
// An operation that removes a triangle with an angle below this may move the surface twice as far.
constexpr double kVeryBadAngleDeg = 2.0;
// A relaxation of a star whose smallest angle is at least kVeryBadAngleDeg must raise that angle at least
// to kRelaxGainFactor times it plus kRelaxGainMin (in sines): tiny gains would creep on round after round
// (and on in the next call), moving the surface for nothing.
constexpr double kRelaxGainFactor = 1.2;
constexpr double kRelaxGainMin = 1e-3;
// Above this smallest-angle sine (about 0.57°) a triangle whose edges are long against the float spacing of
// its coordinates cannot become degenerate by rounding to float.
constexpr double kRoundingSafeQuality = 1e-2;
// The least gain in the sharpest crease of a star for a move that softens a fold it cannot remove (soften_fold).
constexpr double kSoftenGainDeg = 0.5;
// Bisection steps that refine the shortest move removing a fold (fold_pass).
constexpr int kUnfoldBisections = 5;
// Tolerance on the cosine of the sharpest crease for a move that keeps the planes of the faces at a crease.
constexpr double kCreaseNoise = 1e-9;

template <class F>
void parallel_over(std::size_t n, F&& f) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

//! Candidates (key, index), processed in increasing key order, ties by the smaller index.
using Candidates = std::vector<std::pair<double, Index>>;

enum EdgeFlag : std::uint8_t { kLong = 1, kShort = 2, kFold = 4 };

//! Why an edge is collapsed, which decides what the collapse may do to the triangles (§4.1).
enum class CollapseMode {
  Short,    //!< shorter than L_min: must not create a new bad angle (or only a mildly bad one)
  Improve,  //!< edge of a triangle with a small angle: must raise the smallest angle around
  Fold,     //!< across a small dihedral angle: removes the fold, exempt from the deviation bound
};

//! The candidates of one round, found by a parallel scan.
struct Survey {
  Candidates long_edges, short_edges, bad_faces, folds;
  bool empty() const { return long_edges.empty() && short_edges.empty() && bad_faces.empty() && folds.empty(); }
};

// Operations are applied serially in a fixed order; only the surveys run in parallel. Parallel collapses on
// independent sets of edges were measured not to pay: on a 100k-vertex resurfaced elephant frame (gen
// resurface --resolution 230, 24k collapses) the collapse pass is ~38% of improve_mesh's time (scan 16%,
// splits 13%, compaction and quality 33%), 0.07-0.14 s CPU per 100k vertices in all (bench/improve), so two
// cores could save at most ~0.03 s on a first improvement; in the tracker's steady state (an improved mesh
// moved by the alignment) there are almost no collapses and the call is the parallel scan (samba, 13k
// vertices: 0.8 ms), against 1.15 s per tracker frame.
class Improver {
public:
  Improver(SurfaceMesh& mesh, const ImproveParams& params, EventList* events, ImproveReport& report)
      : m_(mesh), p_(params), events_(events), rep_(report) {}

  void run(double L) {
    lmin_ = L / std::sqrt(p_.ratio);
    lmax_ = L * std::sqrt(p_.ratio);
    lmin2_ = lmin_ * lmin_;
    lmax2_ = lmax_ * lmax_;
    max_dev_ = p_.max_surface_deviation * L;
    op_dev_ = p_.max_operation_deviation * L;
    q_very_bad_ = std::sin(kVeryBadAngleDeg * kDegToRad);
    q_min_ = std::sin(p_.min_angle_deg * kDegToRad);
    q_bad_ = std::max(q_min_, kDegenerateQuality);
    q_bad2_ = q_bad_ * q_bad_;
    q_floor_ = std::sin(kShortCollapseAngleFloor * p_.min_angle_deg * kDegToRad);
    lmax_short2_ = lmax2_ * kShortCollapseStretch * kShortCollapseStretch;
    cos_fold_ = std::cos((180.0 - p_.min_dihedral_deg) * kDegToRad);
    lcrease2_ = p_.crease_collapse_fraction * p_.crease_collapse_fraction * lmin2_;
    cos_flip_bend_ = std::cos(p_.max_flip_bend_deg * kDegToRad);
    rep_.min_edge_length = lmin_;
    rep_.max_edge_length = lmax_;
    Survey s;
    bool full_survey = true;
    for (int it = 0; it < p_.max_iterations; ++it) {
      auto t0 = Clock::now();
      // After a busy round the parallel full scan is cheaper than gathering the touched neighbourhoods.
      if (std::exchange(full_survey, false) || touched_.size() > m_.vertices_size() / 8)
        survey_all(s);
      else
        survey_touched(s);
      rep_.seconds_scan += since(t0);
      if (s.empty() && unfixed_.empty() && unfixed_short_.empty()) {
        // relax_pass forgets the triangles and short edges it could not fix, and survey_touched sees only what
        // the last round touched: once a relaxation has run, the last resort below is checked on a full
        // survey before stopping too. Without this a call could stop with a triangle below kVeryBadAngleDeg
        // that a second call removed at once (resurfaced pcow frame 3, capture profile on the extraction grid:
        // a 0.6° triangle; docs/results.md, 2026-11-25 night).
        if (!relaxed_ || last_resort_) break;
        survey_all(s);
        if (!any_below(s.bad_faces, q_very_bad_)) break;
        last_resort_ = true;
      }
      rep_.iterations = it + 1;
      std::size_t ops = 0;
      t0 = Clock::now();
      ops += short_edge_pass(s.short_edges);
      rep_.seconds_collapse += since(t0);
      t0 = Clock::now();
      ops += split_pass(s.long_edges);
      rep_.seconds_split += since(t0);
      t0 = Clock::now();
      ops += bad_triangle_pass(s.bad_faces);
      rep_.seconds_bad_triangles += since(t0);
      t0 = Clock::now();
      ops += fold_pass(s.folds);
      rep_.seconds_folds += since(t0);
      if (ops == 0) {
        // Splits, collapses and flips are at their fixed point: relax around what is still bad.
        t0 = Clock::now();
        ops = p_.enable_relaxation ? relax_pass() : 0;
        rep_.seconds_bad_triangles += since(t0);
        relaxed_ = relaxed_ || ops > 0;
        if (ops > 0) continue;
        // The last resort for a triangle below kVeryBadAngleDeg that nothing removed (a full survey finds
        // it), from the next round on: crease collapses judged by the two-ring (crease_collapse_ok) and
        // fold-mode collapses of a valence-3 corner that blocks a collapse (collapse_unblocking).
        if (last_resort_) break;
        survey_all(s);
        if (!any_below(s.bad_faces, q_very_bad_)) break;
        last_resort_ = full_survey = true;
      }
    }
  }

private:
  const Vec3& pos(Vertex v) const { return m_.position(v); }
  double length2(Edge e) const { return (pos(m_.vertex(e, 0)) - pos(m_.vertex(e, 1))).squaredNorm(); }
  //! The corners of f in SurfaceMesh::vertices order, inline (the scans call this for every face).
  std::array<Vertex, 3> corners(Face f) const {
    const Halfedge h = m_.halfedge(f);
    return {m_.to_vertex(m_.prev(h)), m_.to_vertex(h), m_.to_vertex(m_.next(h))};
  }
  Vec3 area_vector(Face f) const {
    const auto t = corners(f);
    return (pos(t[1]) - pos(t[0])).cross(pos(t[2]) - pos(t[0]));
  }
  double quality(Face f) const {
    const auto t = corners(f);
    return triangle_quality(pos(t[0]), pos(t[1]), pos(t[2]));
  }
  //! A live triangle with an angle below min_angle, or degenerate (is_near_degenerate: a tiny triangle of
  //! good shape can still vanish when rounded to float; only one with an edge below L_min is that small).
  //! triangle_quality < q_bad without its square roots: |e0 x e2|^2 < q_bad^2 * (product of the two
  //! longest squared edge lengths).
  bool is_bad(Face f) const {
    if (m_.is_deleted(f)) return false;
    const auto t = corners(f);
    const Vec3 &p0 = pos(t[0]), &p1 = pos(t[1]), &p2 = pos(t[2]);
    const Vec3 e0 = p1 - p0, e1 = p2 - p1, e2 = p0 - p2;
    const double l0 = e0.squaredNorm(), l1 = e1.squaredNorm(), l2 = e2.squaredNorm();
    const double lmin = std::min({l0, l1, l2});
    const double prod = (l0 == lmin) ? l1 * l2 : (l1 == lmin ? l0 * l2 : l0 * l1);
    if (!(prod > 0) || e0.cross(e2).squaredNorm() < q_bad2_ * prod) return true;
    if (!(lmin < lmin2_)) return false;
    // Rounding to float moves a corner by at most sqrt(3) 2^-24 |p|_inf: with the shortest edge 1e4 times
    // longer and the smallest angle above 0.5°, it cannot make the triangle degenerate.
    const double m = std::max({p0.cwiseAbs().maxCoeff(), p1.cwiseAbs().maxCoeff(), p2.cwiseAbs().maxCoeff()});
    const double round2 = 3.0 * (m * 0x1p-24) * (m * 0x1p-24);
    if (q_bad2_ >= kRoundingSafeQuality * kRoundingSafeQuality && lmin > 1e8 * round2) return false;
    return is_near_degenerate(p0, p1, p2);
  }
  //! Whether a live face among the candidates has quality below q.
  bool any_below(const Candidates& faces, double q) const {
    for (const auto& [key, fi] : faces)
      if (!m_.is_deleted(Face(fi)) && quality(Face(fi)) < q) return true;
    return false;
  }
  //! Normals more than 180° - min_dihedral apart (degenerate faces have no normal and fold nothing).
  bool normals_fold(const Vec3& n0, const Vec3& n1) const {
    return n0.squaredNorm() > 0 && n1.squaredNorm() > 0 && !normals_within(n0, n1, cos_fold_);
  }
  bool is_fold(Edge e) const {
    return normals_fold(area_vector(m_.face(m_.halfedge(e, 0))), area_vector(m_.face(m_.halfedge(e, 1))));
  }
  //! How far one operation may move the surface (max_operation_deviation), given the smallest triangle
  //! quality among the triangles it replaces.
  double operation_bound(double old_q) const { return old_q < q_very_bad_ ? 2 * op_dev_ : op_dev_; }
  void after_operation() {
    if (p_.validate_each_step) m_.validate();
  }

  // Survey ---------------------------------------------------------------------------------------
  //! Byte flags only, so a survey of a large mesh touches little fresh memory; keys are recomputed for
  //! the few flagged elements when they are collected.
  void measure_face(Index i) { fbad_[i] = is_bad(Face(i)); }
  void measure_edge(Index i) { eflag_[i] = edge_flag(Edge(i)); }
  std::uint8_t edge_flag(Edge e) const {
    if (m_.is_deleted(e)) return 0;
    const Halfedge h0 = m_.halfedge(e, 0), h1 = m_.halfedge(e, 1);
    const Vec3 &a = pos(m_.to_vertex(h1)), &b = pos(m_.to_vertex(h0));
    const Vec3 &c = pos(m_.to_vertex(m_.next(h0))), &d = pos(m_.to_vertex(m_.next(h1)));
    const Vec3 ab = b - a;
    const double l2 = ab.squaredNorm();
    std::uint8_t flag = l2 > lmax2_ ? kLong : (l2 < lmin2_ ? kShort : 0);
    // Faces (a, b, c) and (b, a, d).
    if (normals_fold(ab.cross(c - a), (d - a).cross(ab))) flag |= kFold;
    return flag;
  }
  void resize_survey_arrays() {
    fbad_.resize(m_.faces_size());
    eflag_.resize(m_.edges_size());
  }
  void add_edge_candidate(Survey& s, Index e, std::uint8_t flag) const {
    if (!flag) return;
    const double l2 = length2(Edge(e));
    if (flag & kLong) s.long_edges.emplace_back(-l2, e);  // longest first
    if (flag & kShort) s.short_edges.emplace_back(l2, e);  // shortest first
    if (flag & kFold) s.folds.emplace_back(0.0, e);        // by index
  }
  void add_face_candidate(Survey& s, Index f) const {
    s.bad_faces.emplace_back(quality(Face(f)), f);  // worst first
  }
  static void clear_survey(Survey& s) {
    for (Candidates* c : {&s.long_edges, &s.short_edges, &s.bad_faces, &s.folds}) c->clear();
  }
  static void sort_survey(Survey& s) {
    for (Candidates* c : {&s.long_edges, &s.short_edges, &s.bad_faces, &s.folds}) std::sort(c->begin(), c->end());
  }

  //! One parallel pass over all faces (quality) and one over all edges (length, fold); the candidate
  //! lists are collected and sorted serially, so their order never depends on the thread count.
  void survey_all(Survey& s) {
    clear_survey(s);
    for (const Index v : touched_) vtouched_[v] = 0;
    touched_.clear();
    resize_survey_arrays();
    parallel_over(m_.faces_size(), [&](std::size_t i) { measure_face(static_cast<Index>(i)); });
    parallel_over(m_.edges_size(), [&](std::size_t i) { measure_edge(static_cast<Index>(i)); });
    for (Index e = 0; e < m_.edges_size(); ++e) add_edge_candidate(s, e, eflag_[e]);
    for (Index f = 0; f < m_.faces_size(); ++f)
      if (fbad_[f]) add_face_candidate(s, f);
    sort_survey(s);
  }

  //! The same over the faces and edges around the vertices that the last round touched: elsewhere nothing
  //! changed, so what could not be fixed there still cannot.
  void survey_touched(Survey& s) {
    clear_survey(s);
    resize_survey_arrays();
    estamp_.resize(m_.edges_size(), 0);
    fstamp_.resize(m_.faces_size(), 0);
    ++stamp_;
    local_edges_.clear();
    local_faces_.clear();
    for (const Index vi : touched_) {
      vtouched_[vi] = 0;
      const Vertex v(vi);
      if (m_.is_deleted(v) || m_.is_isolated(v)) continue;
      const Halfedge g0 = m_.halfedge(v);
      Halfedge g = g0;
      do {
        const Index e = SurfaceMesh::edge(g).idx, f = m_.face(g).idx;
        if (estamp_[e] != stamp_) {
          estamp_[e] = stamp_;
          local_edges_.push_back(e);
        }
        if (f != kInvalidIndex && fstamp_[f] != stamp_) {
          fstamp_[f] = stamp_;
          local_faces_.push_back(f);
        }
        g = m_.ccw_rotated(g);
      } while (g != g0);
    }
    touched_.clear();
    parallel_over(local_faces_.size(), [&](std::size_t i) { measure_face(local_faces_[i]); });
    parallel_over(local_edges_.size(), [&](std::size_t i) { measure_edge(local_edges_[i]); });
    for (const Index e : local_edges_) add_edge_candidate(s, e, eflag_[e]);
    for (const Index f : local_faces_)
      if (fbad_[f]) add_face_candidate(s, f);
    sort_survey(s);
  }

  void touch(Vertex v) {
    if (vtouched_.size() < m_.vertices_size()) vtouched_.resize(m_.vertices_size(), 0);
    if (vtouched_[v.idx]) return;
    vtouched_[v.idx] = 1;
    touched_.push_back(v.idx);
  }
  void touch_ring(Vertex v) {
    touch(v);
    const Halfedge g0 = m_.halfedge(v);
    Halfedge g = g0;
    do {
      touch(m_.to_vertex(g));
      g = m_.ccw_rotated(g);
    } while (g != g0);
  }

  // Splits ---------------------------------------------------------------------------------------
  std::size_t split_pass(const Candidates& c) {
    std::size_t n = 0;
    for (const auto& [key, ei] : c) {
      const Edge e(ei);
      if (m_.is_deleted(e) || length2(e) <= lmax2_) continue;
      const Vertex v0 = m_.vertex(e, 0), v1 = m_.vertex(e, 1);
      const Vertex k = m_.split(e, 0.5 * (pos(v0) + pos(v1)), 0.5);
      if (events_) events_->record_split(m_.id(v0), m_.id(v1), m_.id(k), 0.5);
      touch_ring(k);
      ++n;
      after_operation();
    }
    rep_.splits += n;
    return n;
  }

  // Collapses ------------------------------------------------------------------------------------
  //! A triangle around the collapsing edge that survives it: (v, w1, w2) becomes (p, w1, w2).
  struct RingFace {
    Vertex v, w1, w2;
    Halfedge outer;  // w2 -> w1, in the unchanged face across (w1, w2)
    Vec3 n_old, n_new, n_out;  // n_out: of the face across (w1, w2)
    std::size_t next = 0;      // index in ring_ of the face across the new spoke (p, w2)
  };

  //! The sharpest crease (smallest cosine between the normals of neighbouring faces) and the number of
  //! folds among the edges in the star of a and b and the edges of its boundary, before a collapse of (a, b).
  std::pair<double, int> creases_before_collapse(Vertex a, Vertex b) const {
    double worst = 1;
    int folds = 0;
    auto add = [&](const Vec3& n, const Vec3& m) {
      const double c = normal_cos(n, m);
      worst = std::min(worst, c);
      folds += c < cos_fold_;
    };
    for (const Vertex v : {a, b}) {
      const Halfedge g0 = m_.halfedge(v);
      Halfedge g = g0;
      do {
        if (v == a || m_.to_vertex(g) != a)
          add(area_vector(m_.face(g)), area_vector(m_.face(SurfaceMesh::opposite(g))));
        g = m_.ccw_rotated(g);
      } while (g != g0);
    }
    for (const RingFace& r : ring_) add(r.n_old, r.n_out);
    return {worst, folds};
  }

  //! Whether a collapse of the edge (pa, pb) may sharpen a crease or add a fold (ImproveParams::
  //! crease_collapse_fraction): the edge is that much shorter than L_min and the one-ring around it (ring_, as
  //! try_collapse gathered it) spans at least L_min, so that a speck smaller than L_min is not folded up.
  //! Once the last resort is on (last_resort_), a collapse removing a triangle below kVeryBadAngleDeg (old_q) may
  //! go for any edge below L_min, and where its two-ring spans L_min: in a sheet thinner than L_min pressed flat
  //! by the alignment every edge may be shorter than L_min (resurfaced pcow at half-L voxels), its one-rings
  //! span less though the sheet is large, and needles and caps stayed below 2° (a cap's short edges are longer
  //! than the fraction: `gen splash` frame 25). Not before: allowing the two-ring from the start changed the
  //! default profile's runs for the worse (resurfaced samba: topology as the input's in 38 -> 35 of 40 frames,
  //! a trajectory where the other operations had removed such needles otherwise).
  bool crease_collapse_ok(const Vec3& pa, const Vec3& pb, double old_q) const {
    const bool wide = last_resort_ && old_q < q_very_bad_ && lcrease2_ > 0;  // fraction 0: no crease collapse
    if (!((pa - pb).squaredNorm() < (wide ? lmin2_ : lcrease2_))) return false;
    Vec3 lo = pa, hi = pa;
    for (const RingFace& r : ring_) {
      lo = lo.cwiseMin(pos(r.w1));
      hi = hi.cwiseMax(pos(r.w1));
    }
    if ((hi - lo).squaredNorm() >= lmin2_) return true;
    if (!wide) return false;
    for (const RingFace& r : ring_) {
      const Halfedge g0 = m_.halfedge(r.w1);
      Halfedge g = g0;
      do {
        lo = lo.cwiseMin(pos(m_.to_vertex(g)));
        hi = hi.cwiseMax(pos(m_.to_vertex(g)));
        g = m_.ccw_rotated(g);
      } while (g != g0);
    }
    return (hi - lo).squaredNorm() >= lmin2_;
  }

  std::size_t valence(Vertex v) const {
    std::size_t n = 0;
    const Halfedge g0 = m_.halfedge(v);
    Halfedge g = g0;
    do {
      ++n;
      g = m_.ccw_rotated(g);
    } while (g != g0);
    return n;
  }

  //! SurfaceMesh::is_collapse_ok for an interior edge in O(valence) with vertex stamps: the opposite
  //! corners differ and keep valence >= 3, the one-rings of the end points share only them (link
  //! condition) and the merged vertex keeps valence >= 3. Symmetric in the two directions.
  bool collapse_topology_ok(Halfedge h) {
    blocked_by_valence3_ = false;
    const Halfedge o = SurfaceMesh::opposite(h);
    if (m_.is_boundary(h) || m_.is_boundary(o)) return m_.is_collapse_ok(h);
    const Vertex a = m_.to_vertex(o), b = m_.to_vertex(h);
    const Vertex vl = m_.to_vertex(m_.next(h)), vr = m_.to_vertex(m_.next(o));
    if (vl == vr) return false;
    const std::size_t val_l = valence(vl), val_r = valence(vr);
    if (val_l <= 3 || val_r <= 3) {
      blocked_by_valence3_ = val_l == 3 || val_r == 3;
      return false;
    }
    if (vstamp_.size() < m_.vertices_size()) vstamp_.resize(m_.vertices_size(), 0);
    ++vstamp_counter_;
    std::size_t val_a = 0, val_b = 0;
    Halfedge g = m_.halfedge(b);
    const Halfedge gb = g;
    do {
      vstamp_[m_.to_vertex(g).idx] = vstamp_counter_;
      ++val_b;
      g = m_.ccw_rotated(g);
    } while (g != gb);
    g = m_.halfedge(a);
    const Halfedge ga = g;
    do {
      const Vertex w = m_.to_vertex(g);
      if (w != b && w != vl && w != vr && vstamp_[w.idx] == vstamp_counter_) return false;
      ++val_a;
      g = m_.ccw_rotated(g);
    } while (g != ga);
    return val_a + val_b >= 7;
  }

  //! Collapse e into its midpoint (§4.1, §4.4) if that keeps a closed 2-manifold without fold-over,
  //! zero-area triangle, new fold, edge longer than L_max or excess surface movement, and if the
  //! triangles get better as `mode` demands. With `dry_run` only report whether it could go and, in
  //! *dry_run, how far it would move the surface.
  bool try_collapse(Edge e, CollapseMode mode, double* dry_run = nullptr) {
    const Halfedge h = m_.halfedge(e, 0);
    if (!collapse_topology_ok(h)) return false;
    const Vertex a = m_.from_vertex(h), b = m_.to_vertex(h);
    const Vec3 p = 0.5 * (pos(a) + pos(b));
    const Face f0 = m_.face(h), f1 = m_.face(SurfaceMesh::opposite(h));
    // The two faces that vanish: (a, b, vl) and (b, a, vr).
    const Vec3 &pa = pos(a), &pb = pos(b);
    const Vec3 &pl = pos(m_.to_vertex(m_.next(h))), &pr = pos(m_.to_vertex(m_.next(SurfaceMesh::opposite(h))));
    double old_q = std::min(triangle_quality(pa, pb, pl), triangle_quality(pb, pa, pr));
    const Vec3 n0 = (pb - pa).cross(pl - pa), n1 = (pa - pb).cross(pr - pb);
    Vec3 n_ref = n0 + n1;
    double area_sum = n0.norm() + n1.norm();
    ring_.clear();
    for (const Vertex v : {a, b}) {
      const Halfedge g0 = m_.halfedge(v);
      Halfedge g = g0;
      do {
        const Face f = m_.face(g);
        if (f != f0 && f != f1) {
          const Halfedge gn = m_.next(g);
          RingFace r{v, m_.to_vertex(g), m_.to_vertex(gn), SurfaceMesh::opposite(gn), Vec3::Zero(), Vec3::Zero(),
                     Vec3::Zero()};
          const Vec3 &q = pos(v), &q1 = pos(r.w1), &q2 = pos(r.w2);
          if ((q1 - p).squaredNorm() > (mode == CollapseMode::Short ? lmax_short2_ : lmax2_)) return false;
          r.n_old = (q1 - q).cross(q2 - q);
          r.n_new = (q1 - p).cross(q2 - p);
          n_ref += r.n_old;
          area_sum += r.n_old.norm();
          old_q = std::min(old_q, triangle_quality(q, q1, q2));
          ring_.push_back(r);
        }
        g = m_.ccw_rotated(g);
      } while (g != g0);
    }
    // Where the neighbourhood is roughly a height field (its area vectors do not cancel out) no new face
    // may face away from it; around a thin tube or a fold that reference means nothing.
    const bool check_ref = mode != CollapseMode::Fold && n_ref.norm() >= 0.5 * area_sum;
    double new_q = 1, dev_local = 0;
    for (const RingFace& r : ring_) {
      const double ln_new = r.n_new.norm();
      if (!(ln_new > 0)) return false;
      const double ln_old = r.n_old.norm();
      // A degenerate old face has no normal to compare with; around a fold the old normals are what is
      // wrong, and the checks for new folds below judge the result instead.
      if (ln_old > 0 && mode != CollapseMode::Fold) {
        if (r.n_old.dot(r.n_new) <= 0) return false;  // fold-over
        dev_local = std::max(dev_local, std::abs((p - pos(r.v)).dot(r.n_old)) / ln_old);
      }
      if (check_ref && r.n_new.dot(n_ref) <= 0 && r.n_old.dot(n_ref) > 0) return false;
      dev_local = std::max(dev_local, std::abs((pos(r.v) - p).dot(r.n_new)) / ln_new);
      // In a cluster of short edges the needles around it get worse until their own short edge goes:
      // a Short collapse judges only the triangles it leaves without a short edge (such a needle may be
      // degenerate for a moment; its short edge is collapsed next, and the degenerate pass ends it).
      const Vec3 &q1 = pos(r.w1), &q2 = pos(r.w2);
      if (mode == CollapseMode::Short && std::min({(q1 - p).squaredNorm(), (q2 - p).squaredNorm(),
                                                   (q2 - q1).squaredNorm()}) < lmin2_)
        continue;
      new_q = std::min(new_q, triangle_quality(p, q1, q2));
    }
    if (!(new_q > kDegenerateQuality)) return false;
    switch (mode) {
      case CollapseMode::Short:
        if (new_q < q_min_ && new_q < old_q && new_q < q_floor_) return false;
        break;
      case CollapseMode::Improve:
        if (!(new_q > old_q)) return false;
        break;
      case CollapseMode::Fold:
        break;
    }
    // No new fold across the new spokes (p, w2) and the ring edges (w1, w2). Where the neighbourhood is
    // creased already (thin sheets and tubes a few voxels across) a collapse may go if it neither makes
    // the sharpest crease sharper nor adds a fold; a fold collapse must leave none.
    int new_folds = 0;
    const std::size_t n_ring = ring_.size();
    for (std::size_t i = 0; i < n_ring; ++i) {
      RingFace& r = ring_[i];
      // The face across the new spoke (p, w2): the next one around the same end point, except where the
      // two fans meet.
      r.next = i + 1 < n_ring && ring_[i + 1].w1 == r.w2 ? i + 1 : n_ring;
      for (std::size_t j = 0; r.next == n_ring && j < n_ring; ++j)
        if (ring_[j].w1 == r.w2) r.next = j;
      const Vertex x = m_.to_vertex(m_.next(r.outer));
      r.n_out = (pos(r.w1) - pos(r.w2)).cross(pos(x) - pos(r.w2));
      if (r.next < n_ring) new_folds += normals_fold(r.n_new, ring_[r.next].n_new);
      new_folds += normals_fold(r.n_new, r.n_out);
    }
    if (new_folds > 0) {
      if (mode == CollapseMode::Fold) return false;
      double new_worst = 1;
      for (const RingFace& r : ring_) {
        if (r.next < n_ring) new_worst = std::min(new_worst, normal_cos(r.n_new, ring_[r.next].n_new));
        new_worst = std::min(new_worst, normal_cos(r.n_new, r.n_out));
      }
      const auto [old_worst, old_folds] = creases_before_collapse(a, b);
      if ((new_worst < old_worst || new_folds > old_folds) && !crease_collapse_ok(pa, pb, old_q)) return false;
    }
    // Short collapses are bounded too: on a ridge the midpoint of an edge across it cuts the ridge off, and
    // a few such cuts in a row moved the surface of resurfaced frames by 0.34 L (elephant frame 3); the
    // short edges they leave are lengthened by a slide instead (try_lengthen). Fold collapses are exempt
    // (fold_pass picks the gentlest fold removal by its exact deviation).
    if (mode != CollapseMode::Fold && dev_local > operation_bound(old_q)) return false;
    if (mode == CollapseMode::Fold) {
      const double dev = collapse_deviation(a, b, p);
      if (dev > max_dev_) return false;
      if (dry_run) *dry_run = dev;
    }
    if (dry_run) return true;
    const VertexId k = m_.take_fresh_id();
    if (events_) events_->record_collapse(m_.id(a), m_.id(b), k);
    m_.collapse(h, p);
    m_.set_id(b, k);
    touch_ring(b);
    ++rep_.collapses;
    after_operation();
    return true;
  }

  //! The local deviation of a collapse of (a, b) into p whose surviving ring faces are in ring_ (filled by
  //! try_collapse): the larger of the distances from a and b to the new faces and from p to the old ones,
  //! exact distances to triangles (distances to their planes understate the cut of a knife-edge crease).
  double collapse_deviation(Vertex a, Vertex b, const Vec3& p) const {
    double da = std::numeric_limits<double>::infinity(), db = da, dp = da;
    const Vec3 &pa = pos(a), &pb = pos(b);
    for (const RingFace& r : ring_) {
      const Vec3 &q1 = pos(r.w1), &q2 = pos(r.w2);
      da = std::min(da, (closest_point_on_triangle(pa, p, q1, q2) - pa).squaredNorm());
      db = std::min(db, (closest_point_on_triangle(pb, p, q1, q2) - pb).squaredNorm());
      dp = std::min(dp, (closest_point_on_triangle(p, pos(r.v), q1, q2) - p).squaredNorm());
    }
    return std::sqrt(std::max({da, db, dp}));
  }

  //! An opposite corner of valence 3 blocks a collapse of e (it would become a loop): collapse that
  //! vertex into a neighbour first (its shortest edge that can go), then e if it is still there.
  std::size_t collapse_unblocking(Edge e, CollapseMode mode) {
    const Halfedge h = m_.halfedge(e, 0);
    for (const Halfedge side : {h, SurfaceMesh::opposite(h)}) {
      const Vertex corner = m_.to_vertex(m_.next(side));
      if (m_.valence(corner) != 3) continue;
      const Vertex a = m_.from_vertex(h), b = m_.to_vertex(h);
      std::array<std::pair<double, Edge>, 3> spokes;
      int k = 0;
      const Halfedge g0 = m_.halfedge(corner);
      Halfedge g = g0;
      do {
        spokes[k++] = {length2(SurfaceMesh::edge(g)), SurfaceMesh::edge(g)};
        g = m_.ccw_rotated(g);
      } while (g != g0 && k < 3);
      std::sort(spokes.begin(), spokes.end());
      for (const auto& [l2, spoke] : spokes) {
        // As the last resort a fold-mode collapse (the exact deviation bounds it, no new fold may result): the
        // midpoint of a spoke of a spike much shorter than L_min turns a face over against the neighbourhood.
        if (!try_collapse(spoke, CollapseMode::Short) && !(last_resort_ && try_collapse(spoke, CollapseMode::Fold)))
          continue;
        if (m_.is_deleted(a) || m_.is_deleted(b)) return 1;
        const Halfedge ab = m_.find_halfedge(a, b);
        return 1 + (ab.is_valid() && try_collapse(SurfaceMesh::edge(ab), mode));
      }
    }
    return 0;
  }

  std::size_t collapse_or_unblock(Edge e, CollapseMode mode) {
    if (try_collapse(e, mode)) return 1;
    return blocked_by_valence3_ ? collapse_unblocking(e, mode) : 0;
  }

  std::size_t short_edge_pass(const Candidates& c) {
    std::size_t n = 0;
    for (const auto& [key, ei] : c) {
      const Edge e(ei);
      if (m_.is_deleted(e) || length2(e) >= lmin2_) continue;
      const Vertex a = m_.vertex(e, 0), b = m_.vertex(e, 1);
      const std::size_t done = collapse_or_unblock(e, CollapseMode::Short);
      if (!done) unfixed_short_.emplace_back(a.idx, b.idx);
      n += done;
    }
    return n;
  }

  // Bad triangles: flip where flat, else collapse ------------------------------------------------
  //! Flip e (§7) if the two faces are nearly coplanar, the new edge is within [L_min, L_max], the flip
  //! moves the surface little, creates no fold and strictly raises the smallest angle of the pair.
  bool try_flip(Edge e) {
    if (!m_.is_flip_ok(e)) return false;
    const Halfedge h0 = m_.halfedge(e, 0), h1 = m_.halfedge(e, 1);
    const Vertex a = m_.from_vertex(h0), b = m_.to_vertex(h0);
    const Vertex c = m_.to_vertex(m_.next(h0)), d = m_.to_vertex(m_.next(h1));
    const Vec3 &pa = pos(a), &pb = pos(b), &pc = pos(c), &pd = pos(d);
    const double l2 = (pc - pd).squaredNorm();
    if (l2 > lmax2_ || l2 < lmin2_) return false;
    // Old faces (a,b,c), (b,a,d); new faces (c,a,d), (d,b,c).
    const Vec3 n0 = (pb - pa).cross(pc - pa), n1 = (pa - pb).cross(pd - pb);
    const Vec3 m0 = (pa - pc).cross(pd - pc), m1 = (pb - pd).cross(pc - pd);
    if (!normals_within(n0, n1, cos_flip_bend_) || !normals_within(m0, m1, cos_flip_bend_)) return false;
    for (const Vec3* n : {&n0, &n1})
      for (const Vec3* q : {&m0, &m1})
        if (n->dot(*q) <= 0) return false;
    const double old_q = std::min(triangle_quality(pa, pb, pc), triangle_quality(pb, pa, pd));
    const double new_q = std::min(triangle_quality(pc, pa, pd), triangle_quality(pd, pb, pc));
    if (!(new_q > old_q)) return false;
    // The outer edges (b,c), (c,a), (a,d), (d,b) change one face each: no new fold there.
    const Halfedge outer[4] = {m_.next(h0), m_.next(m_.next(h0)), m_.next(h1), m_.next(m_.next(h1))};
    const Vec3* new_normal[4] = {&m1, &m0, &m0, &m1};
    for (int k = 0; k < 4; ++k) {
      const Halfedge o = SurfaceMesh::opposite(outer[k]);
      if (normals_fold(*new_normal[k], area_vector(m_.face(o)))) return false;
    }
    const double dev_local = segment_distance(pa, pb, pc, pd);
    if (dev_local > operation_bound(old_q)) return false;
    m_.flip(e);
    for (const Vertex v : {a, b, c, d}) touch(v);
    ++rep_.flips;
    after_operation();
    return true;
  }

  // Tangential relaxation ------------------------------------------------------------------------
  //! A triangle around v before and after v moves: (v, w1, w2), with the face across (w1, w2).
  struct StarFace {
    Vertex w1, w2;
    Vec3 n_old, n_new, n_out;
    bool degenerate;  // before the move: its normal is noise
  };

  //! The triangles around v (star_) before a move, the sum of their area vectors (false when it vanishes),
  //! the centroid of its one-ring and the smallest triangle quality.
  bool gather_star(Vertex v, Vec3& centroid, Vec3& normal, double& old_q) {
    star_.clear();
    const Vec3& p0 = pos(v);
    centroid = Vec3::Zero();
    normal = Vec3::Zero();
    old_q = 1;
    const Halfedge g0 = m_.halfedge(v);
    Halfedge g = g0;
    do {
      const Halfedge gn = m_.next(g);
      StarFace s{m_.to_vertex(g), m_.to_vertex(gn), Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), false};
      const Vec3 &q1 = pos(s.w1), &q2 = pos(s.w2);
      s.n_old = (q1 - p0).cross(q2 - p0);
      s.n_out = (q1 - q2).cross(pos(m_.to_vertex(m_.next(SurfaceMesh::opposite(gn)))) - q2);
      const double q = triangle_quality(p0, q1, q2);
      s.degenerate = !(q > kDegenerateQuality);
      old_q = std::min(old_q, q);
      normal += s.n_old;
      centroid += q1;
      star_.push_back(s);
      g = m_.ccw_rotated(g);
    } while (g != g0);
    centroid /= double(star_.size());
    return normal.squaredNorm() > 0;
  }

  //! The local deviation of moving the centre of star_ from p0 to q: the larger of the distances from p0
  //! to the moved triangles and from q to the old ones (exact distances to triangles).
  double star_deviation(const Vec3& p0, const Vec3& q) const {
    double d_old = std::numeric_limits<double>::infinity(), d_new = d_old;
    for (const StarFace& s : star_) {
      const Vec3 &q1 = pos(s.w1), &q2 = pos(s.w2);
      d_old = std::min(d_old, (closest_point_on_triangle(p0, q, q1, q2) - p0).squaredNorm());
      d_new = std::min(d_new, (closest_point_on_triangle(q, p0, q1, q2) - q).squaredNorm());
    }
    return std::sqrt(std::max(d_old, d_new));
  }

  //! Whether moving the centre of star_ to q inverts no triangle, makes none degenerate, keeps its edges
  //! within L_max and adds no fold nor sharpens a crease beyond min_dihedral; *new_q: the smallest
  //! quality of the moved triangles.
  bool star_move_ok(const Vec3& q, double* new_q, int* folds_removed = nullptr, double crease_slack = 0,
                    std::pair<double, double>* worst = nullptr) {
    *new_q = 1;
    for (StarFace& s : star_) {
      const Vec3 &q1 = pos(s.w1), &q2 = pos(s.w2);
      s.n_new = (q1 - q).cross(q2 - q);
      if ((q1 - q).squaredNorm() > lmax2_ || !(s.n_new.squaredNorm() > 0) || (!s.degenerate && s.n_old.dot(s.n_new) <= 0))
        return false;
      *new_q = std::min(*new_q, triangle_quality(q, q1, q2));
    }
    if (!(*new_q > kDegenerateQuality)) return false;
    double old_worst = 1, new_worst = 1;
    int old_folds = 0, new_folds = 0;
    // A degenerate triangle had no normal: the crease it shows once it has one is no new fold (the fold
    // pass judges it next round).
    for (std::size_t i = 0; i < star_.size(); ++i) {
      const StarFace &s = star_[i], &next = star_[(i + 1) % star_.size()];
      if (s.degenerate) continue;
      for (const auto& [n, m, skip] : {std::tuple{s.n_old, next.n_old, next.degenerate}, std::tuple{s.n_old, s.n_out, false}}) {
        if (skip) continue;
        const double c = normal_cos(n, m);
        old_worst = std::min(old_worst, c);
        old_folds += c < cos_fold_;
      }
      for (const auto& [n, m, skip] : {std::tuple{s.n_new, next.n_new, next.degenerate}, std::tuple{s.n_new, s.n_out, false}}) {
        if (skip) continue;
        const double c = normal_cos(n, m);
        new_worst = std::min(new_worst, c);
        new_folds += c < cos_fold_;
      }
    }
    if (folds_removed) *folds_removed = old_folds - new_folds;
    if (worst) *worst = {old_worst, new_worst};
    return !(new_worst < cos_fold_ && (new_worst < old_worst - crease_slack || new_folds > old_folds));
  }

  void move_vertex(Vertex v, const Vec3& q) {
    m_.position(v) = q;
    touch_ring(v);
    ++rep_.relaxations;
    after_operation();
  }

  //! Move v towards the centroid of its one-ring within its tangent plane (full step, else a half or a
  //! quarter) if that raises the smallest angle of its triangles, inverts none, adds no fold, keeps its
  //! edges within L_max and the surface within the movement bound. The last resort for a bad triangle that
  //! no flip or collapse can fix (a needle whose short edge would pinch a thin tube, a cap between creases).
  //! The vertex keeps its id: it stands for the same surface point, moved a little along the surface as the
  //! alignment moves every vertex; event lists record re-sampling only (§4.4), so no event is recorded.
  bool try_relax(Vertex v) {
    Vec3 centroid, normal;
    double old_q = 1;
    if (!gather_star(v, centroid, normal, old_q)) return false;
    const Vec3& p0 = pos(v);
    const Vec3 nv = normal.normalized();
    Vec3 d = centroid - p0;
    d -= d.dot(nv) * nv;
    for (const double t : {1.0, 0.5, 0.25}) {
      const Vec3 q = p0 + t * d;
      double new_q = 1;
      // The whole step counts against the movement bound: across a crease or off the end of a sliver the
      // tangent plane is not the surface, so distances to the face planes would underestimate the move.
      const double dev_local = t * d.norm();
      // Around a triangle below 2° any gain counts; above, only a clear one (no creeping on).
      const double gain_floor = old_q < q_very_bad_ ? old_q : kRelaxGainFactor * old_q + kRelaxGainMin;
      if (dev_local > operation_bound(old_q) || !star_move_ok(q, &new_q) || !(new_q > gain_floor))
        continue;
      move_vertex(v, q);
      return true;
    }
    return false;
  }

  //! A removal of a fold: move `v` to `q` (when v is valid) or collapse `e`, with its local deviation.
  struct FoldFix {
    double dev = std::numeric_limits<double>::infinity();
    Vertex v;
    Vec3 q = Vec3::Zero();
    Edge e;
  };

  //! Moves of v towards `target` (else the centroid of its one-ring; from a sixteenth of the way up to the
  //! whole: across a fold the tangent plane means nothing) that remove a fold, add none, give no triangle a
  //! new angle below min_angle (below asin(q_keep_cap) where that is lower) and, with keep_lengths, shorten
  //! no edge below L_min (which a short collapse would then remove, moving the surface again); the shortest
  //! such move goes into `best` if it moves the surface less (star_deviation). Where a crease is barely a
  //! fold a small move rounds it off.
  void unfold_candidates(Vertex v, FoldFix& best, bool keep_lengths, const Vec3* target = nullptr,
                         double q_keep_cap = 1) {
    Vec3 centroid, normal;
    double old_q = 1;
    if (!gather_star(v, centroid, normal, old_q)) return;
    const Vec3 p0 = pos(v), d = (target ? *target : centroid) - p0;
    const double q_keep = std::min({old_q, q_min_, q_keep_cap});
    const auto ok = [&](double t) {
      double new_q = 1;
      int removed = 0;
      const Vec3 q = p0 + t * d;
      if (keep_lengths)
        for (const StarFace& f : star_)
          if ((pos(f.w1) - q).squaredNorm() < lmin2_ && (pos(f.w1) - p0).squaredNorm() >= lmin2_) return false;
      return star_move_ok(q, &new_q, &removed) && removed > 0 && new_q >= q_keep;
    };
    // The shortest step that works: the first of a coarse sequence, refined by bisection.
    double lo = 0, hi = -1;
    for (const double t : {0.0625, 0.125, 0.25, 0.5, 1.0}) {
      if (ok(t)) {
        hi = t;
        break;
      }
      lo = t;
    }
    if (hi < 0) return;
    for (int i = 0; i < kUnfoldBisections; ++i) {
      const double mid = 0.5 * (lo + hi);
      (ok(mid) ? hi : lo) = mid;
    }
    const Vec3 q = p0 + hi * d;
    const double dev = star_deviation(p0, q);
    if (dev <= max_dev_ && dev < best.dev) best = {dev, v, q, Edge()};
  }

  //! The last resort for an edge below L_min that no collapse can remove (its collapse would pinch a
  //! handle or a sheet thinner than L_min, or sharpen a crease into a fold): slide v within its tangent
  //! plane, towards the centroid of its one-ring or straight away from `other`, so that the edge reaches
  //! L_min, v has fewer short edges than before, no triangle of its star gets a new angle below
  //! min_angle (or worse than before) and no fold appears. The move is at most L_min / 2, as a collapse of
  //! the edge would move v. All or nothing, so a second call refuses what the first refused (fixed point).
  //! With it and the short collapses' bound (try_collapse), edges below L_min on frames 1-3 of `gen
  //! resurface` (128 voxels) went from 38/32/27 (elephant), 18/19/18 (samba), 25/31/26 (pcow) to 4/4/0,
  //! 0/0/0, 0/9/2, most of the rest on handles thinner than L_min (tests/kernels/improve/improve_data_test).
  bool try_lengthen(Vertex v, Vertex other) {
    Vec3 centroid, normal;
    double old_q = 1;
    if (!gather_star(v, centroid, normal, old_q)) return false;
    const Vec3 p0 = pos(v), po = pos(other);
    std::size_t old_short = 0;
    for (const StarFace& s : star_) old_short += (pos(s.w1) - p0).squaredNorm() < lmin2_;
    const Vec3 nv = normal.normalized();
    Vec3 to_c = centroid - p0, away = p0 - po;
    to_c -= to_c.dot(nv) * nv;
    away -= away.dot(nv) * nv;
    std::array<Vec3, 3> moves{p0 + to_c, p0 + 0.5 * to_c, p0};
    if (away.squaredNorm() > 0) {
      // The step along `away` that makes |v - other| = 1.01 L_min.
      const Vec3 u = away.normalized(), r = p0 - po;
      const double target = 1.01 * lmin_, b = r.dot(u), disc = b * b - r.squaredNorm() + target * target;
      if (disc >= 0) moves[2] = p0 + (std::sqrt(disc) - b) * u;
    }
    const double q_keep = std::min(old_q, q_min_);
    for (const Vec3& q : moves) {
      const double dev_local = (q - p0).norm();
      if (!(dev_local > 0) || dev_local > 0.5 * lmin_ || (q - po).squaredNorm() < lmin2_) continue;
      std::size_t new_short = 0;
      for (const StarFace& s : star_) new_short += (pos(s.w1) - q).squaredNorm() < lmin2_;
      double new_q = 1;
      if (new_short >= old_short || !star_move_ok(q, &new_q) || new_q < q_keep ||
          star_deviation(p0, q) > operation_bound(old_q))
        continue;
      move_vertex(v, q);
      return true;
    }
    return false;
  }

  //! Flip (where flat), else collapse one of its edges (shortest first); else remember it for relax_pass.
  bool fix_bad_triangle(Face f) {
    std::array<std::pair<double, Edge>, 3> edges;
    Halfedge h = m_.halfedge(f);
    for (int k = 0; k < 3; ++k, h = m_.next(h)) {
      const Edge e = SurfaceMesh::edge(h);
      edges[k] = {length2(e), e};
    }
    std::sort(edges.begin(), edges.end());
    if (p_.enable_flips)
      for (int k = 2; k >= 0; --k)
        if (try_flip(edges[k].second)) return true;
    for (const auto& [len, e] : edges)
      if (collapse_or_unblock(e, CollapseMode::Improve)) return true;
    unfixed_.push_back(f.idx);
    return false;
  }

  //! Relax a corner of each triangle that the last round could not fix and that is still bad: the corner
  //! opposite its longest edge (the largest angle) first, then the ends of that edge.
  std::size_t relax_pass() {
    std::size_t n = 0;
    std::vector<std::pair<Index, Index>> shorts;
    shorts.swap(unfixed_short_);
    for (const auto& [ai, bi] : shorts) {
      const Vertex a(ai), b(bi);
      if (m_.is_deleted(a) || m_.is_deleted(b) || !m_.find_halfedge(a, b).is_valid()) continue;
      if ((pos(a) - pos(b)).squaredNorm() >= lmin2_) continue;
      n += try_lengthen(a, b) || try_lengthen(b, a);
    }
    std::sort(unfixed_.begin(), unfixed_.end());
    unfixed_.erase(std::unique(unfixed_.begin(), unfixed_.end()), unfixed_.end());
    std::vector<Index> faces;
    faces.swap(unfixed_);
    for (const Index fi : faces) {
      const Face f(fi);
      if (!is_bad(f)) continue;
      Halfedge longest = m_.halfedge(f);
      for (Halfedge h = m_.next(longest); h != m_.halfedge(f); h = m_.next(h))
        if (length2(SurfaceMesh::edge(h)) > length2(SurfaceMesh::edge(longest))) longest = h;
      for (const Vertex v : {m_.to_vertex(m_.next(longest)), m_.from_vertex(longest), m_.to_vertex(longest)})
        if (try_relax(v)) {
          ++n;
          break;
        }
    }
    return n;
  }

  std::size_t bad_triangle_pass(const Candidates& c) {
    std::size_t n = 0;
    for (const auto& [key, fi] : c) {
      const Face f(fi);
      if (!is_bad(f)) continue;
      n += fix_bad_triangle(f);
    }
    return n;
  }

  // Folds ----------------------------------------------------------------------------------------
  //! The gentlest removal of the fold across e: moves of the four corners of its two faces
  //! (unfold_candidates) and collapses of `edges` (e and the other edges of its faces).
  FoldFix gentlest_fold_fix(Edge e, const std::array<Edge, 5>& edges, bool keep_lengths) {
    FoldFix best;
    if (p_.enable_relaxation) {
      const Halfedge h0 = m_.halfedge(e, 0), h1 = m_.halfedge(e, 1);
      for (const Vertex v : {m_.to_vertex(m_.next(h0)), m_.to_vertex(m_.next(h1)), m_.to_vertex(h0), m_.to_vertex(h1)})
        unfold_candidates(v, best, keep_lengths);
      // The ends of the folded edge also towards the middle of the opposite corners: straight into a
      // knife-edge crease, where the one-ring's centroid lies along the crease.
      const Vec3 mid = 0.5 * (pos(m_.to_vertex(m_.next(h0))) + pos(m_.to_vertex(m_.next(h1))));
      for (const Vertex v : {m_.to_vertex(h0), m_.to_vertex(h1)}) unfold_candidates(v, best, keep_lengths, &mid);
    }
    for (const Edge x : edges) {
      double dev = 0;
      if (try_collapse(x, CollapseMode::Fold, &dev) && dev < best.dev) best = {dev, Vertex(), Vec3::Zero(), x};
    }
    return best;
  }

  //! The last resort for a fold in a feature thinner than L_min where no collapse may go (each would pinch
  //! the feature or add a fold) and no move towards the inside works: a tube three edges around, a flat
  //! tetrahedron left of a speck. Moves one corner of the fold's faces outwards, along its star's normal
  //! or away from the centroid of its one-ring (unfold_candidates: the shortest move that removes the fold
  //! under the same checks, except that a triangle may be left with an angle down to 2° instead of min_angle: a
  //! fold breaks the quality bounds, a small angle is tolerated, and the bad-triangle pass works on it next).
  //! `topotrack improve` on every frame of the raw captures in ../shared/data: folds left elephant
  //! 2449 -> 64, pcow 513 -> 144, samba 3 -> 0.
  void inflate_fold(Edge e, FoldFix& best) {
    const Halfedge h0 = m_.halfedge(e, 0), h1 = m_.halfedge(e, 1);
    for (const Vertex v : {m_.to_vertex(m_.next(h0)), m_.to_vertex(m_.next(h1)), m_.to_vertex(h0), m_.to_vertex(h1)}) {
      Vec3 centroid, normal;
      double old_q = 1;
      if (!gather_star(v, centroid, normal, old_q)) continue;
      const Vec3 p0 = pos(v);
      const Vec3 along_normal = p0 + lmin_ * normal.normalized(), away = 2 * p0 - centroid;
      unfold_candidates(v, best, false, &along_normal, q_floor_);
      unfold_candidates(v, best, false, &away, q_floor_);
    }
  }

  //! The last resort for a fold on a crease sharper than min_dihedral that runs across several edges
  //! (the input's own crease, sampled by a mesh at another resolution): every removal above folds the next
  //! edge along the crease. Soften the crease instead: of the moves of a corner of the fold's faces towards
  //! the centroid of its one-ring (a sixteenth of the way up to the whole), the one that leaves the sharpest
  //! crease of its star the least sharp, if that is at least kSoftenGainDeg less sharp than before, leaves no
  //! triangle below 2° that was not (as inflate_fold: a fold breaks the quality bounds, a small angle is
  //! tolerated and the bad-triangle pass works on it next) and moves the surface by at most
  //! max_operation_deviation. It may fold an edge beside the old fold, but never as sharply as the new
  //! sharpest crease: each move raises the sharpest crease it touches, so the rounds that follow cannot
  //! cycle, and they remove those folds as any other. On resurfaced pcow frame 19 (capture profile on the
  //! extraction grid): a 33.5° fold beside the input's 51.6° crease, where each removal added a fold, gone
  //! after one such move and one collapse; frame 27 of the capture profile's own lattice: a 21.3° fold whose
  //! softening moves all took a 6.6° triangle to 6.1° (docs/results.md, 2026-11-25, later).
  void soften_fold(Edge e, FoldFix& best) {
    const Halfedge h0 = m_.halfedge(e, 0), h1 = m_.halfedge(e, 1);
    double best_worst = -2;
    for (const Vertex v : {m_.to_vertex(m_.next(h0)), m_.to_vertex(m_.next(h1)), m_.to_vertex(h0), m_.to_vertex(h1)}) {
      Vec3 centroid, normal;
      double old_q = 1;
      if (!gather_star(v, centroid, normal, old_q)) continue;
      const Vec3 p0 = pos(v), d = centroid - p0;
      const double q_keep = std::min(old_q, q_floor_);
      for (const double t : {0.0625, 0.125, 0.25, 0.5, 1.0}) {
        const Vec3 q = p0 + t * d;
        double new_q = 1;
        std::pair<double, double> worst{1, -2};  // stays so where the move inverts or degenerates a triangle
        star_move_ok(q, &new_q, nullptr, 0, &worst);  // its verdict on folds is the one not wanted here
        const auto [old_worst, new_worst] = worst;
        if (new_q < q_keep || new_worst <= best_worst ||
            !(std::acos(std::clamp(old_worst, -1.0, 1.0)) - std::acos(std::clamp(new_worst, -1.0, 1.0)) >=
              kSoftenGainDeg * kDegToRad))
          continue;
        const double dev = star_deviation(p0, q);
        if (dev > op_dev_) continue;
        best_worst = new_worst;
        best = {dev, v, q, Edge()};
      }
    }
  }

  //! Slide c straight towards `end`, a corner of a face of c (so that face keeps its plane), 0.4 of the way
  //! or less, if no edge of c gets shorter than L_min, no crease gets sharper, no triangle gets a new angle
  //! below min_angle and the surface moves by at most half of max_operation_deviation; adds the move to
  //! *dev. Does not count as an operation (prepare_knife_edge decides).
  bool slide_towards(Vertex c, Vertex end, double* dev) {
    Vec3 centroid, normal;
    double old_q = 1;
    if (!gather_star(c, centroid, normal, old_q)) return false;
    const Vec3 p0 = pos(c), d = pos(end) - p0;
    const double q_keep = std::min(old_q, q_min_);
    for (const double t : {0.4, 0.3, 0.2, 0.1}) {
      const Vec3 q = p0 + t * d;
      bool short_edge = false;
      for (const StarFace& f : star_) short_edge = short_edge || (pos(f.w1) - q).squaredNorm() < lmin2_;
      double new_q = 1;
      // The faces that keep their plane come out with rounding noise in their normals.
      if (short_edge || !star_move_ok(q, &new_q, nullptr, kCreaseNoise) || new_q < q_keep) continue;
      const double dev_slide = star_deviation(p0, q);
      if (dev_slide > 0.5 * op_dev_) continue;
      m_.position(c) = q;
      *dev = std::max(*dev, dev_slide);
      return true;
    }
    return false;
  }

  //! A fold whose gentlest removal moves the surface more than max_operation_deviation lies on a knife-edge
  //! crease: its edge must sink into the wedge by about 0.4 of the distance to the opposite corners before
  //! its dihedral angle reaches 45°. Sliding those corners along the flanks towards the edge first makes
  //! the cut shallower (on the tip of a 28° fin of resurfaced pcow frame 3: 0.37 L -> 0.24 L). The slides are
  //! kept if the removal then moves the surface less, else undone (positions restored bit for bit).
  void prepare_knife_edge(Edge e, const std::array<Edge, 5>& edges, FoldFix& best) {
    const Halfedge h0 = m_.halfedge(e, 0), h1 = m_.halfedge(e, 1);
    const Vertex c = m_.to_vertex(m_.next(h0)), d = m_.to_vertex(m_.next(h1));
    const Vec3 pc = pos(c), pd = pos(d);
    double dev = 0;
    bool moved_c = false, moved_d = false;
    for (const Vertex end : {m_.to_vertex(h0), m_.to_vertex(h1)}) {
      if (!moved_c) moved_c = slide_towards(c, end, &dev);
      if (!moved_d) moved_d = slide_towards(d, end, &dev);
    }
    if (!moved_c && !moved_d) return;
    const FoldFix alt = gentlest_fold_fix(e, edges, true);
    if (std::max(alt.dev, dev) < best.dev) {
      best = alt;
      for (const auto& [v, moved] : {std::pair{c, moved_c}, std::pair{d, moved_d}})
        if (moved) {
          touch_ring(v);
          ++rep_.relaxations;
          after_operation();
        }
      return;
    }
    m_.position(c) = pc;
    m_.position(d) = pd;
  }


  //! Remove each fold (§4.1) by the gentlest of: a collapse of the folded edge or of another edge of its
  //! two faces, a move of one of their four corners (unfold_candidates). Fold removals are exempt from the
  //! deviation bounds, so they are compared by their exact local deviation (collapse_deviation,
  //! star_deviation), each move the shortest that works, on a knife-edge crease after prepare_knife_edge:
  //! on resurfaced pcow frames, whose level set has such creases along the plane of symmetry (dihedral
  //! angles down to 20°), the first removal that could go moved the surface by 0.5 L, the gentlest collapse
  //! by plane distances still by 0.45 L, this choice by 0.24 L (frame 3: 0.0029, 0.0025, 0.0013 of the
  //! diagonal); never more than max_surface_deviation. Where none of these can go, an outward move
  //! (inflate_fold); where that fails too, a move that softens the crease (soften_fold); where nothing can,
  //! unblock a valence-3 corner first.
  std::size_t fold_pass(const Candidates& c) {
    std::size_t n = 0;
    for (const auto& [key, ei] : c) {
      const Edge e(ei);
      if (m_.is_deleted(e) || !is_fold(e)) continue;
      std::array<Edge, 5> edges;
      edges[0] = e;
      int k = 1;
      for (const Halfedge h : {m_.halfedge(e, 0), m_.halfedge(e, 1)}) {
        edges[k++] = SurfaceMesh::edge(m_.next(h));
        edges[k++] = SurfaceMesh::edge(m_.prev(h));
      }
      FoldFix best = gentlest_fold_fix(e, edges, true);
      if (p_.enable_relaxation && best.dev > op_dev_) prepare_knife_edge(e, edges, best);
      if (!best.v.is_valid() && !best.e.is_valid()) best = gentlest_fold_fix(e, edges, false);
      if (!best.v.is_valid() && !best.e.is_valid() && p_.enable_relaxation) inflate_fold(e, best);
      if (!best.v.is_valid() && !best.e.is_valid() && p_.enable_relaxation) soften_fold(e, best);
      if (best.v.is_valid()) {
        move_vertex(best.v, best.q);
        ++n;
        continue;
      }
      if (best.e.is_valid() && try_collapse(best.e, CollapseMode::Fold)) {
        ++n;
        continue;
      }
      for (const Edge x : edges)
        if (collapse_or_unblock(x, CollapseMode::Fold)) {
          ++n;
          break;
        }
    }
    return n;
  }

  SurfaceMesh& m_;
  const ImproveParams& p_;
  EventList* events_;
  ImproveReport& rep_;
  double lmax_short2_ = 0;
  double lcrease2_ = 0;
  double lmin_ = 0, lmax_ = 0, lmin2_ = 0, lmax2_ = 0, max_dev_ = 0, op_dev_ = 0, q_very_bad_ = 0;
  double q_min_ = 0, q_bad_ = 0, q_bad2_ = 0, q_floor_ = 0, cos_fold_ = 0, cos_flip_bend_ = 1;
  std::vector<std::uint8_t> fbad_;  // survey: face with a small angle
  std::vector<std::uint8_t> eflag_;
  std::vector<RingFace> ring_;
  std::vector<StarFace> star_;
  std::vector<Index> touched_, local_edges_, local_faces_;
  std::vector<Index> unfixed_;  // bad triangles that no flip or collapse fixed since the last relax_pass
  std::vector<std::pair<Index, Index>> unfixed_short_;  // short edges (end points) no collapse removed
  bool relaxed_ = false;      // relax_pass moved a vertex (run)
  bool last_resort_ = false;  // a fixed point with a triangle below kVeryBadAngleDeg was reached (run)
  std::vector<std::uint8_t> vtouched_;
  std::vector<std::uint32_t> estamp_, fstamp_;
  std::uint32_t stamp_ = 0;
  std::vector<std::uint32_t> vstamp_;
  std::uint32_t vstamp_counter_ = 0;
  bool blocked_by_valence3_ = false;
};

void check_params(const ImproveParams& params) {
  if (!(params.ratio > 1)) TT_THROW(InvalidInput, "improve_mesh: ratio must be > 1, got " << params.ratio);
  if (!(params.min_angle_deg >= 0 && params.min_angle_deg < 60))
    TT_THROW(InvalidInput, "improve_mesh: min_angle_deg must be in [0, 60), got " << params.min_angle_deg);
  if (!(params.min_dihedral_deg >= 0 && params.min_dihedral_deg < 180))
    TT_THROW(InvalidInput, "improve_mesh: min_dihedral_deg must be in [0, 180), got " << params.min_dihedral_deg);
  if (params.max_iterations < 0)
    TT_THROW(InvalidInput, "improve_mesh: max_iterations must be >= 0, got " << params.max_iterations);
  if (!(params.max_operation_deviation >= 0))
    TT_THROW(InvalidInput, "improve_mesh: max_operation_deviation must be >= 0, got " << params.max_operation_deviation);
  if (!(params.max_surface_deviation >= 0))
    TT_THROW(InvalidInput, "improve_mesh: max_surface_deviation must be >= 0, got " << params.max_surface_deviation);
  if (!(params.max_flip_bend_deg >= 0 && params.max_flip_bend_deg <= 180))
    TT_THROW(InvalidInput, "improve_mesh: max_flip_bend_deg must be in [0, 180], got " << params.max_flip_bend_deg);
  if (!(params.crease_collapse_fraction >= 0 && params.crease_collapse_fraction <= 1))
    TT_THROW(InvalidInput,
             "improve_mesh: crease_collapse_fraction must be in [0, 1], got " << params.crease_collapse_fraction);
  if (!std::isfinite(params.target_edge_length))
    TT_THROW(InvalidInput, "improve_mesh: target_edge_length must be finite");
}

}  // namespace

double mean_edge_length_parallel(const SurfaceMesh& mesh) {
  constexpr std::size_t kChunk = 8192;
  const std::size_t ne = mesh.edges_size(), chunks = (ne + kChunk - 1) / kChunk;
  std::vector<double> sum(chunks, 0.0);
  std::vector<std::size_t> count(chunks, 0);
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    double s = 0;
    std::size_t n = 0;
    for (std::size_t i = c * kChunk, end = std::min(ne, i + kChunk); i < end; ++i) {
      const Edge e(static_cast<Index>(i));
      if (mesh.is_deleted(e)) continue;
      s += (mesh.position(mesh.vertex(e, 0)) - mesh.position(mesh.vertex(e, 1))).norm();
      ++n;
    }
    sum[c] = s;
    count[c] = n;
  });
  double s = 0;
  std::size_t n = 0;
  for (std::size_t c = 0; c < chunks; ++c) {
    s += sum[c];
    n += count[c];
  }
  return n ? s / double(n) : 0.0;
}

ImproveReport improve_mesh(SurfaceMesh& mesh, const ImproveParams& params, EventList* events) {
  const auto t0 = Clock::now();
  check_params(params);
  ImproveReport report;
  if (mesh.n_faces() > 0) {
    if (const std::size_t open = boundary_edge_count(mesh); open > 0)
      TT_THROW(InvalidInput, "improve_mesh: the surface is open (" << open << " boundary edges); a closed one is required");
    const double L = params.target_edge_length > 0 ? params.target_edge_length : mean_edge_length_parallel(mesh);
    if (L > 0) {
      Improver imp(mesh, params, events, report);
      imp.run(L);
    }
  }
  const auto t1 = Clock::now();
  if (mesh.has_garbage()) mesh.compact();
  if (params.measure_quality) report.quality = quality_stats(mesh);
  report.seconds_finish = since(t1);
  report.seconds = since(t0);
  return report;
}

}  // namespace topotrack
