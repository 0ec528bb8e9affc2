#include "kernels/topology/constrain.hpp"

#include <chrono>
#include <cmath>

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

}  // namespace

ConstrainReport constrain_topology(SurfaceMesh& mesh, const openvdb::FloatGrid& theta, const ConstrainParams& params,
                                   EventList* events) {
  const auto t0 = Clock::now();
  ConstrainReport report;
  const openvdb::math::Transform& xform = theta.transform();
  if (!xform.isLinear()) TT_THROW(InvalidInput, "constrain topology: the level set's transform is not linear");
  if (params.max_region_growth < 0)
    TT_THROW(InvalidInput, "constrain topology: max_region_growth must be >= 0, got " << params.max_region_growth);

  LatticeCut cut = cut_by_lattice(mesh, xform);
  report.seconds_cut = since(t0);
  const CellIndex index = index_cells(cut, theta, params.flips_keep_topology);
  report.seconds_index = since(t0) - report.seconds_cut;
  std::vector<std::uint64_t> region =
      complex_cells(mesh, cut, index, theta, topology::ClassifyPath::kFast, &report.cells_by_verdict);
  report.bad_faces = cut.bad_faces.size();
  report.seconds_classify = since(t0);
  if (params.count_components) {
    const auto tc = Clock::now();
    report.components_before = int(connected_components(mesh));
    report.seconds_components = since(tc);
  }
  if (region.empty()) {
    report.components_after = report.components_before;
    report.seconds_total = since(t0);
    return report;
  }
  auto timed = [](double& acc, auto&& f) {
    const auto ts = Clock::now();
    f();
    acc += since(ts);
  };
  timed(report.seconds_slivers, [&] { absorb_sliver_pieces(mesh, cut, region); });

  // Replacement, growing the region when a check fails (§4.3: "if a local repair fails, grow"), then
  // taking in the cells of any sliver (at most kSliverRounds times; a valid result is never given up).
  const auto t1 = Clock::now();
  constexpr int kSliverRounds = 3;
  Assembly A, valid_A;
  SurfaceMesh result, valid_result;
  std::vector<std::uint64_t> valid_region;
  bool have_valid = false;
  std::string why;
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
  report.complex_cells = region.size();
  report.seconds_replace = since(t1);

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
