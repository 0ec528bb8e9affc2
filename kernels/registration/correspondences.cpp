#include "kernels/registration/correspondences.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <numbers>

namespace topotrack {

Correspondence find_correspondence(const TargetSurface& target, const Vec3& x, const Vec3& n,
                                   const CorrespondenceParams& params) {
  Correspondence out;
  const double len = n.norm();
  if (!(len > 0) || !std::isfinite(len)) return out;
  const Vec3 dir = n / len;
  const TargetSurface::Hit hit = params.closest_point ? target.closest_point(x, params.max_distance)
                                                      : target.cast_undirected(x, dir, params.max_distance);
  if (!hit.hit) return out;
  out.point = hit.point;
  out.normal = hit.normal;
  out.distance = hit.distance;
  if (params.max_normal_angle_deg < 180) {
    const double cos_max = std::cos(params.max_normal_angle_deg * std::numbers::pi / 180.0);
    if (!(dir.dot(hit.normal) >= cos_max)) {
      out.status = CorrespondenceStatus::NormalAngle;
      return out;
    }
  }
  if (!params.closest_point && std::isfinite(params.max_closest_ratio)) {
    // The closest point is at most hit.distance away, which bounds the query.
    const TargetSurface::Hit closest = target.closest_point(x, hit.distance);
    const double closest_distance = closest.hit ? closest.distance : hit.distance;
    const double slack = 1e-9 * target.bbox_diagonal();
    if (hit.distance > params.max_closest_ratio * closest_distance + slack) {
      out.status = CorrespondenceStatus::TooFar;
      return out;
    }
  }
  out.status = CorrespondenceStatus::Ok;
  return out;
}

std::vector<Correspondence> find_correspondences(const TargetSurface& target, std::span<const Vec3> x,
                                                 std::span<const Vec3> n, const CorrespondenceParams& params) {
  if (x.size() != n.size())
    TT_THROW(InvalidInput, "find_correspondences: " << x.size() << " points but " << n.size() << " normals");
  std::vector<Correspondence> out(x.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, x.size(), 128), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = find_correspondence(target, x[i], n[i], params);
  });
  return out;
}

CorrespondenceCounts count_correspondences(std::span<const Correspondence> c) {
  CorrespondenceCounts k;
  for (const auto& x : c) switch (x.status) {
      case CorrespondenceStatus::Ok: ++k.ok; break;
      case CorrespondenceStatus::NoHit: ++k.no_hit; break;
      case CorrespondenceStatus::NormalAngle: ++k.normal_angle; break;
      case CorrespondenceStatus::TooFar: ++k.too_far; break;
    }
  return k;
}

}  // namespace topotrack
