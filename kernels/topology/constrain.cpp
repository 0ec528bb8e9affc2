#include "kernels/topology/constrain.hpp"

#include <chrono>
#include <cmath>

#include <openvdb/tools/Morphology.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/topology/classify.hpp"
#include "kernels/topology/lattice_cut.hpp"
#include "kernels/topology/patch_march.hpp"
#include "kernels/topology/replace.hpp"

namespace topotrack {
namespace {

using namespace topology;
using Clock = std::chrono::steady_clock;
double since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// Weights of every output vertex that is not a kept vertex of M: derived points over old vertices, patch
// vertices by the §4.4 march over output vertices.
struct Weights {
  std::vector<PointWeights> derived;        // per derived vertex, over old vertex handles
  std::vector<MarchedPatch> created;        // over output vertex indices
  std::vector<MarchedPatch> deleted;        // over old vertex handles
};

template <class T>
bool carry_property(const SurfaceMesh& old_mesh, SurfaceMesh& out, const std::string& name, const Assembly& A,
                    const Weights& W) {
  const VertexProperty<T> src = old_mesh.get_vertex_property<T>(name);
  if (!src.is_valid()) return false;
  const int w = src.width();
  VertexProperty<T> dst = out.add_vertex_property<T>(name, w);
  for (std::size_t i = 0; i < A.n_kept(); ++i)
    for (int c = 0; c < w; ++c) dst(Vertex(Index(i)), c) = src(Vertex(A.kept_old[i]), c);
  for (std::size_t i = 0; i < A.n_derived(); ++i) {
    const PointWeights& pw = W.derived[i];
    for (int c = 0; c < w; ++c) {
      double s = 0;
      for (int k = 0; k < pw.n; ++k) s += pw.w[k] * double(src(pw.v[k], c));
      dst(Vertex(Index(A.n_kept() + i)), c) = static_cast<T>(std::is_integral_v<T> ? std::round(s) : s);
    }
  }
  for (const MarchedPatch& P : W.created)
    for (std::size_t r = 0; r < P.ruled; ++r)
      for (int c = 0; c < w; ++c) {
        double s = 0;
        for (std::uint32_t k = P.rule_begin[r]; k < P.rule_begin[r + 1]; ++k)
          s += P.terms[k].second * double(dst(Vertex(P.terms[k].first), c));
        dst(Vertex(P.order[r]), c) = static_cast<T>(std::is_integral_v<T> ? std::round(s) : s);
      }
  return true;
}

// One event per patch (§4.4). A deleted patch (ids of the old mesh) lists its vertices and the ring around it as
// in-vertices, the ring as out-vertices, and has backward rules; a created patch (ids of the new mesh) the ring
// as in-vertices, the ring and its vertices as out-vertices, and forward rules.
void record_patches(const SurfaceMesh& m, const std::vector<MarchedPatch>& patches, EventKind kind, EventList& events) {
  const bool created = kind == EventKind::PatchCreate;
  std::vector<RuleTerm> terms;
  for (const MarchedPatch& P : patches) {
    events.begin_event(kind);
    if (!created)
      for (Index v : P.order) events.add_in(m.id(Vertex(v)));
    for (Index v : P.boundary) events.add_in(m.id(Vertex(v)));
    for (Index v : P.boundary) events.add_out(m.id(Vertex(v)));
    if (created)
      for (Index v : P.order) events.add_out(m.id(Vertex(v)));
    for (std::size_t r = 0; r < P.ruled; ++r) {
      terms.clear();
      for (std::uint32_t k = P.rule_begin[r]; k < P.rule_begin[r + 1]; ++k)
        terms.push_back({m.id(Vertex(P.terms[k].first)), P.terms[k].second});
      const VertexId target = m.id(Vertex(P.order[r]));
      if (created) events.add_forward_rule(target, terms);
      else events.add_backward_rule(target, terms);
    }
    events.end_event();
  }
}

void record(const SurfaceMesh& old_mesh, const SurfaceMesh& out, const Assembly& A, const Weights& W,
            EventList& events) {
  // Cut points of kept triangles: edge splits and triangle subdivisions with their exact weights.
  for (std::size_t i = 0; i < A.n_derived(); ++i) {
    const PointWeights& pw = W.derived[i];
    const VertexId id = out.id(Vertex(Index(A.n_kept() + i)));
    if (pw.n == 2) events.record_split(old_mesh.id(pw.v[0]), old_mesh.id(pw.v[1]), id, pw.w[0]);
    else
      events.record_subdivide(old_mesh.id(pw.v[0]), old_mesh.id(pw.v[1]), old_mesh.id(pw.v[2]), id, pw.w[0], pw.w[1],
                              pw.w[2]);
  }
  record_patches(old_mesh, W.deleted, EventKind::PatchDelete, events);
  record_patches(out, W.created, EventKind::PatchCreate, events);
}

// The cells examined around the complex region found slab by slab: its 26 neighbours must be examined (the
// stitching reads their pieces), and a margin more saves a round when the region grows by a layer.
constexpr int kExaminedMargin = 2;
constexpr int kMaxExaminedRounds = 8;

// Whether every cell of `region` and its 26 neighbours is a cell of `examined`; if not, the cells within
// `grow` of the region join `examined`.
bool region_surrounded(const std::vector<std::uint64_t>& region, openvdb::MaskGrid& examined, int grow) {
  auto acc = examined.getConstAccessor();
  bool all = true;
  for (std::size_t i = 0; i < region.size() && all; ++i) {
    const openvdb::Coord c = cell_from_key(region[i]);
    for (int d = 0; d < 27 && all; ++d) all = acc.isValueOn(c.offsetBy(d % 3 - 1, d / 3 % 3 - 1, d / 9 - 1));
  }
  if (all) return true;
  openvdb::MaskTree grown;
  for (std::uint64_t k : region) grown.setValueOn(cell_from_key(k));
  openvdb::tools::dilateActiveValues(grown, grow, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                     openvdb::tools::IGNORE_TILES);
  examined.tree().topologyUnion(grown);
  return false;
}

// Where to cut M slab by slab: across the longest side of the box of cells of M's faces and Θ's sign
// changes, into slabs whose faces' boxes hold about `budget` cells each (about the pieces the cut of those
// faces makes, or a few times more). One slab when all of M is within budget.
struct Slabs {
  openvdb::CoordBBox box;
  int axis = 0;
  std::vector<int> begin;  //!< slab k holds the cells with axis coordinate in [begin[k], begin[k + 1])
};
Slabs plan_slabs(const SurfaceMesh& mesh, const openvdb::FloatGrid& theta, double budget) {
  const openvdb::math::Transform& xform = theta.transform();
  const std::size_t nf = mesh.faces_size();
  std::vector<openvdb::CoordBBox> boxes(nf);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nf, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t f = r.begin(); f != r.end(); ++f) {
      if (mesh.is_deleted(Face(Index(f)))) continue;
      for (Vertex v : mesh.vertices(Face(Index(f)))) {
        const Vec3& w = mesh.position(v);
        const openvdb::Vec3d q = xform.worldToIndex(openvdb::Vec3d(w.x(), w.y(), w.z()));
        if (!q.isFinite() || std::abs(q.x()) > kCellRange || std::abs(q.y()) > kCellRange || std::abs(q.z()) > kCellRange) {
          boxes[f] = openvdb::CoordBBox();  // the cut reports it
          break;
        }
        boxes[f].expand(openvdb::Coord::floor(q));
      }
    }
  });
  Slabs s;
  double total = 0;
  for (const auto& b : boxes)
    if (!b.empty()) s.box.expand(b), total += double(b.volume());
  if (budget <= 0 || total <= budget || s.box.empty()) return s;
  const openvdb::CoordBBox active = theta.evalActiveVoxelBoundingBox();
  if (!active.empty()) s.box.expand(active);
  const openvdb::Coord dim = s.box.dim();
  s.axis = dim[0] >= dim[1] && dim[0] >= dim[2] ? 0 : dim[1] >= dim[2] ? 1 : 2;
  const int lo = s.box.min()[s.axis], n = dim[s.axis];
  std::vector<double> cells(std::size_t(n) + 1, 0.0);  // by the face box's lowest coordinate
  for (const auto& b : boxes)
    if (!b.empty()) cells[std::size_t(b.min()[s.axis] - lo)] += double(b.volume());
  s.begin.push_back(lo);
  double acc = 0;
  for (int k = 0; k < n; ++k) {
    acc += cells[std::size_t(k)];
    if (acc >= budget && k + 1 < n) {
      s.begin.push_back(lo + k + 1);
      acc = 0;
    }
  }
  s.begin.push_back(lo + n);
  if (s.begin.size() <= 2) s.begin.clear();
  return s;
}

