#include "kernels/topology/huge_pages.hpp"

#include <sys/mman.h>

#include <algorithm>
#include <mutex>
#include <unordered_map>
#include <vector>

namespace topotrack::topology {
namespace {
constexpr std::size_t kHugePage = std::size_t(2) << 20;
std::size_t rounded(std::size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }

// Freed big blocks kept for the next call (see kHugeCacheBytes), and the capacity of every big block handed
// out (a block from the cache can be larger than asked for).
struct BlockCache {
  std::mutex mutex;
  std::vector<std::pair<std::size_t, void*>> free_blocks;  // (capacity, block)
  std::size_t free_bytes = 0;
  std::unordered_map<void*, std::size_t> capacity;
};
BlockCache& cache() {
  static BlockCache* c = new BlockCache;  // never destroyed: blocks may be freed during static destruction
  return *c;
}
}  // namespace

void* huge_page_alloc(std::size_t bytes) {
  if (bytes < kHugeBlock) return ::operator new(bytes);
  const std::size_t want = rounded(bytes);
  BlockCache& c = cache();
  {
    std::lock_guard<std::mutex> lock(c.mutex);
    // The smallest cached block that fits and wastes at most half of itself.
    auto best = c.free_blocks.end();
    for (auto it = c.free_blocks.begin(); it != c.free_blocks.end(); ++it)
      if (it->first >= want && it->first <= 2 * want && (best == c.free_blocks.end() || it->first < best->first))
        best = it;
    if (best != c.free_blocks.end()) {
      void* p = best->second;
      c.free_bytes -= best->first;
      c.capacity[p] = best->first;
      c.free_blocks.erase(best);
      return p;
    }
  }
  void* p = std::aligned_alloc(kHugePage, want);
  if (!p) throw std::bad_alloc();
  ::madvise(p, want, MADV_HUGEPAGE);  // advice only: a refusal leaves ordinary pages
  std::lock_guard<std::mutex> lock(cache().mutex);
  cache().capacity[p] = want;
  return p;
}

void huge_page_free(void* p, std::size_t bytes) {
  if (bytes < kHugeBlock) {
    ::operator delete(p);
    return;
  }
  BlockCache& c = cache();
  std::vector<void*> release;
  {
    std::lock_guard<std::mutex> lock(c.mutex);
    const auto it = c.capacity.find(p);
    const std::size_t cap = it != c.capacity.end() ? it->second : rounded(bytes);
    if (it != c.capacity.end()) c.capacity.erase(it);
    c.free_blocks.emplace_back(cap, p);
    c.free_bytes += cap;
    // Over the limit: release the largest blocks first (the smaller ones fit more requests).
    while (c.free_bytes > kHugeCacheBytes && !c.free_blocks.empty()) {
      auto largest = std::max_element(c.free_blocks.begin(), c.free_blocks.end());
      c.free_bytes -= largest->first;
      release.push_back(largest->second);
      c.free_blocks.erase(largest);
    }
  }
  for (void* q : release) std::free(q);
}

std::size_t huge_page_cached_bytes() {
  std::lock_guard<std::mutex> lock(cache().mutex);
  return cache().free_bytes;
}

}  // namespace topotrack::topology
