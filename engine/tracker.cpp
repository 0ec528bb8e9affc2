#include "engine/tracker.hpp"

#include <chrono>
#include <utility>

#include "engine/agree_near_surface.hpp"
#include "engine/small_components.hpp"
#include "io/error.hpp"
#include "kernels/mesh/mesh_convert.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/propagate/propagate.hpp"
#include "kernels/raycast/target_surface.hpp"
#include "kernels/registration/projection.hpp"
#include "kernels/sdf/extraction_grid.hpp"
#include "kernels/sdf/marching_cubes.hpp"
#include "kernels/sdf/signed_distance.hpp"

namespace topotrack {
namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// ConstrainParams::max_cut_cells on lattices of a quarter of the first one's voxel and finer: resurfaced pcow
// (capture profile, two halvings, 40 frames) peaked at 1 086 MB; in one pass 1.73 GB (docs/results.md).
constexpr double kSlabCells = 4.0e6;

}  // namespace

struct Tracker::Impl {
  TrackerParams params;
  SurfaceMesh mesh;
  EventList events;
  std::vector<Vec3> velocities;
  FrameReport report;
  std::size_t frames = 0;
  double edge_length = 0, voxel_size = 0;
  Vec3 origin = Vec3::Zero();  //!< the lattices' node (0, 0, 0): the extraction grid's origin, else 0

  //! Whether the first lattice is on the first frame's extraction grid (half its spacing, or its spacing:
  //! extraction_grid_voxel; TrackerParams::extraction_grid found one). Derived from the state a checkpoint
  //! restores.
  bool lattice_on_extraction_grid() const {
    return params.extraction_grid && !(params.voxel_size > 0) && voxel_size > 0 &&
           voxel_size != first_voxel_size(params, edge_length);
  }

  ImproveParams improve_params() const {
    ImproveParams p = params.improve;
    p.target_edge_length = edge_length;
    return p;
  }

  //! ImproveMesh(M) (§4.1), timed into the improve column.
  void improve(EventList* ev) {
    const auto t0 = Clock::now();
    improve_mesh(mesh, improve_params(), ev);
    report.seconds.improve += since(t0);
  }

  //! ConstrainTopology(M, Θ) (§4.3), timed into the topology column. Returns the number of complex cells
  //! and sets `reasons`. `flips_keep_topology`: ConstrainParams::flips_keep_topology.
  std::size_t constrain(const openvdb::FloatGrid& theta, double h, topology::VerdictCounts& reasons,
                        bool flips_keep_topology) {
    const auto t0 = Clock::now();
    // A failed local replacement leaves M as it was (constrain_topology commits only a valid result):
    // the frame goes on without this topology step, and the failure is reported, not hidden.
    EventList ev;
    std::size_t cells = 0;
    try {
      ConstrainParams cp = params.constrain;
      cp.count_components = false;  // not reported per frame
      cp.flips_keep_topology = flips_keep_topology;
      // From two halvings of the first lattice on, the cut of all of M is most of the memory: in slabs.
      if (h < 0.3 * voxel_size) cp.max_cut_cells = kSlabCells;
      const ConstrainReport r = constrain_topology(mesh, theta, cp, &ev);
      cells = r.complex_cells;
      reasons = r.cells_by_verdict;
      events.append(ev);
    } catch (const TopologyError& e) {
      ++report.topology_failures;
      report.warnings.push_back(std::string("ConstrainTopology skipped: ") + e.what());
    }
    report.seconds.topology += since(t0);
    return cells;
  }

  openvdb::FloatGrid::Ptr distance(const SurfaceMesh& m, double h) {
    const auto t0 = Clock::now();
    auto grid = signed_distance(m, h, params.sdf_half_width, params.exact_sign_band, origin);
    report.seconds.signed_distance += since(t0);
    return grid;
  }

