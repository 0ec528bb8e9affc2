#include "engine/agree_near_surface.hpp"

#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include <array>
#include <cmath>
#include <vector>

#include "kernels/topology/simple_point.hpp"

namespace topotrack {
namespace {

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
          topology::NodeBlock inside;
          for (int a = 0; a < 27; ++a)
            inside[a] = acc.getValue(candidates[i].coord.offsetBy(a % 3 - 1, a / 3 % 3 - 1, a / 9 - 1)) < 0;
          take[i] = topology::simple_node(inside);
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
