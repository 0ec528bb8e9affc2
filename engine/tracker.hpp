#pragma once
//! The tracker: Algorithm 1 of the paper, fed one frame at a time. No files: a simulation post-processor
//! hands it each frame's closed surface (a mesh, or an OpenVDB level set straight from the simulation) and
//! gets back the tracked mesh M and that frame's event list. Memory is independent of the sequence length
//! (pairwise work only, §6).
#include <openvdb/openvdb.h>

#include <memory>
#include <string>
#include <vector>

#include "engine/profile.hpp"
#include "io/event_list.hpp"
#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

//! Seconds spent per stage on one frame: the columns of the paper's Table 1 (I/O is the caller's).
//! The work done by Tracker::prepare is included (signed_distance: φ_S; prepare: all of it), wherever
//! and whenever it ran, so the columns add up to the work of the frame, not to its wall time.
struct StageSeconds {
  double coarse = 0, fine = 0, improve = 0, signed_distance = 0, topology = 0;
  double prepare = 0;  //!< Tracker::prepare: checking S_n, its ray-casting scene and φ_S
  double total = 0;    //!< prepare + add_frame
};

//! S_n made ready for Tracker::add_frame: the part of Algorithm 1 that depends on S_n alone (and the
//! voxel size, fixed by the first frame), so that a caller can compute it for frame n+1 while frame n is
//! being tracked: the checked surface, its ray-casting scene for the alignment (§4.2, lines 5-6) and its
//! signed distance φ_S (line 10, §4.3). Whatever is missing (the scene or φ_S of a frame prepared before
//! the voxel size was known) add_frame computes itself; the result is the same either way, bit for bit.
struct PreparedFrame {
  std::string name;                        //!< for error messages
  SurfaceMesh surface;                     //!< S_n (for a level set: its zero set)
  std::unique_ptr<TargetSurface> target;   //!< the scene of S_n; null when S_n is empty or not built yet
  openvdb::FloatGrid::Ptr phi;             //!< φ_S at `voxel_size`; null when not computed
  double voxel_size = 0;                   //!< of phi
  StageSeconds seconds;                    //!< signed_distance (φ_S) and prepare
};

//! What one call of Tracker::add_frame did.
struct FrameReport {
  std::size_t index = 0;  //!< 0 for the first frame given to this tracker's sequence
  std::size_t vertices = 0, triangles = 0;
  std::size_t components = 0;
  long euler = 0;
  std::vector<std::size_t> events_by_kind;  //!< indexed by int(EventKind) - 1
  std::size_t complex_cells_self = 0, complex_cells_target = 0;  //!< ConstrainTopology(M, φ_M) and (M, φ_S)
  //! Why cells were complex in those two calls (ConstrainReport::cells_by_verdict).
  topology::VerdictCounts complex_reasons_self{}, complex_reasons_target{};
  int coarse_iterations = 0, fine_iterations = 0;
  int fine_rounds = 0;             //!< ray casting + solve rounds of the fine stage (FineParams::max_rounds)
  int relax_iterations = 0;        //!< of the relaxation on S_n towards M's shape (FineParams::relax; 0 by default)
  int coarse_pass_iterations = 0;  //!< rounds of the low-density large-motion pass (0: it did not run)
  //! ConstrainTopology calls that could not produce a valid mesh and were skipped (M kept as it was).
  std::size_t topology_failures = 0;
  //! Components below the lattice's resolution that M took from S_n or dropped (engine/small_components.hpp).
  std::size_t small_components_added = 0, small_components_removed = 0;
  //! TrackerParams::topology_refinements: lattices tried after the first because M's topology was not
  //! S_n's, and how many times the voxel size of the one kept was halved (0: the first lattice's result);
  //! of the retries, those that had S_n's topology but were not kept for their mesh quality.
  int topology_retries = 0, topology_level = 0, topology_rejected_for_quality = 0;
  std::vector<std::string> warnings;
  StageSeconds seconds;
};

class Tracker {
public:
  //! \throw InvalidInput on inconsistent parameters.
  explicit Tracker(TrackerParams params = {});
  ~Tracker();
  Tracker(Tracker&&) noexcept;
  Tracker& operator=(Tracker&&) noexcept;

  //! Track the next frame S_n (Algorithm 1, lines 4-14; for the first frame lines 1-2): add_frame(prepare(...)).
  //! \pre target is a closed 2-manifold (validate() passes). \throw InvalidInput if not, naming `name`.
  const FrameReport& add_frame(const SurfaceMesh& target, const std::string& name = "frame");
  //! Same with S_n given as a narrow-band level set (negative inside); it is used directly as φ_S when its
  //! voxel size matches the tracker's, and its zero set (marching cubes) as the surface for alignment.
  const FrameReport& add_frame(const openvdb::FloatGrid& target, const std::string& name = "frame");

  //! Do the work of add_frame that depends on S_n alone (see PreparedFrame), so that a caller can read and
  //! prepare frame n+1 while frame n is tracked. Const and thread-safe: it may run concurrently with other
  //! prepare calls and, once the first frame is done (the voxel size is then fixed), with add_frame (not
  //! with restore). Before the first frame it only checks the surface. It takes the surface: a caller
  //! holding a const mesh passes a clone(). \pre as add_frame. \throw InvalidInput as add_frame, naming `name`.
  PreparedFrame prepare(SurfaceMesh target, const std::string& name = "frame") const;
  //! Same for a level set (see add_frame): φ_S is a copy of `target` when the voxel sizes match.
  PreparedFrame prepare(const openvdb::FloatGrid& target, const std::string& name = "frame") const;
  //! Track a prepared frame: the same result as add_frame on the surface it was prepared from.
  //! \throw InvalidInput on an empty first frame.
  const FrameReport& add_frame(PreparedFrame frame);

  //! The tracked mesh M after the last add_frame (compacted; ids are the persistent vertex ids).
  const SurfaceMesh& mesh() const;
  //! The event list of the last add_frame (§4.4): it takes M of the previous frame to M of this one.
  //! Empty for the first frame.
  const EventList& events() const;
  //! Moves the event list of the last add_frame out, for a caller that keeps it beyond the next add_frame
  //! (a writer running beside it) without a copy: a frame's list on a fine lattice is ~100 MB. events() is
  //! empty afterwards; the next add_frame is unaffected (the tracker does not read its previous list).
  EventList take_events();
  //! Per vertex of mesh(), the motion since the previous frame (position minus the previous frame's
  //! position propagated through events(), §4.6): per-frame velocity for motion blur. Zero on the first frame.
  const std::vector<Vec3>& velocities() const;
  const FrameReport& report() const;
  const TrackerParams& params() const;
  //! Frames tracked so far.
  std::size_t frames() const;
  //! L and the voxel size in effect (fixed by the first frame when edge_length is 0).
  double edge_length() const;
  double voxel_size() const;
  //! The lattices' node (0, 0, 0): the origin of the grid the first frame was extracted on when the lattice is
  //! that grid's (TrackerParams::extraction_grid), else 0 (signed_distance.hpp's convention).
  const Vec3& lattice_origin() const;

  //! Resume from a saved state: M and the fixed scalars (see engine/checkpoint.hpp); the next add_frame
  //! continues exactly as an uninterrupted run would.
  void restore(SurfaceMesh mesh, std::size_t frames_done, double edge_length, double voxel_size,
               const Vec3& lattice_origin = Vec3::Zero());

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace topotrack
