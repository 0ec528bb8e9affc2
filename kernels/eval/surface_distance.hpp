#pragma once
//! Distances between two surfaces, for `topotrack eval` (issue 8): how far the tracked mesh is from the
//! input frame it should match.
#include <span>

#include "kernels/mesh/surface_mesh.hpp"
#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

struct DistanceStats {
  std::size_t samples = 0;
  double mean = 0, rms = 0, max = 0;
  std::size_t max_index = 0;  //!< the point farthest from `to` (the first of equal ones)
  Vec3 max_point = Vec3::Zero();  //!< that point
};

//! Distance from each point to its closest point on `to` (parallel, deterministic).
DistanceStats one_sided_distance(std::span<const Vec3> points, const TargetSurface& to);

//! The points a surface is sampled at: its vertices and its triangle centroids.
std::vector<Vec3> surface_samples(const SurfaceMesh& mesh);

struct SurfaceDistance {
  DistanceStats a_to_b, b_to_a;
  double mean() const { return 0.5 * (a_to_b.mean + b_to_a.mean); }  //!< symmetric mean distance
  double hausdorff() const { return std::max(a_to_b.max, b_to_a.max); }
};
//! Symmetric distance between two meshes, sampled at vertices and triangle centroids of each.
//! \throw InvalidInput when either mesh has no triangles.
SurfaceDistance surface_distance(const SurfaceMesh& a, const SurfaceMesh& b);

}  // namespace topotrack
