#include "kernels/sdf/extraction_grid.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Dense>

namespace topotrack {
namespace {

//! Whether `points` lie on the edges of the grid (see the header).
bool on_grid(std::span<const Vec3> points, double r, const Vec3& origin) {
  std::size_t one = 0, two = 0, three = 0;
  for (const Vec3& p : points) {
    int on = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const double t = (p[axis] - origin[axis]) / r;
      on += std::abs(t - std::round(t)) < 1e-3;
    }
    one += on == 1;
    two += on >= 2;
    three += on == 3;
  }
  const double n = double(points.size());
  return two >= 0.6 * n && one <= 0.02 * n && three <= 0.5 * n;
}

//! Per axis, the recurring coordinate values taken for lattice planes, ascending.
using AxisPlanes = std::array<std::vector<double>, 3>;

//! Where the axis's planes lie between multiples of r, in [-r/2, r/2]: the offset most of them share (a flat
//! face off the grid, a tank's wall, may recur more than any lattice plane but is one plane); the lowest
//! plane's among equals. 0 within the on-grid tolerance of 0, and on an axis without planes.
double axis_origin(const std::vector<double>& planes, double r) {
  const auto offset = [r](double p) { return p - r * std::round(p / r); };
  double best = 0;
  std::size_t best_count = 0;
  for (const double p : planes) {
    const double o = offset(p);
    std::size_t count = 0;
    for (const double q : planes) count += std::abs(offset(q - o)) < 2e-3 * r;
    if (count > best_count) best = o, best_count = count;
  }
  return std::abs(best) < 1e-3 * r ? 0.0 : best;
}

//! The grid of the largest divisor of `gap`, by 1 to 8, on which the points lie. The origin starts from the
//! offset each axis's planes share (axis_origin); spacing and origin are then refined by least squares over
//! the planes (the stored floats carry their own rounding), twice. A grid at the origin keeps origin 0 exactly
//! and the spacing sum p k / sum k^2 over its planes, as before origins were found.
std::optional<ExtractionGrid> divide_gap(std::span<const Vec3> points, const AxisPlanes& axes, double gap,
                                         double edge_length, bool* too_fine) {
  for (int m = 1; m <= 8; ++m) {
    const double r0 = gap / m;
    ExtractionGrid g{r0, Vec3::Zero()};
    // f(axis, plane, k) for each plane within 1 % of r0 of its multiple k of r0 from the origin.
    const auto for_each_plane = [&](auto&& f) {
      for (int a = 0; a < 3; ++a)
        for (const double plane : axes[a]) {
          const double p = plane - g.origin[a];
          const double k = std::round(p / r0);
          if (std::abs(p / r0 - k) <= 0.01) f(a, plane, k);
        }
    };
    for (int a = 0; a < 3; ++a) g.origin[a] = axis_origin(axes[a], r0);
    for (int round = 0; round < 2; ++round) {
      // plane = origin[a] + k r: least squares in (r, origin) where an origin is off 0, then r alone with the
      // origins fixed (for a grid at the origin the planes' own multiples: sum p k / sum k^2).
      Eigen::Matrix4d AtA = Eigen::Matrix4d::Zero();
      Eigen::Vector4d Atb = Eigen::Vector4d::Zero();
      for (int a = 0; a < 3; ++a)
        if (g.origin[a] == 0) AtA(a + 1, a + 1) += 1;  // held at 0
      for_each_plane([&](int a, double plane, double k) {
        Eigen::Vector4d row = Eigen::Vector4d::Zero();
        row[0] = k;
        if (g.origin[a] != 0) row[a + 1] = 1;
        AtA += row * row.transpose();
        Atb += row * plane;
      });
      if (AtA(0, 0) == 0) break;
      if (!g.origin.isZero()) {
        const Eigen::Vector4d x = AtA.ldlt().solve(Atb);
        if (!x.allFinite() || !(x[0] > 0)) break;
        for (int a = 0; a < 3; ++a) {
          if (g.origin[a] == 0) continue;
          const double o = x[a + 1] - x[0] * std::round(x[a + 1] / x[0]);
          g.origin[a] = std::abs(o) < 1e-3 * x[0] ? 0.0 : o;
        }
      }
      double pk = 0, kk = 0;
      for_each_plane([&](int a, double plane, double k) {
        pk += (plane - g.origin[a]) * k;
        kk += k * k;
      });
      if (kk > 0) g.spacing = pk / kk;
    }
    const double r = g.spacing;
    if (edge_length > 0 && r < 0.1 * edge_length) {
      *too_fine = true;
      return std::nullopt;
    }
    if (edge_length > 0 && r > 10 * edge_length) continue;
    if (on_grid(points, r, g.origin)) return g;
  }
  return std::nullopt;
}

}  // namespace

std::optional<ExtractionGrid> extraction_grid(std::span<const Vec3> points, double edge_length) {
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
  AxisPlanes best, all;
  std::vector<double> other_gaps;
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
    for (std::size_t i = 0; i < top; ++i) {
      all[axis].push_back(recurring[i].second);
      if (4 * recurring[i].first >= recurring[0].first) best[axis].push_back(recurring[i].second);
    }
    auto& b = best[axis];
    auto& v = all[axis];
    std::sort(b.begin(), b.end());
    std::sort(v.begin(), v.end());
    for (std::size_t i = 1; i < b.size(); ++i) smallest_gap = std::min(smallest_gap, b[i] - b[i - 1]);
    for (std::size_t i = 1; i < v.size(); ++i) other_gaps.push_back(v[i] - v[i - 1]);
  }
  bool too_fine = false;
  if (std::isfinite(smallest_gap) && smallest_gap > 0) {
    if (auto g = divide_gap(points, best, smallest_gap, edge_length, &too_fine)) return g;
    if (too_fine) return std::nullopt;
  }
  // A grid's points lie on every grid of a divisor of its spacing too: keep the largest spacing that passes.
  std::sort(other_gaps.begin(), other_gaps.end(), std::greater<>());
  other_gaps.erase(std::unique(other_gaps.begin(), other_gaps.end()), other_gaps.end());
  std::optional<ExtractionGrid> found;
  for (const double gap : other_gaps) {
    if (found && gap <= found->spacing) break;
    if (!(gap > 0) || gap == smallest_gap || (edge_length > 0 && gap < 0.1 * edge_length)) continue;
    const auto g = divide_gap(points, all, gap, edge_length, &too_fine);
    if (g && (!found || g->spacing > found->spacing)) found = g;
  }
  return found;
}

}  // namespace topotrack
