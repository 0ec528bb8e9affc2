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

//! The largest divisor of `gap`, by 1 to 8, on whose grid the points lie; refined by least squares over the
//! planes first (the stored floats carry their own rounding).
std::optional<double> divide_gap(std::span<const Vec3> points, const std::vector<double>& planes, double gap,
                                 double edge_length, bool* too_fine) {
  for (int m = 1; m <= 8; ++m) {
    double r = gap / m;
    double pk = 0, kk = 0;
    for (const double p : planes) {
      const double k = std::round(p / r);
      if (std::abs(p / r - k) > 0.01) continue;
      pk += p * k;
      kk += k * k;
    }
    if (kk > 0) r = pk / kk;
    if (edge_length > 0 && r < 0.1 * edge_length) {
      *too_fine = true;
      return std::nullopt;
    }
    if (edge_length > 0 && r > 10 * edge_length) continue;
    if (on_grid(points, r)) return r;
  }
  return std::nullopt;
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
  // the smallest gap between them is the spacing or a small multiple of it. A flat face of the surface normal
  // to an axis, off the grid's planes (the walls and floor of a tank), recurs more than any lattice plane and
  // can leave none within a quarter of its count: then the gaps between all 16 most frequent values of each
  // axis are tried (gen splash's first frame).
  std::vector<double> planes, all_planes, other_gaps;
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
    std::vector<double> best, all;
    for (std::size_t i = 0; i < top; ++i) {
      all.push_back(recurring[i].second);
      if (4 * recurring[i].first >= recurring[0].first) best.push_back(recurring[i].second);
    }
    std::sort(best.begin(), best.end());
    std::sort(all.begin(), all.end());
    for (std::size_t i = 1; i < best.size(); ++i) smallest_gap = std::min(smallest_gap, best[i] - best[i - 1]);
    for (std::size_t i = 1; i < all.size(); ++i) other_gaps.push_back(all[i] - all[i - 1]);
    planes.insert(planes.end(), best.begin(), best.end());
    all_planes.insert(all_planes.end(), all.begin(), all.end());
  }
  bool too_fine = false;
  if (std::isfinite(smallest_gap) && smallest_gap > 0) {
    if (auto r = divide_gap(points, planes, smallest_gap, edge_length, &too_fine)) return r;
    if (too_fine) return std::nullopt;
  }
  // A grid's points lie on every grid of a divisor of its spacing too: keep the largest spacing that passes.
  std::sort(other_gaps.begin(), other_gaps.end(), std::greater<>());
  other_gaps.erase(std::unique(other_gaps.begin(), other_gaps.end()), other_gaps.end());
  std::optional<double> found;
  for (const double gap : other_gaps) {
    if (found && gap <= *found) break;
    if (!(gap > 0) || gap == smallest_gap || (edge_length > 0 && gap < 0.1 * edge_length)) continue;
    const auto r = divide_gap(points, all_planes, gap, edge_length, &too_fine);
    if (r && (!found || *r > *found)) found = r;
  }
  return found;
}

}  // namespace topotrack
