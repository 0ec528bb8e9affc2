#include "kernels/sdf/winding_number.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "io/error.hpp"

namespace topotrack {

double solid_angle(const Vec3& p, const Vec3& a0, const Vec3& b0, const Vec3& c0) {
  const Vec3 a = a0 - p, b = b0 - p, c = c0 - p;
  const double la = a.norm(), lb = b.norm(), lc = c.norm();
  const double num = a.dot(b.cross(c));
  const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
  return 2 * std::atan2(num, den);
}

WindingNumber::WindingNumber(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles,
                             double accuracy)
    : positions_(positions.begin(), positions.end()),
      triangles_(triangles.begin(), triangles.end()),
      accuracy_(accuracy) {
  if (!(accuracy >= 1)) TT_THROW(InvalidInput, "winding number: accuracy must be >= 1, got " << accuracy);
  for (std::size_t f = 0; f < triangles_.size(); ++f)
    for (Index v : triangles_[f])
      if (v >= positions_.size())
        TT_THROW(InvalidInput, "winding number: triangle " << f << " has vertex index " << v << " out of range");
  if (triangles_.empty()) return;
  order_.resize(triangles_.size());
  std::vector<Vec3> centroids(triangles_.size());
  for (std::size_t f = 0; f < triangles_.size(); ++f) {
    order_[f] = std::uint32_t(f);
    const auto& t = triangles_[f];
    centroids[f] = (positions_[t[0]] + positions_[t[1]] + positions_[t[2]]) / 3.0;
  }
  nodes_.reserve(2 * triangles_.size() / 4 + 1);
  build(0, std::uint32_t(triangles_.size()), centroids);
}

std::uint32_t WindingNumber::build(std::uint32_t first, std::uint32_t count, std::vector<Vec3>& centroids) {
  constexpr std::uint32_t kLeafSize = 8;
  const std::uint32_t id = std::uint32_t(nodes_.size());
  nodes_.emplace_back();
  Node node;
  Vec3 lo = centroids[order_[first]], hi = lo;
  double total = 0;
  Vec3 weighted = Vec3::Zero();
  for (std::uint32_t i = first; i < first + count; ++i) {
    const auto& t = triangles_[order_[i]];
    const Vec3 n = 0.5 * (positions_[t[1]] - positions_[t[0]]).cross(positions_[t[2]] - positions_[t[0]]);
    const double a = n.norm();
    node.area += n;
    weighted += a * centroids[order_[i]];
    total += a;
    lo = lo.cwiseMin(centroids[order_[i]]);
    hi = hi.cwiseMax(centroids[order_[i]]);
  }
  node.centre = total > 0 ? Vec3(weighted / total) : Vec3(0.5 * (lo + hi));
  for (std::uint32_t i = first; i < first + count; ++i)
    for (Index v : triangles_[order_[i]]) node.radius = std::max(node.radius, (positions_[v] - node.centre).norm());
  if (count <= kLeafSize) {
    node.first = first;
    node.count = count;
  } else {
    // Median split along the longest axis of the centroids' box; ties by triangle index (deterministic).
    int axis = 0;
    (hi - lo).maxCoeff(&axis);
    const std::uint32_t half = count / 2;
    std::nth_element(order_.begin() + first, order_.begin() + first + half, order_.begin() + first + count,
                     [&](std::uint32_t a, std::uint32_t b) {
                       const double ca = centroids[a][axis], cb = centroids[b][axis];
                       return ca < cb || (ca == cb && a < b);
                     });
    node.left = build(first, half, centroids);
    node.right = build(first + half, count - half, centroids);
  }
  nodes_[id] = node;
  return id;
}

double WindingNumber::operator()(const Vec3& p) const {
  if (nodes_.empty()) return 0;
  double sum = 0;
  std::uint32_t stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    const Vec3 d = n.centre - p;
    const double r2 = d.squaredNorm();
    if (r2 > accuracy_ * accuracy_ * n.radius * n.radius) {
      sum += n.area.dot(d) / (r2 * std::sqrt(r2));  // the dipole: the solid angle of the whole node
    } else if (n.count > 0) {
      for (std::uint32_t i = n.first; i < n.first + n.count; ++i) {
        const auto& t = triangles_[order_[i]];
        sum += solid_angle(p, positions_[t[0]], positions_[t[1]], positions_[t[2]]);
      }
    } else {
      stack[top++] = n.right;
      stack[top++] = n.left;
    }
  }
  return sum / (4 * std::numbers::pi);
}

std::vector<double> WindingNumber::evaluate(std::span<const Vec3> points) const {
  std::vector<double> w(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 256), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) w[i] = (*this)(points[i]);
  });
  return w;
}

}  // namespace topotrack
