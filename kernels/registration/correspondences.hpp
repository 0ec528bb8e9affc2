#pragma once
//! Correspondence search of the non-rigid alignment (§4.2): project a point onto the target S_n along
//! its normal with an undirected ray (nearest hit either way), and prune the match where the normals
//! differ by more than a given angle or where the hit is more than a given factor farther than the
//! closest point on S_n (coarse stage), or farther than sigma (fine stage).
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "kernels/raycast/target_surface.hpp"

namespace topotrack {

enum class CorrespondenceStatus : std::uint8_t {
  Ok,           //!< a valid match
  NoHit,        //!< the ray misses S_n within max_distance (or the normal is zero)
  NormalAngle,  //!< the normals at x and c differ by more than max_normal_angle_deg
  TooFar,       //!< c is more than max_closest_ratio times farther than the closest point of S_n
};

struct CorrespondenceParams {
  double max_normal_angle_deg = 60;  //!< §4.2 coarse stage; >= 180 disables the test
  double max_closest_ratio = 3;      //!< §4.2 coarse stage; infinity disables the test (and the closest-point query)
  double max_distance = std::numeric_limits<double>::infinity();  //!< ray length either way (fine stage: sigma)
  //! Match x to its closest point on S_n instead of casting along the normal (the ICP-style search of
  //! Li et al. 2009; our option for large motion, where a normal ray often lands on the wrong part).
  //! The normal-angle test still applies; the closest-point ratio test is moot.
  bool closest_point = false;
};

struct Correspondence {
  CorrespondenceStatus status = CorrespondenceStatus::NoHit;
  Vec3 point = Vec3::Zero();   //!< c, on S_n
  Vec3 normal = Vec3::Zero();  //!< unit normal of S_n at c
  double distance = 0;         //!< |x - c|
  bool valid() const { return status == CorrespondenceStatus::Ok; }
};

//! The correspondence of point x with (not necessarily unit) normal n.
Correspondence find_correspondence(const TargetSurface& target, const Vec3& x, const Vec3& n,
                                   const CorrespondenceParams& params = {});

//! find_correspondence for every (x, n), in parallel; results indexed like the input.
std::vector<Correspondence> find_correspondences(const TargetSurface& target, std::span<const Vec3> x,
                                                 std::span<const Vec3> n, const CorrespondenceParams& params = {});

//! The target sampled for the backward (target -> source) correspondences: its triangles' centroids,
//! unit normals and areas (degenerate triangles left out), in triangle order; every k-th triangle
//! when there are more than `max_samples` (0: all).
struct TargetSamples {
  std::vector<Vec3> point, normal;
  std::vector<double> area;
};
TargetSamples sample_target(const TargetSurface& target, std::size_t max_samples = 0);

//! Backward correspondences (our addition for large motion, the target -> source half of a symmetric
//! ICP): each target sample is matched to the nearest of the points x (the deformed graph nodes)
//! whose normal is within max_normal_angle_deg of its own (among the `candidates` nearest); node j's
//! correspondence is the area-weighted mean point and normal of the samples matched to it (NoHit when
//! none). A part of the target that no forward ray reaches (a limb that swung away) thus pulls the
//! nearest compatible nodes. Deterministic: matches in parallel, sums in sample order.
std::vector<Correspondence> find_backward_correspondences(const TargetSamples& samples, std::span<const Vec3> x,
                                                          std::span<const Vec3> n, double max_normal_angle_deg,
                                                          int candidates = 8);

//! Counts per status of a list of correspondences.
struct CorrespondenceCounts {
  std::size_t ok = 0, no_hit = 0, normal_angle = 0, too_far = 0;
  std::size_t pruned() const { return no_hit + normal_angle + too_far; }
};
CorrespondenceCounts count_correspondences(std::span<const Correspondence> c);

}  // namespace topotrack
