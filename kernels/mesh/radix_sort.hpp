#pragma once
//! Parallel least-significant-digit radix sort of 64-bit keys, for the big key arrays of ConstrainTopology
//! (the cut's (cell, piece) words: 0.8 M keys at 109k vertices) and of the narrow-band signed distance.
//! Written by hand because nothing in Debian's libraries sorts integers in parallel this way
//! (tbb::parallel_sort compares, Boost's spreadsort is sequential); in place of tbb::parallel_sort it took
//! `constrain_bench --benchmark_filter=BM_IndexCells/300` from 103–123 to 75–98 ms (load 4). The result is
//! the sorted order, so it does not depend on the thread count; the digits are split over fixed chunks.
#include <cstddef>
#include <cstdint>
#include <span>

namespace topotrack {

//! Sort `keys` ascending; `scratch` must hold at least keys.size() elements (its contents are overwritten).
//! Only as many 8–11-bit digits as the largest key needs are sorted, and a digit equal in all keys is
//! skipped. Small inputs use std::sort.
void radix_sort(std::span<std::uint64_t> keys, std::span<std::uint64_t> scratch);

}  // namespace topotrack
