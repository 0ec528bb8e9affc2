#pragma once
//! How a command asks glibc's malloc to treat large blocks: a choice for the whole process, so the command
//! line makes it and the library leaves its embedder's allocator alone (bench/registration mirrors the
//! commands). Neither changes a result, only where memory comes from: on this project's machines (a
//! paravirtualised guest) a page's first touch costs several microseconds, so memory handed back to the
//! system and asked for again is slow, and memory kept is large. Elsewhere than glibc both do nothing.
#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace topotrack::cli {

//! For long runs (`track`). glibc raises its mmap threshold (up to 32 MiB) each time a large block is freed, so
//! that later blocks of a frame's grids, cuts and event lists come from the heap, whose freed pages it keeps:
//! over a run the resident memory grows well past what is live. A fixed threshold (which also stops the
//! raising) gives blocks from 4 MiB on back at once. Resurfaced pcow, capture profile, 40 frames: peak 1 107 ->
//! 974 MB, no slower, output byte-identical (128 KiB saved no more and cost 8 % of the time; docs/results.md,
//! 2026-11-25 evening). The trim threshold and top pad are glibc's defaults, set (and what an earlier policy
//! kept handed back) so that the policy is the same whatever ran before: the benchmarks run several in one process.
inline void keep_large_blocks_unpooled() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 4 << 20);
  mallopt(M_TRIM_THRESHOLD, 128 << 10);
  mallopt(M_TOP_PAD, 128 << 10);
  malloc_trim(0);
#endif
}

//! For one pair (`align`): blocks up to 32 MiB (glibc's largest threshold) from the heap, and the heap's freed
//! memory kept, so the full graph's system, factor and skinning arrays reuse the pages of the low-density
//! pass's instead of faulting in new ones (the elephant at 98k vertices: about 30 000 page faults in
//! align_coarse with glibc's defaults). Peak memory of `topotrack align` on the elephant frames 1 -> 16 (42k
//! vertices): 106 MB either way. Measured in docs/results.md (2026-12-02, "Memory kept for align").
inline void keep_freed_memory() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);  // int: 1 GiB of free memory at the heap's top before any goes back
  mallopt(M_TOP_PAD, 128 << 10);
#endif
}

}  // namespace topotrack::cli
