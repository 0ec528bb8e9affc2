// Tests of the parallel radix sort (kernels/mesh/radix_sort.hpp).
#include "kernels/mesh/radix_sort.hpp"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <random>
#include <vector>

#include "io/error.hpp"

namespace topotrack {
namespace {

std::vector<std::uint64_t> sorted_copy(std::vector<std::uint64_t> v) {
  std::vector<std::uint64_t> scratch(v.size());
  radix_sort(v, scratch);
  return v;
}

// Keys shaped like ConstrainTopology's: packed fields with unused bits between them, duplicates, the full
// 64-bit range, sizes on both sides of the small-input cut-off and not multiples of the chunk count.
TEST(RadixSort, SortsLikeStdSort) {
  std::mt19937_64 rng(7);
  for (std::size_t n : {0u, 1u, 5u, 1000u, 65535u, 65536u, 100003u, 400001u}) {
    for (int shape = 0; shape < 4; ++shape) {
      std::vector<std::uint64_t> v(n);
      for (std::size_t i = 0; i < n; ++i) {
        const std::uint64_t r = rng();
        switch (shape) {
          case 0: v[i] = r; break;                                    // all 64 bits
          case 1: v[i] = (r % 300) << 42 | (r >> 20) % 300 << 21 | i; break;  // cell fields, an index
          case 2: v[i] = r % 17; break;                               // many duplicates, one digit
          default: v[i] = (r % 5) << 60; break;                       // only the top digit varies
        }
      }
      std::vector<std::uint64_t> expected = v;
      std::sort(expected.begin(), expected.end());
      SCOPED_TRACE("n " + std::to_string(n) + " shape " + std::to_string(shape));
      EXPECT_TRUE(sorted_copy(v) == expected);
    }
  }
}

TEST(RadixSort, SameWithOneThreadOrMany) {
  std::mt19937_64 rng(11);
  std::vector<std::uint64_t> v(300000);
  for (auto& x : v) x = rng() >> 7;
  std::vector<std::uint64_t> one, many;
  {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
    one = sorted_copy(v);
  }
  {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 4);
    many = sorted_copy(v);
  }
  EXPECT_TRUE(one == many);
  EXPECT_TRUE(std::is_sorted(one.begin(), one.end()));
}

TEST(RadixSort, RejectsAShortScratch) {
  std::vector<std::uint64_t> v(10, 1), scratch(9);
  EXPECT_THROW(radix_sort(v, scratch), InvalidInput);
}

}  // namespace
}  // namespace topotrack
