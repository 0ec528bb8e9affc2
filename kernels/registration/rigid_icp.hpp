#pragma once
//! Global rigid pre-alignment for large motion (our addition before §4.2's coarse stage, which
//! assumes the surfaces start within the capture range of its correspondences): trimmed ICP
//! (Chetverikov et al. 2002) with closest points on the target, pairs whose normals differ by more
//! than 60° dropped (the §4.2 test), each step a Gauss–Newton step of the rotation and translation on
//! §4.2's fitting energy alpha_point |x - c|^2 + alpha_plane <n, x - c>^2 over the kept pairs. Tried from the
//! identity and from the area-weighted centroids matched, the lower trimmed mean distance winning; then from the
//! principal axes matched four ways, which win only by a clear margin (RigidIcpParams::axes_win_ratio). The transform
//! is applied only when it beats the identity.
#include <cstddef>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

struct RigidIcpParams {
  double point_weight = 0.1;         //!< alpha_point (§4.2)
  double plane_weight = 1;           //!< alpha_plane (§4.2)
  double trim_fraction = 0.8;        //!< fraction of the (normal-compatible) pairs kept, the closest ones
  double max_normal_angle_deg = 60;  //!< pair pruning (§4.2's coarse test); >= 180 disables it
  int max_iterations = 40;           //!< ICP steps per start
  //! Converged when a step moves no sample by more than this fraction of the target's bbox diagonal.
  double tolerance = 1e-5;
  //! Also converged when a step lowers the trimmed mean distance by less than this fraction.
  double score_tolerance = 1e-3;
  std::size_t max_samples = 1000;    //!< source vertices used (every k-th live vertex)
  bool try_centroid_start = true;    //!< also start from the area-weighted centroids matched
  //! Also start from the source's principal axes turned onto the target's, four ways (our addition), and take the
  //! best of those ends only where its trimmed mean distance is at most this fraction of the two starts' best
  //! (0: not tried). A turn beyond ICP's reach is then found (pcow frame 57 onto 72, turned 102°: the two starts end
  //! at 4.4 % of the diagonal in a wrong pose, the axes at 1.2 % in the right one). The margin is there because the
  //! trimmed 80 % cannot tell poses that fit about as well: at pcow 33 onto 48 an axes end turned 150° off the right
  //! pose fits to 1.55 % against the right pose's 1.63 %. Measured in docs/results.md (2026-12-04 night).
  double axes_win_ratio = 0.5;
};

struct RigidIcpReport {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  //!< the applied transform x -> R x + t
  Vec3 translation = Vec3::Zero();
  bool applied = false;              //!< false: the identity was at least as good, mesh untouched
  int iterations = 0;                //!< ICP steps over all starts
  int axes_starts = 0;               //!< starts from the principal axes tried (axes_win_ratio)
  bool axes_won = false;             //!< the applied transform is an axes start's
  std::size_t samples = 0;
  double distance_start = 0;         //!< trimmed mean sample-to-target distance at the identity
  double distance_end = 0;           //!< same after the applied transform (= start when not applied)
  double seconds = 0;
};

//! \throw InvalidInput unless 0 < trim_fraction <= 1, max_iterations >= 0, tolerances >= 0, max_samples >= 3,
//! 0 <= axes_win_ratio <= 1.
void validate(const RigidIcpParams& params);

//! The trimmed mean closest-point distance of (every k-th live vertex of) `mesh` to `target`:
//! the misfit measure of align_rigid, cheap enough to decide whether to pre-align at all (infinity
//! when fewer than 3 samples pass the normal test).  \throw InvalidInput on bad parameters.
double trimmed_mean_distance(const SurfaceMesh& mesh, const TargetSurface& target, const RigidIcpParams& params = {});

//! Move `mesh` rigidly onto `target` by trimmed ICP (see above). Positions only. Deterministic for
//! any thread count.  \throw InvalidInput on bad parameters, an empty mesh or a non-finite position.
RigidIcpReport align_rigid(SurfaceMesh& mesh, const TargetSurface& target, const RigidIcpParams& params = {});

}  // namespace topotrack