  //! The work on S_n alone (see PreparedFrame). Reads only params and voxel_size, which add_frame no longer
  //! writes once the first frame is done: safe to run concurrently with add() from then on.
  PreparedFrame prepare(SurfaceMesh surface, const std::string& name, const openvdb::FloatGrid* theta) const {
    const auto t0 = Clock::now();
    PreparedFrame p;
    p.name = name;
    p.surface = std::move(surface);
    if (voxel_size > 0) {  // before the first frame S_1 only becomes M (lines 1-2); nothing to prepare
      if (p.surface.n_faces() > 0) p.target = std::make_unique<TargetSurface>(TargetSurface::from_mesh(p.surface));
      if (params.topology) {  // φ_S, line 10
        const auto t1 = Clock::now();
        // The level set itself where it lies on the tracker's lattice (φ_M and φ_S are combined node by node).
        if (theta && is_lattice(theta->transform(), voxel_size, origin)) p.phi = theta->deepCopy();
        else p.phi = signed_distance(p.surface, voxel_size, params.sdf_half_width, params.exact_sign_band, origin);
        p.voxel_size = voxel_size;
        p.seconds.signed_distance = since(t1);
      }
    }
    p.seconds.prepare = since(t0);
    return p;
  }

  void first_frame(SurfaceMesh target) {
    // Algorithm 1, lines 1-2: M = S_1, ImproveMesh(M). The events of this first improvement relate the
    // input's triangulation to M, not two frames of M, so they are not part of any frame's list.
    edge_length = params.edge_length > 0 ? params.edge_length : mean_edge_length(target);
    if (!(edge_length > 0)) TT_THROW(InvalidInput, "the first frame has no edges to derive the edge length from");
    mesh = std::move(target);
    voxel_size = first_voxel_size(params, edge_length);
    if (params.extraction_grid && !(params.voxel_size > 0)) {
      const auto grid = extraction_grid(mesh.positions(), mean_edge_length(mesh));
      const auto h = grid ? extraction_grid_voxel(grid->spacing, voxel_size) : std::nullopt;
      if (h) {
        voxel_size = *h;
        origin = grid->origin;
      } else if (grid)
        report.warnings.push_back("tracker.extraction_grid: the first frame was extracted on a grid of spacing " +
                                  std::to_string(grid->spacing) + ", finer than a quarter of the profile's voxels of " +
                                  std::to_string(voxel_size) + " (voxel_size_factor x L), which are used");
      else
        report.warnings.push_back("tracker.extraction_grid: the first frame's vertices do not lie on the edges of "
                                  "one grid; voxels of " +
                                  std::to_string(voxel_size) + " (voxel_size_factor x L) used");
    }
    improve(nullptr);
  }

  //! Lines 8-12 of Algorithm 1 on a lattice of voxel size h: ConstrainTopology against φ_M and φ_S (§4.3),
  //! the small components (engine/small_components.hpp), then ImproveMesh(M). φ_S takes φ_M's sign where the
  //! two surfaces pass within `agree_within` of a node and the flip keeps φ_S's topology (agree_near_surface;
  //! 0: never). `self` runs line 9; a refinement (below) leaves it out. `keep`: line 11's flips keep φ_S's
  //! topology on the first lattice too.
  void topology_lines(PreparedFrame& frame, double h, bool self, double agree_within, bool keep = false) {
    const SurfaceMesh& target = frame.surface;
    openvdb::FloatGrid::Ptr phi_m;
    if (mesh.n_faces() > 0 && (self || agree_within > 0)) {
      phi_m = distance(mesh, h);                                                             // line 8
      if (self) report.complex_cells_self = constrain(*phi_m, h, report.complex_reasons_self, false);  // line 9
    }
    openvdb::FloatGrid::Ptr phi_s;  // line 10, usually done by prepare
    if (frame.phi && frame.voxel_size == h) phi_s = std::move(frame.phi);
    else phi_s = distance(target, h);
    if (phi_m && agree_within > 0) {
      const auto t0 = Clock::now();
      // On a finer lattice S and M can be several of its nodes apart: flip until nothing more is simple.
      agree_near_surface(*phi_s, *phi_m, agree_within, self ? 1 : 0);
      report.seconds.topology += since(t0);
    }
    // Line 11. Lattice nodes within kSignTolerance of φ_S's zero set take M's side (classify.hpp): on the first
    // lattice wherever M's crossings say so, as in line 9, where M's crossings are M's own side; on a finer
    // lattice (a refinement, which is there to give M S_n's topology) only where that keeps φ_S's topology.
    // With the check on the first lattice too, resurfaced pcow matched the input's topology in 5 of 40
    // frames with the default profile instead of 7 and samba in 36 instead of 38 (docs/results.md,
    // 2026-11-25). On the input's extraction grid refined_topology_lines redoes the first lattice with the
    // check when the topology differs.
    phi_m.reset();  // not needed any more: its memory is free for the cut
    report.complex_cells_target = constrain(*phi_s, h, report.complex_reasons_target, !self || keep);
    report.small_components_added = report.small_components_removed = 0;
    if (params.small_component_voxels > 0 && target.n_faces() > 0) {
      const auto t0 = Clock::now();
      if (!frame.target) frame.target = std::make_unique<TargetSurface>(TargetSurface::from_mesh(target));
      const SmallComponentReport r = match_small_components(mesh, *frame.target, 0.5 * h,
                                                            params.small_component_voxels * h, edge_length, &events);
      report.small_components_added = r.added;
      report.small_components_removed = r.removed;
      report.seconds.topology += since(t0);
    }
    if (mesh.n_faces() > 0) improve(&events);  // line 12
  }

