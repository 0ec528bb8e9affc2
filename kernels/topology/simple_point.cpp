#include "kernels/topology/simple_point.hpp"

#include <cstdlib>

namespace topotrack::topology {
namespace {

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
int geodesic_components(const NodeBlock& set, bool corners_allowed, Adjacent adjacent) {
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

}  // namespace

bool simple_node(const NodeBlock& inside) {
  NodeBlock outside;
  for (int a = 0; a < 27; ++a) outside[a] = !inside[a];
  return geodesic_components(inside, false, adjacent6) == 1 &&
         geodesic_components(outside, true, adjacent18) == 1;
}

}  // namespace topotrack::topology
