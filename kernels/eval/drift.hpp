#pragma once
//! Drift of tracked points against ground truth (issue 8): a point of the tracked mesh carries its
//! frame-1 "material" position through the event lists (§4.6); the ground truth says where that
//! material point is in frame n; the drift is the distance between that and the tracked position.
#include <Eigen/Core>
#include <span>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

struct DriftStats {
  std::size_t points = 0;
  double mean = 0, rms = 0, max = 0, median = 0;
};

//! Statistics of |tracked[i] - expected[i]|. \pre equal sizes.
DriftStats drift_stats(std::span<const Vec3> tracked, std::span<const Vec3> expected);

//! Ground truth by a rigid motion (the blobs generator): expected = R (material - c) + c + t.
std::vector<Vec3> expected_by_rotation(std::span<const Vec3> material, const Eigen::Matrix3d& R, const Vec3& center,
                                       const Vec3& translation = Vec3::Zero());

//! Ground truth by a coherent sequence (a resurfaced source): each material point is located on the
//! coherent frame 1 (`first`: closest point, its triangle and barycentric coordinates) and mapped to the
//! same barycentric point of the same triangle in the coherent frame n (`frame_n_positions`, same
//! connectivity as `first`). \throw InvalidInput when the vertex counts differ.
std::vector<Vec3> expected_by_correspondence(std::span<const Vec3> material, const TargetSurface& first,
                                             std::span<const Vec3> frame_n_positions);

//! Barycentric coordinates of p with respect to triangle (a, b, c) (p projected onto its plane).
Eigen::Vector3d barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace topotrack
