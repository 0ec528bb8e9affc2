#pragma once
//! A std::vector allocator for the lattice cut's big flat arrays (tens of MB per call, fresh each call):
//! blocks of kHugeBlock bytes or more are 2 MB-aligned and advised as transparent huge pages
//! (madvise(MADV_HUGEPAGE); the system's setting is "madvise"), so that first touching them costs one page
//! fault per 2 MB instead of one per 4 KB. Measured on the cut of a 109k-vertex mesh: page faults were a
//! third of its time. Smaller blocks use operator new. Elements added by resize() are left unwritten.
//! Freed blocks are kept (up to kHugeCacheBytes, process-wide, thread-safe) and handed out again: the tracker
//! cuts a mesh of the same size twice a frame, and fresh pages cost a fault and zeroing each time.
#include <cstddef>
#include <cstdlib>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace topotrack::topology {

void* huge_page_alloc(std::size_t bytes);
void huge_page_free(void* p, std::size_t bytes);
//! Bytes of freed blocks kept for reuse (at most kHugeCacheBytes).
std::size_t huge_page_cached_bytes();
inline constexpr std::size_t kHugeBlock = std::size_t(1) << 20;
//! Freed blocks kept for reuse, at most this many bytes (beyond it the largest are returned to the system).
inline constexpr std::size_t kHugeCacheBytes = std::size_t(256) << 20;

template <class T>
struct HugePageAllocator {
  using value_type = T;
  HugePageAllocator() = default;
  template <class U>
  HugePageAllocator(const HugePageAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(huge_page_alloc(n * sizeof(T))); }
  void deallocate(T* p, std::size_t n) { huge_page_free(p, n * sizeof(T)); }
  //! resize() leaves new elements unwritten (the cut overwrites every one; zeroing 60 MB first cost as much
  //! as copying into it). Only for implicit-lifetime element types.
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    static_assert(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>);
    if constexpr (sizeof...(Args) > 0) ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
  template <class U>
  bool operator==(const HugePageAllocator<U>&) const { return true; }
};

template <class T>
using HugeVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace topotrack::topology