  //! topology_lines with TrackerParams::topology_refinements: when M's components or Euler characteristic
  //! are not S_n's after lines 8-12, M takes S_n's topology once more on a lattice of half the voxel size
  //! (then a quarter, ...), each time from the first result. That result already has S_n's topology as the
  //! first lattice sees it, and lies within about one of its voxels of S_n; a sign difference between the
  //! finer φ_S and φ_M within that distance is either one the first lattice could not see (a tunnel or a
  //! bridge thinner than its voxel) or alignment error. agree_near_surface keeps the first and removes the
  //! second, so the finer ConstrainTopology(M, φ_S) resamples M only around S_n's small features, and line 9
  //! (done on the first lattice) is not repeated. A finer result replaces the first only when its topology
  //! is S_n's and its mesh quality is no worse. (Redoing lines 8-12 from M after line 7 instead matched as
  //! many resurfaced pcow frames at commit 6f1b969, 25 of 40, with 19.5 % new vertices per frame instead
  //! of 16.7 %, 1.4x the time per frame and 1.17x the peak memory; docs/results.md.)
  void refined_topology_lines(PreparedFrame& frame) {
    const SurfaceMesh& target = frame.surface;
    const Index want_components = connected_components(target);
    const long want_euler = euler_characteristic(target);
    const auto matches = [&] {
      return connected_components(mesh) == want_components && euler_characteristic(mesh) == want_euler;
    };
    // On the input's extraction grid φ_S's signs are the input's topology, but a marching-cubes vertex at the
    // middle of a grid edge is a node of the half-spacing lattice with |φ_S| ≈ 0, and its flip to M's side in
    // line 11 can cut a neck the input has (resurfaced pcow frames 28 and 30, capture profile: a bulge cut
    // off as a component). There lines 8-12 are redone on the same lattice with line 11's flips keeping φ_S's
    // topology before any finer lattice is tried. Keeping them in every frame's first pass instead matched all
    // 40 frames too but left a fold in 3; redoing the first lattice from its result (without line 9) did
    // not mend frame 30 (docs/results.md, 2026-11-25 night).
    const bool redo_first = lattice_on_extraction_grid();
    SurfaceMesh before;
    EventList before_events;
    FrameReport before_report;
    if (redo_first) {
      before = mesh.clone();
      before_events = events;
      before_report = report;
    }
    topology_lines(frame, voxel_size, true, params.topology_tolerance * voxel_size);
    if (matches()) return;
    const QualityStats first = quality_stats(mesh);
    const auto worse = [first](const QualityStats& q) {
      return q.below_2deg > first.below_2deg || q.dihedral_below_45deg > first.dihedral_below_45deg;
    };
    SurfaceMesh kept = std::move(mesh);
    EventList kept_events = std::move(events);
    const FrameReport kept_report = report;
    // Back to the first result with its report, except the seconds and counts of every attempt so far; `last`:
    // for good (the first result is moved, not copied).
    const auto restore_first = [&](bool last) {
      const StageSeconds seconds = report.seconds;
      const int retries = report.topology_retries, rejected = report.topology_rejected_for_quality;
      mesh = last ? std::move(kept) : kept.clone();
      events = last ? std::move(kept_events) : kept_events;
      report = kept_report;
      report.seconds = seconds;
      report.topology_retries = retries;
      report.topology_rejected_for_quality = rejected;
    };
    if (redo_first) {
      const StageSeconds seconds = report.seconds;
      mesh = std::move(before);
      events = std::move(before_events);
      report = std::move(before_report);
      report.seconds = seconds;
      report.topology_retries = 1;
      topology_lines(frame, voxel_size, true, params.topology_tolerance * voxel_size, true);
      if (matches() && !worse(quality_stats(mesh))) return;
      if (matches()) report.topology_rejected_for_quality = 1;
      restore_first(false);
    }
    double h = voxel_size;
    for (int level = 1; level <= params.topology_refinements; ++level) {
      mesh = kept.clone();
      events = kept_events;
      report.topology_failures = kept_report.topology_failures;
      report.warnings = kept_report.warnings;
      h *= 0.5;
      topology_lines(frame, h, false, voxel_size);
      ++report.topology_retries;
      if (!matches()) continue;
      // The finer cut leaves smaller triangles for line 12 to coarsen; one more ImproveMesh pass often
      // still finds work there and removes what would reject this result.
      if (worse(quality_stats(mesh))) improve(&events);
      if (worse(quality_stats(mesh))) {
        ++report.topology_rejected_for_quality;
        continue;
      }
      report.topology_level = level;
      return;
    }
    // No finer lattice gave S_n's topology with no worse quality: the first result stays, with its report
    // (the seconds count every attempt).
    restore_first(true);
  }