// The complex cells (§4.3, steps 1-2) slab by slab, each with its own cut of the faces that reach it (and 2
// cells beyond, so that the signs index_cells takes from M's crossings there are those of the whole cut):
// the cut of all of M at once is most of ConstrainTopology's memory on a fine lattice. The verdicts are
// counted into `report`.
std::vector<std::uint64_t> complex_in_slabs(const SurfaceMesh& mesh, const openvdb::FloatGrid& theta,
                                            const ConstrainParams& params, const Slabs& slabs,
                                            ConstrainReport& report) {
  const int axis = slabs.axis;
  std::vector<std::uint64_t> region;
  report.cells_by_verdict = {};
  for (std::size_t i = 0; i + 1 < slabs.begin.size(); ++i) {
    const int a = slabs.begin[i], b = slabs.begin[i + 1];  // [a, b)
    openvdb::CoordBBox box = slabs.box;
    box.expand(2);
    box.min()[axis] = a - 2;
    box.max()[axis] = b + 1;
    auto only = openvdb::MaskGrid::create();
    only->tree().fill(box, true);
    const auto t0 = Clock::now();
    const LatticeCut cut = cut_by_lattice(mesh, theta.transform(), only.get());
    const double cut_seconds = since(t0);
    report.seconds_cut += cut_seconds;
    const CellIndex index = index_cells(cut, theta, params.flips_keep_topology, only.get());
    report.seconds_index += since(t0) - cut_seconds;
    const std::vector<CellVerdict> verdict = classify_cells(mesh, cut, index, theta);
    const auto in_slab = [&](const openvdb::Coord& c) { return c[axis] >= a && c[axis] < b; };
    for (std::size_t k = 0; k < verdict.size(); ++k) {
      const openvdb::Coord c = cell_from_key(index.cells[k]);
      if (!in_slab(c)) continue;
      ++report.cells_by_verdict[int(verdict[k])];
      if (verdict[k] != CellVerdict::kSimple) region.push_back(index.cells[k]);
    }
    for (const auto& bb : cut.bad_boxes)
      for (int x = bb[0].x(); x <= bb[1].x(); ++x)
        for (int y = bb[0].y(); y <= bb[1].y(); ++y)
          for (int z = bb[0].z(); z <= bb[1].z(); ++z)
            if (in_slab(openvdb::Coord(x, y, z))) region.push_back(cell_key(openvdb::Coord(x, y, z)));
    report.bad_faces += cut.bad_faces.size();
    report.seconds_classify += since(t0);
  }
  std::sort(region.begin(), region.end());
  region.erase(std::unique(region.begin(), region.end()), region.end());
  return region;
}

