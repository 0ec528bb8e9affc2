#include "kernels/mesh/radix_sort.hpp"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <vector>

#include "io/error.hpp"

namespace topotrack {

void radix_sort(std::span<std::uint64_t> keys, std::span<std::uint64_t> scratch) {
  const std::size_t n = keys.size();
  if (scratch.size() < n) TT_THROW(InvalidInput, "radix_sort: scratch holds " << scratch.size() << " of " << n);
  constexpr std::size_t kSmall = 1 << 16;
  if (n < kSmall || n > std::size_t(UINT32_MAX)) {  // 32-bit bucket offsets
    std::sort(keys.begin(), keys.end());
    return;
  }
  constexpr std::size_t kGrain = 1 << 15;
  const std::uint64_t all = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, kGrain), std::uint64_t(0),
      [&](const tbb::blocked_range<std::size_t>& r, std::uint64_t acc) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) acc |= keys[i];
        return acc;
      },
      [](std::uint64_t a, std::uint64_t b) { return a | b; });
  const int bits = std::bit_width(all);
  if (bits == 0) return;
  // At most 11 bits per digit (2048 buckets: the scatter's write streams stay in L1/TLB reach).
  const int passes = (bits + 10) / 11, digit = (bits + passes - 1) / passes;
  const std::size_t buckets = std::size_t(1) << digit;
  const std::uint64_t mask = buckets - 1;
  // Fixed chunks (not one per thread): the same split for any thread count.
  constexpr std::size_t kChunks = 16;
  const std::size_t chunk = (n + kChunks - 1) / kChunks;
  std::vector<std::uint32_t> offset(kChunks * buckets);
  std::uint64_t* src = keys.data();
  std::uint64_t* dst = scratch.data();
  for (int p = 0; p < passes; ++p) {
    const int shift = p * digit;
    tbb::parallel_for(std::size_t(0), kChunks, [&](std::size_t c) {
      std::uint32_t* h = offset.data() + c * buckets;
      std::fill(h, h + buckets, 0u);
      for (std::size_t i = c * chunk, end = std::min(n, (c + 1) * chunk); i < end; ++i) ++h[(src[i] >> shift) & mask];
    });
    // A digit that is the same in every key (e.g. unused high bits of a field) needs no pass.
    bool constant = false;
    for (std::size_t b = 0; b < buckets && !constant; ++b) {
      std::size_t total = 0;
      for (std::size_t c = 0; c < kChunks; ++c) total += offset[c * buckets + b];
      constant = total == n;
      if (total != 0) break;
    }
    if (constant) continue;
    // Exclusive prefix sum, bucket-major then chunk: chunk c's keys of digit b follow chunk c-1's (stable).
    std::uint32_t sum = 0;
    for (std::size_t b = 0; b < buckets; ++b)
      for (std::size_t c = 0; c < kChunks; ++c) {
        const std::uint32_t count = offset[c * buckets + b];
        offset[c * buckets + b] = sum;
        sum += count;
      }
    tbb::parallel_for(std::size_t(0), kChunks, [&](std::size_t c) {
      std::uint32_t* h = offset.data() + c * buckets;
      for (std::size_t i = c * chunk, end = std::min(n, (c + 1) * chunk); i < end; ++i) {
        const std::uint64_t k = src[i];
        dst[h[(k >> shift) & mask]++] = k;
      }
    });
    std::swap(src, dst);
  }
  if (src != keys.data()) std::memcpy(keys.data(), src, n * sizeof(std::uint64_t));
}

}  // namespace topotrack
