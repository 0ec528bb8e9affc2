#include "kernels/topology/huge_pages.hpp"

#include <sys/mman.h>

namespace topotrack::topology {
namespace {
constexpr std::size_t kHugePage = std::size_t(2) << 20;
std::size_t rounded(std::size_t bytes) { return (bytes + kHugePage - 1) / kHugePage * kHugePage; }
}  // namespace

void* huge_page_alloc(std::size_t bytes) {
  if (bytes < kHugeBlock) return ::operator new(bytes);
  void* p = std::aligned_alloc(kHugePage, rounded(bytes));
  if (!p) throw std::bad_alloc();
  ::madvise(p, rounded(bytes), MADV_HUGEPAGE);  // advice only: a refusal leaves ordinary pages
  return p;
}

void huge_page_free(void* p, std::size_t bytes) {
  if (bytes < kHugeBlock) ::operator delete(p);
  else std::free(p);
}

}  // namespace topotrack::topology
