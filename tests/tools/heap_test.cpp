// tools/heap.hpp: each command's malloc policy takes effect whatever was set before (the benchmarks run
// several in one process): with track's, an 8 MiB block is mapped on its own and goes back when freed; with
// align's, it comes from the heap and its pages stay for the next block.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "tools/heap.hpp"

namespace topotrack::cli {
namespace {

#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)  // (AddressSanitizer has its own allocator)
constexpr std::size_t kBlock = std::size_t(8) << 20;
void* volatile escape = nullptr;  // so that the compiler keeps each malloc and free

void release(void* p) {
  escape = p;
  std::free(escape);
}

void* touched_block() {
  void* p = std::malloc(kBlock);
  EXPECT_NE(p, nullptr);
  if (p) std::memset(p, 1, kBlock);
  escape = p;
  return escape;
}

TEST(Heap, TrackMapsLargeBlocksAndAlignKeepsThem) {
  for (int round = 0; round < 2; ++round) {  // each policy after the other, twice
    keep_large_blocks_unpooled();
    const std::size_t mapped = mallinfo2().hblks;
    void* p = touched_block();
    EXPECT_EQ(mallinfo2().hblks, mapped + 1) << "track: a block of 8 MiB is mapped on its own";
    release(p);
    EXPECT_EQ(mallinfo2().hblks, mapped) << "track: and unmapped when freed";

    keep_freed_memory();
    const std::size_t mapped_before = mallinfo2().hblks;
    p = touched_block();
    EXPECT_EQ(mallinfo2().hblks, mapped_before) << "align: a block of 8 MiB comes from the heap";
    release(p);
    EXPECT_GE(mallinfo2().fordblks, kBlock) << "align: its memory stays in the heap when freed";
    void* q = touched_block();
    EXPECT_EQ(mallinfo2().hblks, mapped_before);
    release(q);
  }
}
#else
TEST(Heap, TrackMapsLargeBlocksAndAlignKeepsThem) { GTEST_SKIP() << "not glibc's malloc: the policies do nothing"; }
#endif

}  // namespace
}  // namespace topotrack::cli