  void next_frame(PreparedFrame& frame) {
    const SurfaceMesh& target = frame.surface;
    const IdField before = position_field(mesh);
    if (mesh.n_faces() > 0 && target.n_faces() > 0) {
      if (!frame.target) frame.target = std::make_unique<TargetSurface>(TargetSurface::from_mesh(target));
      const TargetSurface& surface = *frame.target;
      if (params.projection_only) {
        const auto t0 = Clock::now();
        project_to_closest(mesh, surface);
        report.seconds.coarse += since(t0);
      } else {
        // FineParams::relax slides M along S_n towards its shape before this frame's alignment (off by default).
        const std::vector<Vec3> rest = params.fine && params.fine_params.relax.iterations > 0 ? mesh.positions() : std::vector<Vec3>{};
        if (params.coarse) {  // line 5
          const auto t0 = Clock::now();
          const CoarseReport coarse = align_coarse(mesh, surface, params.coarse_params);
          report.coarse_iterations = coarse.iterations;
          report.coarse_pass_iterations = coarse.coarse_pass_iterations;
          report.seconds.coarse += since(t0);
        }
        if (params.fine) {  // line 6
          const auto t0 = Clock::now();
          const FineReport fine = align_fine(mesh, surface, params.fine_params, rest);
          report.fine_iterations = fine.cg_iterations;
          report.fine_rounds = fine.rounds;
          report.relax_iterations = fine.relax.iterations;
          report.seconds.fine += since(t0);
        }
      }
    }
    if (mesh.n_faces() > 0) improve(&events);  // line 7
    if (!params.topology) {
      if (mesh.n_faces() > 0) improve(&events);  // line 12
    } else if ((params.topology_refinements <= 0 && !lattice_on_extraction_grid()) || target.n_faces() == 0) {
      topology_lines(frame, voxel_size, true, params.topology_tolerance * voxel_size);
    } else {
      refined_topology_lines(frame);
    }

    // Velocity of each vertex from the tracked motion: its position minus where the previous frame's
    // surface point it stands for was (§4.6 forward propagation of positions).
    const IdField carried = propagate_forward(events, before);
    const IdTable table = IdTable::from_field(carried);
    velocities.assign(mesh.vertices_size(), Vec3::Zero());
    for (Index i = 0; i < mesh.vertices_size(); ++i) {
      const Vertex v(i);
      if (mesh.is_deleted(v)) continue;
      const auto prev = table.get(mesh.id(v));
      if (prev.size() == 3) velocities[i] = mesh.position(v) - Vec3(prev[0], prev[1], prev[2]);
    }
  }

  //! Rebuild M from its triangle list so that its half-edge layout depends only on (positions, ids,
  //! triangles): a run resumed from a checkpoint (which stores exactly those) then continues bit for bit
  //! like an uninterrupted one, since the stages visit elements in index order.
  void canonicalize() {
    std::vector<Vec3> pos;
    std::vector<std::array<Index, 3>> tris;
    std::vector<Vertex> of;
    extract_triangles(mesh, pos, tris, &of);
    std::vector<VertexId> ids(of.size());
    std::vector<Vec3> vel(of.size());
    for (std::size_t i = 0; i < of.size(); ++i) {
      ids[i] = mesh.id(of[i]);
      vel[i] = velocities[of[i].idx];
    }
    const VertexId next = mesh.next_id();
    mesh = SurfaceMesh::from_triangles(pos, tris, ids);
    mesh.set_next_id(next);
    velocities = std::move(vel);
  }

