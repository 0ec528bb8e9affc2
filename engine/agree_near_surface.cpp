#include "engine/agree_near_surface.hpp"

#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace topotrack {
namespace {

// The 3×3×3 neighbourhood of a lattice node, index (dx+1) + 3(dy+1) + 9(dz+1); 13 is the node itself.
using Block = std::array<bool, 27>;
constexpr int kCentre = 13;

int taxicab(int a, int b) {
  return std::abs(a % 3 - b % 3) + std::abs(a / 3 % 3 - b / 3 % 3) + std::abs(a / 9 - b / 9);
}
bool cube_corner(int a) { return taxicab(a, kCentre) == 3; }
bool adjacent6(int a, int b) { return taxicab(a, b) == 1; }
bool adjacent18(int a, int b) {
  const bool near =
      std::abs(a % 3 - b % 3) <= 1 && std::abs(a / 3 % 3 - b / 3 % 3) <= 1 && std::abs(a / 9 - b / 9) <= 1;
  const int d = taxicab(a, b);
  return near && d >= 1 && d <= 2;
}

//! Number of components (`adjacent` connectivity) of the geodesic neighbourhood: the nodes of `set`
//! within `reach` (N18* or N26*) that are seeds (adjacent to the centre) or adjacent to a seed.
template <class Adjacent>
int geodesic_components(const Block& set, bool corners_allowed, Adjacent adjacent) {
  std::array<bool, 27> in{};
  for (int a = 0; a < 27; ++a)
    in[a] = a != kCentre && set[a] && (corners_allowed || !cube_corner(a)) && adjacent(a, kCentre);
  std::array<bool, 27> member = in;  // the seeds, then their neighbours within reach
  for (int a = 0; a < 27; ++a) {
    if (a == kCentre || !set[a] || member[a] || (!corners_allowed && cube_corner(a))) continue;
    for (int b = 0; b < 27 && !member[a]; ++b) member[a] = in[b] && adjacent(a, b);
  }
  std::array<bool, 27> seen{};
  int components = 0;
  for (int s = 0; s < 27; ++s) {
    if (!member[s] || seen[s]) continue;
    ++components;
    std::array<int, 27> stack{};
    int top = 0;
    stack[top++] = s;
    seen[s] = true;
    while (top > 0) {
      const int a = stack[--top];
      for (int b = 0; b < 27; ++b)
        if (member[b] && !seen[b] && adjacent(a, b)) {
          seen[b] = true;
          stack[top++] = b;
        }
    }
  }
  return components;
}

//! Whether changing the sign of the centre leaves the topology of the inside (6-connected) and the outside
//! (18-connected) unchanged: the (6, 18) pair is the connectivity of the project's marching cubes, which
//! separates inside corners on an ambiguous face (kernels/sdf/cube_table.hpp). Bertrand and Malandain's
//! characterisation: one 6-component of the inside's geodesic neighbourhood and one 18-component of the
//! outside's.
bool simple_node(const Block& inside) {
  Block outside;
  for (int a = 0; a < 27; ++a) outside[a] = !inside[a];
  return geodesic_components(inside, false, adjacent6) == 1 &&
         geodesic_components(outside, true, adjacent18) == 1;
}

struct Flip {
  openvdb::Coord coord;
  float value;
};

}  // namespace

void agree_near_surface(openvdb::FloatGrid& phi_s, const openvdb::FloatGrid& phi_m, double tolerance, int sweeps) {
  using Leaf = openvdb::FloatTree::LeafNodeType;
  const float tol = float(tolerance);
  openvdb::tree::LeafManager<openvdb::FloatTree> leaves(phi_s.tree());
  // The candidates, per leaf node in parallel, grouped by the parity of their coordinates: nodes of one
  // parity class are two apart, outside each other's 3×3×3 neighbourhoods, so a class is decided in
  // parallel and the classes one after the other give a fixed sequential order.
  std::vector<std::array<std::vector<Flip>, 8>> found(leaves.leafCount());
  leaves.foreach ([&](const Leaf& leaf, std::size_t n) {
    auto acc_m = phi_m.getConstAccessor();
    for (auto it = leaf.cbeginValueOn(); it; ++it) {
      const float s = *it;
      if (std::abs(s) >= tol) continue;
      const openvdb::Coord c = it.getCoord();
      const float m = acc_m.getValue(c);
      if (std::abs(m) >= tol || (s < 0) == (m < 0)) continue;
      found[n][(c.x() & 1) | (c.y() & 1) << 1 | (c.z() & 1) << 2].push_back({c, m});
    }
  });
  std::array<std::vector<Flip>, 8> classes;
  for (int parity = 0; parity < 8; ++parity)
    for (const auto& per_leaf : found)
      classes[parity].insert(classes[parity].end(), per_leaf[parity].begin(), per_leaf[parity].end());
  const openvdb::FloatGrid& s_grid = phi_s;
  bool flipped = true;
  for (int pass = 0; flipped && (sweeps <= 0 || pass < sweeps); ++pass) {
    flipped = false;
    for (std::vector<Flip>& candidates : classes) {
      std::vector<std::uint8_t> take(candidates.size(), 0);
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size(), 256), [&](const auto& r) {
        auto acc = s_grid.getConstAccessor();
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          Block inside;
          for (int a = 0; a < 27; ++a)
            inside[a] = acc.getValue(candidates[i].coord.offsetBy(a % 3 - 1, a / 3 % 3 - 1, a / 9 - 1)) < 0;
          take[i] = simple_node(inside);
        }
      });
      auto acc = phi_s.getAccessor();
      std::size_t kept = 0;
      for (std::size_t i = 0; i < candidates.size(); ++i) {
        if (take[i]) acc.setValueOnly(candidates[i].coord, candidates[i].value);
        else candidates[kept++] = candidates[i];
      }
      flipped = flipped || kept < candidates.size();
      candidates.resize(kept);
    }
  }
}

}  // namespace topotrack