// The cut, the index, the classification and the replacement (§4.3, steps 1-3): of all of M (`only` null), or
// for the complex cells `known` that complex_in_slabs found, of the faces that reach the cells of `only`
// (`only` must hold the cells around `known`). kNone when no cell is complex; kGrow when `only` lacks cells
// around the replaced region (those `grow` cells around it were added). Seconds and counts add up in `report`.
enum class Outcome { kNone, kReplaced, kGrow };
struct Replaced {
  LatticeCut cut;
  std::vector<std::uint64_t> region;
  Assembly A;
  SurfaceMesh result;
};
Outcome replace_complex(const SurfaceMesh& mesh, const openvdb::FloatGrid& theta, const ConstrainParams& params,
                        const std::vector<std::uint64_t>* known, openvdb::MaskGrid* only, int grow,
                        ConstrainReport& report, Replaced& R) {
  const openvdb::math::Transform& xform = theta.transform();
  const auto t0 = Clock::now();
  R.cut = LatticeCut();
  R.cut = cut_by_lattice(mesh, xform, only);
  LatticeCut& cut = R.cut;
  const double cut_seconds = since(t0);
  report.seconds_cut += cut_seconds;
  const CellIndex index = index_cells(cut, theta, params.flips_keep_topology, only);
  report.seconds_index += since(t0) - cut_seconds;
  std::vector<std::uint64_t>& region = R.region;
  if (known) {
    region = *known;
  } else {
    region = complex_cells(mesh, cut, index, theta, topology::ClassifyPath::kFast, &report.cells_by_verdict);
    report.bad_faces = cut.bad_faces.size();
    report.seconds_classify += since(t0);
  }
  if (region.empty()) return Outcome::kNone;
  auto timed = [](double& acc, auto&& f) {
    const auto ts = Clock::now();
    f();
    acc += since(ts);
  };
  timed(report.seconds_slivers, [&] { absorb_sliver_pieces(mesh, cut, region); });
  if (only && !region_surrounded(region, *only, grow)) return Outcome::kGrow;

  // Replacement, growing the region when a check fails (§4.3: "if a local repair fails, grow"), then
  // taking in the cells of any sliver (at most kSliverRounds times; a valid result is never given up).
  const auto t1 = Clock::now();
  constexpr int kSliverRounds = 3;
  Assembly& A = R.A;
  SurfaceMesh& result = R.result;
  Assembly valid_A;
  SurfaceMesh valid_result;
  std::vector<std::uint64_t> valid_region;
  bool have_valid = false;
  std::string why;
  report.region_growth = 0;
  for (int attempt = 0, sliver_round = 0;;) {
    bool ok = false;
    timed(report.seconds_assemble, [&] { ok = assemble(mesh, cut, index, region, theta, A, why); });
    ++report.assemblies;
    const auto tr = Clock::now();
    if (ok) {
      std::vector<VertexId> ids(A.positions.size());
      for (std::size_t i = 0; i < A.n_kept(); ++i) ids[i] = mesh.id(Vertex(A.kept_old[i]));
      for (std::size_t i = A.n_kept(); i < ids.size(); ++i) ids[i] = mesh.next_id() + (i - A.n_kept());
      try {
        // Closed, manifold, consistently oriented: from_triangles' checks with require_closed are all of
        // validate(true)'s (surface_mesh.hpp), so no separate pass over the result.
        result = SurfaceMesh::from_triangles(A.positions, A.triangles, ids, true);
        result.set_next_id(mesh.next_id() + (ids.size() - A.n_kept()));
      } catch (const Error& e) {
        ok = false;
        why = e.what();
      }
    }
    report.seconds_rebuild += since(tr);
    if (ok) {
      if (sliver_round < kSliverRounds) {
        std::vector<std::uint64_t> grown = region;
        std::size_t absorbed = 0;
        timed(report.seconds_slivers, [&] { absorbed = absorb_sliver_triangles(cut, A, xform, grown); });
        if (absorbed > 0) {
          valid_A = std::move(A);
          valid_result = std::move(result);
          valid_region = region;
          have_valid = true;
          region = std::move(grown);
          timed(report.seconds_slivers, [&] { absorb_sliver_pieces(mesh, cut, region); });
          ++sliver_round;
          continue;
        }
      }
      break;
    }
    if (have_valid) {  // a sliver round made the stitching fail: keep the last valid result
      A = std::move(valid_A);
      result = std::move(valid_result);
      region = std::move(valid_region);
      break;
    }
    if (only && !region_surrounded(region, *only, grow)) return Outcome::kGrow;
    if (attempt >= params.max_region_growth)
      TT_THROW(TopologyError, "constrain topology: replacement failed after growing the complex region "
                                  << attempt << " times: " << why);
    timed(report.seconds_slivers, [&] {
      region = grow_region(region);
      absorb_sliver_pieces(mesh, cut, region);
    });
    ++attempt;
    ++report.region_growth;
  }
  report.seconds_replace += since(t1);
  if (only && !region_surrounded(region, *only, grow)) return Outcome::kGrow;
  return Outcome::kReplaced;
}

}  // namespace

