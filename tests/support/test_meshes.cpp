#include "tests/support/test_meshes.hpp"

#include <cmath>
#include <map>
#include <random>

namespace topotrack::test {

Soup tetrahedron() {
  Soup s;
  s.positions = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  s.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  return s;
}

Soup icosphere(int subdivisions, double radius, const Vec3& center) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  Soup s;
  s.positions = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : s.positions) p.normalize();
  s.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int it = 0; it < subdivisions; ++it) {
    std::map<std::pair<Index, Index>, Index> mid;
    auto midpoint = [&](Index a, Index b) {
      const auto key = std::minmax(a, b);
      auto [pos, inserted] = mid.try_emplace(key, Index(s.positions.size()));
      if (inserted) s.positions.push_back((s.positions[a] + s.positions[b]).normalized());
      return pos->second;
    };
    std::vector<std::array<Index, 3>> out;
    for (const auto& tri : s.triangles) {
      const Index a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      out.push_back({tri[0], a, c});
      out.push_back({tri[1], b, a});
      out.push_back({tri[2], c, b});
      out.push_back({a, b, c});
    }
    s.triangles.swap(out);
  }
  for (auto& p : s.positions) p = center + radius * p;
  return s;
}

Soup torus(int n, int m, double R, double r) {
  Soup s;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      const double u = 2 * M_PI * i / n, v = 2 * M_PI * j / m;
      s.positions.emplace_back((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  auto id = [&](int i, int j) { return Index(((i + n) % n) * m + (j + m) % m); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < m; ++j) {
      s.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      s.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return s;
}

Soup open_box() {
  Soup s;
  s.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  s.triangles = {{0, 2, 1}, {0, 3, 2}, {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5},
                 {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};  // top (4 5 6 7) missing
  return s;
}

Soup merge(const Soup& a, const Soup& b) {
  Soup s = a;
  const Index off = Index(a.positions.size());
  s.positions.insert(s.positions.end(), b.positions.begin(), b.positions.end());
  for (auto t : b.triangles) s.triangles.push_back({t[0] + off, t[1] + off, t[2] + off});
  return s;
}

void jitter(Soup& s, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto& p : s.positions) {
    Vec3 d(u(rng), u(rng), u(rng));
    if (d.norm() > 1) d.normalize();
    p += amplitude * d;
  }
}

}  // namespace topotrack::test
