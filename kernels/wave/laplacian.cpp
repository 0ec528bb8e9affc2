#include "kernels/wave/laplacian.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

#include "io/error.hpp"

namespace topotrack {

namespace {

constexpr double kMaxCot = 57.29;     // cot(1 degree)
constexpr double kMassFloor = 0.05;   // times the mean vertex mass

void check_soup(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles, const char* who) {
  for (std::size_t i = 0; i < positions.size(); ++i)
    if (!positions[i].allFinite()) TT_THROW(InvalidInput, who << ": vertex " << i << " is not finite");
  for (std::size_t f = 0; f < triangles.size(); ++f)
    for (Index v : triangles[f])
      if (v >= positions.size())
        TT_THROW(InvalidInput, who << ": triangle " << f << " has vertex index " << v << " >= " << positions.size());
}

// cot of the angle between a and b (0 for a degenerate corner; callers skip degenerate triangles).
double cot(const Vec3& a, const Vec3& b) {
  const double sn = a.cross(b).norm();
  return sn > 0 ? a.dot(b) / sn : 0.0;
}

}  // namespace

CotanLaplacian cotan_laplacian(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles) {
  check_soup(positions, triangles, "cotan_laplacian");
  const std::size_t n = positions.size();
  // Half-weights per directed corner pair: (i, j, 0.5 cot of the angle opposite edge ij).
  struct Entry {
    Index i, j;
    double w;
  };
  std::vector<Entry> entries;
  entries.reserve(6 * triangles.size());
  CotanLaplacian L;
  L.mass.assign(n, 0.0);
  for (const auto& t : triangles) {
    const Vec3& p0 = positions[t[0]];
    const Vec3& p1 = positions[t[1]];
    const Vec3& p2 = positions[t[2]];
    const double area = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    const double longest = std::max({(p1 - p0).squaredNorm(), (p2 - p1).squaredNorm(), (p0 - p2).squaredNorm()});
    if (!(area > 1e-12 * longest)) continue;  // a needle or a cap: no stiffness, no mass
    double c[3];
    double worst = 0;
    for (int k = 0; k < 3; ++k) {
      const Index a = t[k], b = t[(k + 1) % 3], o = t[(k + 2) % 3];
      c[k] = cot(positions[a] - positions[o], positions[b] - positions[o]);
      worst = std::max(worst, std::abs(c[k]));
    }
    // Slivers: scale the whole element (which keeps it positive semi-definite, unlike clamping one cot).
    const double scale = worst > kMaxCot ? kMaxCot / worst : 1.0;
    for (int k = 0; k < 3; ++k) {
      const Index a = t[k], b = t[(k + 1) % 3];
      const double w = 0.5 * scale * c[k];
      entries.push_back({a, b, w});
      entries.push_back({b, a, w});
      L.mass[t[k]] += area / 3;
    }
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry& x, const Entry& y) { return x.i != y.i ? x.i < y.i : x.j < y.j; });
  L.row_begin.assign(n + 1, 0);
  L.diagonal.assign(n, 0.0);
  for (std::size_t k = 0; k < entries.size();) {
    std::size_t e = k;
    double w = 0;
    while (e < entries.size() && entries[e].i == entries[k].i && entries[e].j == entries[k].j) w += entries[e++].w;
    L.col.push_back(entries[k].j);
    L.weight.push_back(w);
    L.diagonal[entries[k].i] += w;
    ++L.row_begin[entries[k].i + 1];
    k = e;
  }
  for (std::size_t i = 0; i < n; ++i) L.row_begin[i + 1] += L.row_begin[i];
  double total = 0;
  for (double m : L.mass) total += m;
  const double floor = n ? kMassFloor * std::max(total / n, 1e-300) : 0;
  for (double& m : L.mass) m = std::max(m, floor);
  return L;
}

void CotanLaplacian::apply(std::span<const double> h, std::span<double> out) const {
  const std::size_t n = size();
  if (h.size() != n || out.size() != n)
    TT_THROW(InvalidInput, "CotanLaplacian::apply: sizes " << h.size() << ", " << out.size() << " for " << n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 2048), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      double s = diagonal[i] * h[i];
      for (std::size_t k = row_begin[i]; k < row_begin[i + 1]; ++k) s -= weight[k] * h[col[k]];
      out[i] = s;
    }
  });
}

double CotanLaplacian::dirichlet(std::span<const double> h) const {
  std::vector<double> ch(size());
  apply(h, ch);
  double s = 0;
  for (std::size_t i = 0; i < ch.size(); ++i) s += h[i] * ch[i];
  return s;
}

double CotanLaplacian::max_eigenvalue_bound() const {
  double best = 0;
  for (std::size_t i = 0; i < size(); ++i) {
    double r = std::abs(diagonal[i]);
    for (std::size_t k = row_begin[i]; k < row_begin[i + 1]; ++k) r += std::abs(weight[k]);
    best = std::max(best, r / mass[i]);
  }
  return best;
}

std::vector<Vec3> soup_vertex_normals(std::span<const Vec3> positions, std::span<const std::array<Index, 3>> triangles) {
  check_soup(positions, triangles, "soup_vertex_normals");
  std::vector<Vec3> n(positions.size(), Vec3::Zero());
  for (const auto& t : triangles) {
    const Vec3 a = (positions[t[1]] - positions[t[0]]).cross(positions[t[2]] - positions[t[0]]);
    for (Index v : t) n[v] += a;
  }
  for (Vec3& v : n) {
    const double len = v.norm();
    v = len > 0 ? Vec3(v / len) : Vec3::Zero();
  }
  return n;
}

std::vector<Vec3> displace_along_normals(std::span<const Vec3> positions,
                                         std::span<const std::array<Index, 3>> triangles,
                                         std::span<const double> heights, double scale) {
  if (heights.size() != positions.size())
    TT_THROW(InvalidInput, "displace_along_normals: " << heights.size() << " heights for " << positions.size()
                                                      << " vertices");
  const std::vector<Vec3> n = soup_vertex_normals(positions, triangles);
  std::vector<Vec3> out(positions.begin(), positions.end());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] += scale * heights[i] * n[i];
  return out;
}

}  // namespace topotrack
