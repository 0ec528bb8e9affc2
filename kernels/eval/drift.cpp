#include "kernels/eval/drift.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "io/error.hpp"

namespace topotrack {

DriftStats drift_stats(std::span<const Vec3> tracked, std::span<const Vec3> expected) {
  DriftStats s;
  s.points = tracked.size();
  if (tracked.empty()) return s;
  std::vector<double> d(tracked.size());
  double sum = 0, sum2 = 0;
  for (std::size_t i = 0; i < tracked.size(); ++i) {
    d[i] = (tracked[i] - expected[i]).norm();
    sum += d[i];
    sum2 += d[i] * d[i];
    s.max = std::max(s.max, d[i]);
  }
  s.mean = sum / double(d.size());
  s.rms = std::sqrt(sum2 / double(d.size()));
  std::nth_element(d.begin(), d.begin() + std::ptrdiff_t(d.size() / 2), d.end());
  s.median = d[d.size() / 2];
  return s;
}

std::vector<Vec3> expected_by_rotation(std::span<const Vec3> material, const Eigen::Matrix3d& R, const Vec3& center,
                                       const Vec3& translation) {
  std::vector<Vec3> out(material.size());
  for (std::size_t i = 0; i < material.size(); ++i) out[i] = R * (material[i] - center) + center + translation;
  return out;
}

Eigen::Vector3d barycentric(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 v0 = b - a, v1 = c - a, v2 = p - a;
  const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
  const double den = d00 * d11 - d01 * d01;
  if (!(std::abs(den) > 0)) return {1.0 / 3, 1.0 / 3, 1.0 / 3};
  const double v = (d11 * d20 - d01 * d21) / den, w = (d00 * d21 - d01 * d20) / den;
  return {1 - v - w, v, w};
}

std::vector<Vec3> expected_by_correspondence(std::span<const Vec3> material, const TargetSurface& first,
                                             std::span<const Vec3> frame_n_positions) {
  if (frame_n_positions.size() != first.n_vertices())
    TT_THROW(InvalidInput, "ground truth: frame has " << frame_n_positions.size() << " vertices, frame 1 has "
                                                      << first.n_vertices() << " (a coherent sequence keeps them)");
  const auto hits = first.closest_points(material);
  std::vector<Vec3> out(material.size());
  const auto& P = first.positions();
  const auto& T = first.triangles();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, material.size(), 1024), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const auto& t = T[hits[i].face];
      const Eigen::Vector3d w = barycentric(hits[i].point, P[t[0]], P[t[1]], P[t[2]]);
      out[i] = w[0] * frame_n_positions[t[0]] + w[1] * frame_n_positions[t[1]] + w[2] * frame_n_positions[t[2]];
    }
  });
  return out;
}

}  // namespace topotrack
