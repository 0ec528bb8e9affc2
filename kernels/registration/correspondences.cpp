#include "kernels/registration/correspondences.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "kernels/spatial/point_index.hpp"

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
    // Pruned when the closest point is nearer than (hit.distance - slack) / ratio: only a point within that (padded by
    // 1e-6, so that no hit beyond it means the test below would pass) is looked for, a far smaller query than the
    // closest point itself where the ray's hit is about as near (most nodes); the decision is the same.
    const double slack = 1e-9 * target.bbox_diagonal();
    const double bound = std::min(hit.distance, (hit.distance - slack) / params.max_closest_ratio * (1 + 1e-6));
    const TargetSurface::Hit closest = target.closest_point(x, bound);
    const double closest_distance = closest.hit ? closest.distance : hit.distance;
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

TargetSamples sample_target(const TargetSurface& target, std::size_t max_samples) {
  TargetSamples s;
  const auto& P = target.positions();
  const auto& T = target.triangles();
  const std::size_t stride = max_samples > 0 ? std::max<std::size_t>(1, (T.size() + max_samples - 1) / max_samples) : 1;
  for (std::size_t f = 0; f < T.size(); f += stride) {
    const Vec3& a = P[T[f][0]];
    const Vec3& b = P[T[f][1]];
    const Vec3& c = P[T[f][2]];
    const double area = 0.5 * (b - a).cross(c - a).norm();
    if (!(area > 0)) continue;
    s.point.push_back((a + b + c) / 3.0);
    s.normal.push_back(target.face_normal(Index(f)));
    s.area.push_back(area);
  }
  return s;
}

std::vector<Correspondence> find_backward_correspondences(const TargetSamples& samples, std::span<const Vec3> x,
                                                          std::span<const Vec3> n, double max_normal_angle_deg,
                                                          int candidates) {
  if (x.size() != n.size())
    TT_THROW(InvalidInput, "find_backward_correspondences: " << x.size() << " points but " << n.size() << " normals");
  if (candidates < 1) TT_THROW(InvalidInput, "find_backward_correspondences: candidates must be at least 1");
  std::vector<Correspondence> out(x.size());
  if (x.empty()) return out;
  const PointIndex index(x);
  const double cos_max = max_normal_angle_deg < 180 ? std::cos(max_normal_angle_deg * std::numbers::pi / 180.0) : -2.0;
  const std::size_t ns = samples.point.size();
  std::vector<Index> match(ns, kInvalidIndex);
  auto compatible = [&](Index j, std::size_t i) {
    const double len = n[j].norm();
    return len > 0 && n[j].dot(samples.normal[i]) >= cos_max * len;
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, ns, 256), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const PointIndex::Neighbor q = index.nearest(samples.point[i]);
      if (compatible(q.index, i)) {
        match[i] = q.index;
        continue;
      }
      if (candidates < 2) continue;
      for (const PointIndex::Neighbor& c : index.k_nearest(samples.point[i], std::size_t(candidates)))
        if (compatible(c.index, i)) {
          match[i] = c.index;
          break;
        }
    }
  });
  std::vector<double> weight(x.size(), 0);
  for (std::size_t i = 0; i < ns; ++i) {
    const Index j = match[i];
    if (j == kInvalidIndex) continue;
    out[j].point += samples.area[i] * samples.point[i];
    out[j].normal += samples.area[i] * samples.normal[i];
    weight[j] += samples.area[i];
  }
  for (std::size_t j = 0; j < x.size(); ++j) {
    const double len = out[j].normal.norm();
    if (!(weight[j] > 0) || !(len > 0)) {
      out[j] = Correspondence{};
      continue;
    }
    out[j].point /= weight[j];
    out[j].normal /= len;
    out[j].distance = (x[j] - out[j].point).norm();
    out[j].status = CorrespondenceStatus::Ok;
  }
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
