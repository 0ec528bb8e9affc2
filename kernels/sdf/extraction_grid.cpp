#include "kernels/sdf/extraction_grid.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

namespace topotrack {
namespace {

//! Whether `points` lie on the edges of the grid of spacing r with nodes at multiples of r (see the header).
bool on_grid(std::span<const Vec3> points, double r) {
  std::size_t one = 0, two = 0, three = 0;
  for (const Vec3& p : points) {
    int on = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double t = p[axis] / r;
      on += std::abs(t - std::round(t)) < 1e-3;
    }
    one += on == 1;
    two += on >= 2;
    three += on == 3;
  }
  const double n = double(points.size());
  return two >= 0.6 * n && one <= 0.02 * n && three <= 0.5 * n;
}

}  // namespace

std::optional<double> extraction_grid_spacing(std::span<const Vec3> points, double edge_length) {
  if (points.size() < 64) return std::nullopt;
  for (const Vec3& p : points)
    if (!p.allFinite()) return std::nullopt;  // (and sorting below needs an order)
  // Lattice planes: coordinate values that recur exactly (every vertex on an edge across a plane x = k r
  // stores the same float k r). Interpolated coordinates recur only by symmetry, a few times each; a plane
  // through the surface holds a whole cross-section's vertices. So the 16 most frequent values per axis, those
  // with at least a quarter of the most frequent one's count (an axis may cross fewer planes), are planes, and
  // the smallest gap between them is the spacing or a small multiple of it.
  std::vector<double> planes;
  double smallest_gap = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> values(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) values[i] = points[i][axis];
    std::sort(values.begin(), values.end());
    std::vector<std::pair<std::size_t, double>> recurring;  // (count, value)
    for (std::size_t i = 0; i < values.size();) {
      std::size_t j = i;
      while (j < values.size() && values[j] == values[i]) ++j;
      if (j - i >= 3) recurring.emplace_back(j - i, values[i]);
      i = j;
    }
    const std::size_t top = std::min<std::size_t>(16, recurring.size());
    std::partial_sort(recurring.begin(), recurring.begin() + top, recurring.end(), std::greater<>());
    std::vector<double> best;
    for (std::size_t i = 0; i < top && 4 * recurring[i].first >= recurring[0].first; ++i)
      best.push_back(recurring[i].second);
    std::sort(best.begin(), best.end());
    for (std::size_t i = 1; i < best.size(); ++i) smallest_gap = std::min(smallest_gap, best[i] - best[i - 1]);
    planes.insert(planes.end(), best.begin(), best.end());
  }
  if (!std::isfinite(smallest_gap) || !(smallest_gap > 0)) return std::nullopt;
  // The largest divisor of that gap, by 1 to 8, on whose grid the points lie; refined by least squares over the
  // planes first (the stored floats carry their own rounding).
  for (int m = 1; m <= 8; ++m) {
    double r = smallest_gap / m;
    double pk = 0, kk = 0;
    for (const double p : planes) {
      const double k = std::round(p / r);
      if (std::abs(p / r - k) > 0.01) continue;
      pk += p * k;
      kk += k * k;
    }
    if (kk > 0) r = pk / kk;
    if (edge_length > 0 && r < 0.1 * edge_length) return std::nullopt;
    if (edge_length > 0 && r > 10 * edge_length) continue;
    if (on_grid(points, r)) return r;
  }
  return std::nullopt;
}

}  // namespace topotrack
