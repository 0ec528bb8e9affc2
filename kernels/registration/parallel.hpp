#pragma once
//! Loops over vertices for the registration's per-vertex solvers (fine.cpp, relax.cpp): TBB-parallel, with sums
//! that give the same bits for any thread count.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

#include "kernels/mesh/surface_mesh.hpp"

namespace topotrack {

//! f(i) for i in [0, n), in parallel.
template <class F>
void parallel_each(std::size_t n, F&& f) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 2048), [&](const auto& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) f(i);
  });
}

//! The sum of term(i) over [0, n): fixed chunks summed in parallel, the partials added in chunk order.
template <class F>
Vec3 deterministic_sum(std::size_t n, F&& term) {
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<Vec3> partial(chunks, Vec3::Zero());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const auto& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      Vec3 s = Vec3::Zero();
      const std::size_t end = std::min(n, (c + 1) * kChunk);
      for (std::size_t i = c * kChunk; i < end; ++i) s += term(i);
      partial[c] = s;
    }
  });
  Vec3 total = Vec3::Zero();
  for (const Vec3& p : partial) total += p;
  return total;
}

}  // namespace topotrack
