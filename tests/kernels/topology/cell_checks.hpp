#pragma once
// Checks on single cells of ConstrainTopology's lattice (§4.3), shared by the topology tests.
#include <algorithm>
#include <utility>
#include <vector>

#include "kernels/topology/classify.hpp"
#include "kernels/topology/lattice_cut.hpp"

namespace topotrack {

// Whether M crosses one of the twelve edges of `cell` more than once (Wojtan et al.'s edge test: a fold or a
// near-tangency that no marching-cubes polygon can represent).
inline bool has_multiply_crossed_edge(const topology::LatticeCut& cut, const topology::CellIndex& index, std::uint64_t cell) {
  using namespace topology;
  const openvdb::Coord C = cell_from_key(cell);
  std::vector<std::pair<int, Index>> crossings;  // (cube edge, face)
  const auto [pb, pe] = index.pieces_of(cell);
  for (std::uint32_t k = pb; k < pe; ++k) {
    const Piece& pc = cut.pieces[index.piece_order[k]];
    for (int i = 0; i < pc.size; ++i) {
      const PointKey& key = cut.keys[pc.begin + i];
      if (kind(key) != PointKind::FacePoint) continue;
      const int L = key_axis(key), ua = L == 0 ? 1 : 0, va = L == 2 ? 1 : 2;
      crossings.emplace_back(4 * L + (key_plane_u(key) - C[ua]) + 2 * (key_plane_v(key) - C[va]), key_element(key));
    }
  }
  std::sort(crossings.begin(), crossings.end());
  crossings.erase(std::unique(crossings.begin(), crossings.end()), crossings.end());
  for (std::size_t i = 1; i < crossings.size(); ++i)
    if (crossings[i].first == crossings[i - 1].first) return true;
  return false;
}

}  // namespace topotrack