ConstrainReport constrain_topology(SurfaceMesh& mesh, const openvdb::FloatGrid& theta, const ConstrainParams& params,
                                   EventList* events) {
  const auto t0 = Clock::now();
  ConstrainReport report;
  const openvdb::math::Transform& xform = theta.transform();
  if (!xform.isLinear()) TT_THROW(InvalidInput, "constrain topology: the level set's transform is not linear");
  if (params.max_region_growth < 0)
    TT_THROW(InvalidInput, "constrain topology: max_region_growth must be >= 0, got " << params.max_region_growth);
  if (params.count_components) {
    const auto tc = Clock::now();
    report.components_before = int(connected_components(mesh));
    report.seconds_components = since(tc);
  }

  // One pass over all of M, unless the faces' boxes hold more than params.max_cut_cells cells: then the
  // complex cells are found slab by slab, and the replacement cuts only the faces around them (the
  // examined cells), more of them while the region reaches beyond (growth, slivers).
  const Slabs slabs = plan_slabs(mesh, theta, params.max_cut_cells);
  openvdb::MaskGrid::Ptr examined;
  std::vector<std::uint64_t> known;
  if (!slabs.begin.empty()) {
    report.slabs = int(slabs.begin.size()) - 1;
    known = complex_in_slabs(mesh, theta, params, slabs, report);
    const std::vector<std::uint64_t>& region = known;
    if (region.empty()) {
      report.components_after = report.components_before;
      report.seconds_total = since(t0);
      return report;
    }
    examined = openvdb::MaskGrid::create();
    for (std::uint64_t k : region) examined->tree().setValueOn(cell_from_key(k));
    openvdb::tools::dilateActiveValues(examined->tree(), kExaminedMargin, openvdb::tools::NN_FACE_EDGE_VERTEX,
                                       openvdb::tools::IGNORE_TILES);
  }
  Replaced R;
  Outcome outcome = Outcome::kNone;
  for (int round = 0;; ++round) {
    // The examined cells grow around the region by kExaminedMargin + 1, then twice, four times as much, ...
    const int grow = (kExaminedMargin + 1) << std::min(round, 6);
    try {
      outcome = replace_complex(mesh, theta, params, examined ? &known : nullptr, examined.get(), grow, report, R);
    } catch (const TopologyError&) {
      if (!examined) throw;
      examined.reset();  // all of M in one pass
      continue;
    }
    if (outcome != Outcome::kGrow) break;
    ++report.examined_growth;
    if (round + 1 >= kMaxExaminedRounds) examined.reset();
  }
  const bool any = outcome == Outcome::kReplaced;
  if (!any) {
    report.components_after = report.components_before;
    report.seconds_total = since(t0);
    return report;
  }
  const LatticeCut& cut = R.cut;
  const Assembly& A = R.A;
  SurfaceMesh& result = R.result;
  report.complex_cells = R.region.size();

  // §4.4: weights of the new vertices, then events and carried properties.
  const auto t2 = Clock::now();
  Weights W;
  W.derived.resize(A.n_derived());
  for (std::size_t i = 0; i < A.n_derived(); ++i) {
    const PointKey& k = A.derived[i];
    if (kind(k) == PointKind::Other) {
      const auto vs = mesh.vertices(Face(key_element(k)));
      W.derived[i] = PointWeights{3, vs, {1.0 / 3, 1.0 / 3, 1.0 / 3}};
    } else {
      point_position(mesh, cut.P, k, &W.derived[i]);
    }
  }
  {
    std::vector<std::uint32_t> adj_begin;
    std::vector<Index> adj;
    std::vector<std::uint8_t> gone(mesh.vertices_size(), 0);
    for (Index v : A.deleted_old) gone[v] = 1;
    mesh_adjacency(mesh, gone, adj_begin, adj);  // the march reads the patch vertices' rows only
    W.deleted = march_patches(gone, adj_begin, adj);
    std::vector<std::uint8_t> fresh(result.vertices_size(), 0);
    for (std::size_t i = A.n_kept() + A.n_derived(); i < fresh.size(); ++i) fresh[i] = 1;
    mesh_adjacency(result, fresh, adj_begin, adj);
    W.created = march_patches(fresh, adj_begin, adj);
  }
  if (events && params.record_events) record(mesh, result, A, W, *events);
  for (const std::string& name : mesh.vertex_property_names()) {
    carry_property<float>(mesh, result, name, A, W) || carry_property<double>(mesh, result, name, A, W) ||
        carry_property<std::int32_t>(mesh, result, name, A, W) ||
        carry_property<std::uint32_t>(mesh, result, name, A, W) ||
        carry_property<std::int64_t>(mesh, result, name, A, W) ||
        carry_property<std::uint64_t>(mesh, result, name, A, W) ||
        carry_property<std::uint8_t>(mesh, result, name, A, W) || carry_property<std::int8_t>(mesh, result, name, A, W);
  }
  report.seconds_events = since(t2);

  report.faces_removed = A.live_faces - A.faces_kept;
  report.faces_added = A.triangles.size() - A.faces_kept;
  report.vertices_removed = A.deleted_old.size();
  report.vertices_added = A.positions.size() - A.n_kept();
  report.patches_created = W.created.size();
  report.patches_deleted = W.deleted.size();
  mesh = std::move(result);
  if (params.count_components) {
    const auto tc = Clock::now();
    report.components_after = int(connected_components(mesh));
    report.seconds_components += since(tc);
  }
  report.seconds_total = since(t0);
  return report;
}

}  // namespace topotrack