  const FrameReport& add(PreparedFrame frame) {
    const auto t0 = Clock::now();
    report = FrameReport{};
    report.index = frames;
    report.seconds.signed_distance = frame.seconds.signed_distance;
    report.seconds.prepare = frame.seconds.prepare;
    events.clear();
    if (frames == 0 && mesh.n_faces() == 0) first_frame(std::move(frame.surface));
    else next_frame(frame);
    if (frames == 0 || velocities.size() != mesh.vertices_size()) velocities.assign(mesh.vertices_size(), Vec3::Zero());
    canonicalize();
    ++frames;
    report.vertices = mesh.n_vertices();
    report.triangles = mesh.n_faces();
    report.components = connected_components(mesh);
    report.euler = euler_characteristic(mesh);
    report.events_by_kind = events.count_by_kind();
    report.seconds.total = since(t0) + frame.seconds.prepare;
    return report;
  }
};

Tracker::Tracker(TrackerParams params) : impl_(std::make_unique<Impl>()) {
  validate(params);
  impl_->params = std::move(params);
}
Tracker::~Tracker() = default;
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;

PreparedFrame Tracker::prepare(SurfaceMesh target, const std::string& name) const {
  const auto t0 = Clock::now();
  try {
    target.validate(/*require_closed=*/true);
  } catch (const TopologyError& e) {
    TT_THROW(InvalidInput, name << ": not a closed 2-manifold: " << e.what());
  }
  PreparedFrame p = impl_->prepare(std::move(target), name, nullptr);
  p.seconds.prepare = since(t0);  // with the check
  return p;
}

PreparedFrame Tracker::prepare(const openvdb::FloatGrid& target, const std::string& name) const {
  const auto t0 = Clock::now();
  SurfaceMesh surface;
  try {
    surface = to_surface_mesh(marching_cubes(target));
  } catch (const InvalidInput& e) {
    TT_THROW(InvalidInput, name << ": " << e.what());
  }
  // The first frame is checked and used as a mesh; later ones take the level set as φ_S.
  PreparedFrame p = impl_->voxel_size > 0 ? impl_->prepare(std::move(surface), name, &target)
                                          : prepare(std::move(surface), name);
  p.seconds.prepare = since(t0);
  return p;
}

const FrameReport& Tracker::add_frame(PreparedFrame frame) {
  if (impl_->frames == 0 && frame.surface.n_faces() == 0)
    TT_THROW(InvalidInput, frame.name << ": the first frame is empty");
  return impl_->add(std::move(frame));
}

const FrameReport& Tracker::add_frame(const SurfaceMesh& target, const std::string& name) {
  return add_frame(prepare(target.clone(), name));
}

const FrameReport& Tracker::add_frame(const openvdb::FloatGrid& target, const std::string& name) {
  return add_frame(prepare(target, name));
}

const SurfaceMesh& Tracker::mesh() const { return impl_->mesh; }
const EventList& Tracker::events() const { return impl_->events; }
EventList Tracker::take_events() { return std::exchange(impl_->events, EventList{}); }
const std::vector<Vec3>& Tracker::velocities() const { return impl_->velocities; }
const FrameReport& Tracker::report() const { return impl_->report; }
const TrackerParams& Tracker::params() const { return impl_->params; }
std::size_t Tracker::frames() const { return impl_->frames; }
double Tracker::edge_length() const { return impl_->edge_length; }
double Tracker::voxel_size() const { return impl_->voxel_size; }
const Vec3& Tracker::lattice_origin() const { return impl_->origin; }

void Tracker::restore(SurfaceMesh mesh, std::size_t frames_done, double edge_length, double voxel_size,
                      const Vec3& lattice_origin) {
  if (!lattice_origin.allFinite()) TT_THROW(InvalidInput, "Tracker::restore: the lattice's origin is not finite");
  impl_->mesh = std::move(mesh);
  impl_->frames = frames_done;
  impl_->edge_length = edge_length;
  impl_->voxel_size = voxel_size;
  impl_->origin = lattice_origin;
  impl_->events.clear();
  impl_->velocities.assign(impl_->mesh.vertices_size(), Vec3::Zero());
  impl_->canonicalize();
}

}  // namespace topotrack
