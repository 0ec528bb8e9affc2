#pragma once
//! Mesh improvement (§4.1, following Wojtan et al. 2011): split long edges at their midpoint, collapse
//! short edges, edges of triangles with a small interior angle and edges across a small dihedral
//! angle; flip edges of bad triangles where the surface is nearly flat (the paper's §7 wish). Every
//! re-sampling is recorded in an EventList (§4.4).
#include "io/event_list.hpp"
#include "kernels/mesh/mesh_queries.hpp"
#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! Parameters of improve_mesh; defaults are the paper's (§4.1). With target edge length L the edge
//! length bounds are L_min = L / sqrt(ratio) and L_max = L * sqrt(ratio) (L/2 and 2L for ratio 4), so
//! L_max : L_min = ratio and L is their geometric middle.
struct ImproveParams {
  double target_edge_length = 0;  //!< L; <= 0: the mean edge length of the input mesh
  double ratio = 4;               //!< L_max : L_min (§4.1: 4 : 1)
  double min_angle_deg = 10;      //!< smallest allowed interior triangle angle (§4.1: 10°)
  double min_dihedral_deg = 45;   //!< smallest allowed dihedral angle, 180 = flat (§4.1: 45°)
  int max_iterations = 20;        //!< cap on the split / collapse / flip rounds
  bool enable_flips = true;       //!< fix bad angles by flips where the surface is nearly flat (§7)
  //! Where no flip or collapse can fix a bad triangle, move one of its corners a little along the surface
  //! (tangential relaxation, within max_surface_deviation; the vertex keeps its id, no event); likewise
  //! slide an end of a short edge that no collapse may remove until it reaches L_min, and round off a
  //! barely-folded crease by a small Laplacian move before resorting to a fold collapse.
  bool enable_relaxation = true;
  //! Bound on how far one operation (collapse, flip, relaxation, slide) may move the surface, as a fraction
  //! of L; twice this for an operation that removes a triangle with an angle below 2°. Removals of folds
  //! (dihedral angle below min_dihedral_deg, removed on purpose) are exempt: of the collapses and vertex
  //! moves that can remove one, the one that moves the surface least (exact local distance) goes. The
  //! slide that lengthens a short edge no collapse may remove also moves a vertex by at most L_min / 2
  //! within its tangent plane. Every bound depends on the mesh alone, never on what the call did before, so
  //! a second call refuses what the first refused (fixed point, issue 3).
  double max_operation_deviation = 0.2;
  //! Hard cap on how far one fold removal may move the surface, as a fraction of L: a fold whose gentlest
  //! removal would move it farther is left (on resurfaced frames 1-3 of the three captures at 128 voxels
  //! the whole call moves the surface by at most 0.31 L; the largest fold removal, 0.24 L, is on pcow's
  //! knife-edge creases).
  double max_surface_deviation = 0.8;
  //! A short edge below this fraction of L_min may be collapsed even where that sharpens a crease or adds a fold
  //! (the fold pass then removes the fold its gentlest way), provided its one-ring spans L_min (our addition).
  //! Without it, needles whose short edge lies in a crease stayed for good: the seams where ConstrainTopology's
  //! patch meets the kept mesh (resurfaced pcow, 40 tracked frames: triangles below 2° in 13 frames and
  //! dihedral angles below 45° in 6 with 0, none and 2 with 0.3; samba: 4 and 4 frames with 0, none with 0.3;
  //! docs/results.md). 0: never.
  double crease_collapse_fraction = 0.3;
  //! Flips only across edges whose faces' normals differ by at most this (nearly coplanar).
  double max_flip_bend_deg = 20;
  //! Fill ImproveReport::quality: an extra O(n) pass over the output that costs far more than improving
  //! an already-good mesh (measured, 76k-vertex resurfaced elephant frame: 0.18 s with it against 0.024 s
  //! without, median of 15, machine loaded), so off by default: the tracker improves every frame twice
  //! and reads no report. `topotrack improve` turns it on.
  bool measure_quality = false;
  //! Debugging aid for tests: call SurfaceMesh::validate() after every operation (O(n) each).
  bool validate_each_step = false;
};

struct ImproveReport {
  std::size_t splits = 0, collapses = 0, flips = 0;
  std::size_t relaxations = 0;    //!< vertex moves: relax, lengthen, unfold (no event: the vertex keeps its id)
  int iterations = 0;             //!< rounds run (a round that finds nothing to do ends the loop)
  double min_edge_length = 0;     //!< L_min used
  double max_edge_length = 0;     //!< L_max used
  QualityStats quality;           //!< of the output mesh (when measure_quality)
  // Seconds per phase.
  double seconds_scan = 0;        //!< parallel searches for candidates
  double seconds_split = 0, seconds_collapse = 0, seconds_bad_triangles = 0, seconds_folds = 0;
  double seconds_finish = 0;      //!< compaction and quality measurement
  double seconds = 0;             //!< total
};

//! Improve `mesh` in place (§4.1) and append the re-sampling events to `events` when not null (§4.4):
//! a split of (i,j) records record_split(i, j, k, 0.5) with k the new vertex's fresh id; a collapse of
//! (i,j) moves the kept vertex to the midpoint, gives it a fresh id k and records record_collapse(i, j, k).
//! Flips record nothing (no vertex data moves). Vertex properties are interpolated as the events say.
//! Every operation keeps a closed 2-manifold (link condition, no fold-over or zero-area triangle, no
//! duplicate edge). Degenerate triangles (is_near_degenerate: needles, caps, zero area, also after
//! rounding to float) count as bad whatever min_angle_deg is and are removed by a flip or a collapse;
//! where neither can go (a needle on a tube so thin that its collapse would pinch it, a cap between
//! creases) a tangential relaxation moves a corner (enable_relaxation; no event, the vertex keeps its id).
//! In a neighbourhood that is creased already an operation may go if it neither sharpens the sharpest
//! crease nor adds a fold. Where that leaves a triangle below 2° at the fixed point, a last resort may collapse
//! into a crease where the two-ring spans L_min and collapse a valence-3 spike tip in fold mode. The mesh is
//! compacted at the end (ids survive). A mesh already within bounds is left
//! bit-identical with zero events after one parallel O(n) scan. Deterministic for any thread count
//! (candidates are found in parallel, operations applied serially in a fixed order).
//! \pre mesh is a closed 2-manifold.  \throw InvalidInput on bad parameters or an open mesh (boundary edges).
ImproveReport improve_mesh(SurfaceMesh& mesh, const ImproveParams& params = {}, EventList* events = nullptr);

//! The mean edge length of `mesh`, summed in parallel in a fixed order (bit-identical for any thread
//! count); the default target edge length of improve_mesh.
double mean_edge_length_parallel(const SurfaceMesh& mesh);

}  // namespace topotrack
