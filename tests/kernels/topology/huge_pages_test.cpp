// The huge-page allocator of the lattice cut: freed blocks are handed out again, within a bounded cache.
#include "kernels/topology/huge_pages.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <numeric>

namespace topotrack::topology {
namespace {

TEST(HugePages, SmallBlocksAreOrdinary) {
  HugeVector<int> v(1000);
  std::iota(v.begin(), v.end(), 0);
  EXPECT_EQ(v[999], 999);
}

TEST(HugePages, FreedBlockIsReused) {
  constexpr std::size_t n = (std::size_t(3) << 20) / sizeof(std::uint64_t);  // 3 MB: a 4 MB block
  const void* first = nullptr;
  {
    HugeVector<std::uint64_t> a(n);
    first = a.data();
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(first) % (std::uintptr_t(2) << 20), 0u);  // 2 MB aligned
    std::iota(a.begin(), a.end(), std::uint64_t(0));
  }
  EXPECT_GE(huge_page_cached_bytes(), std::size_t(4) << 20);
  HugeVector<std::uint64_t> b;
  b.resize(n - 100);  // rounds to the same 4 MB
  EXPECT_EQ(b.data(), first);
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = i;  // resize leaves elements unwritten: write before reading
  EXPECT_EQ(b[n - 101], n - 101);
  // Growing past the block moves to a bigger one and keeps the contents.
  b.resize(4 * n);
  EXPECT_EQ(b[n - 101], n - 101);
}

TEST(HugePages, CacheIsBounded) {
  {
    std::vector<HugeVector<char>> blocks;
    for (int i = 0; i < 12; ++i) blocks.emplace_back(std::size_t(40) << 20);  // 480 MB of address space
  }
  EXPECT_LE(huge_page_cached_bytes(), kHugeCacheBytes);
  EXPECT_GT(huge_page_cached_bytes(), 0u);
}

}  // namespace
}  // namespace topotrack::topology
