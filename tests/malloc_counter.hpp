#pragma once
/// @file malloc_counter.hpp
/// Allocation counter for no-allocation tests. Include it in exactly ONE translation unit of a test
/// executable: it interposes malloc (glibc exports __libc_malloc), so every heap allocation —
/// operator new, Eigen's aligned_malloc, std containers — is counted while g_counting is set.
#include <atomic>
#include <cstddef>

extern "C" void* __libc_malloc(size_t);
namespace {
std::atomic<bool> g_counting{false};
std::atomic<long> g_allocations{0};
}  // namespace
extern "C" void* malloc(size_t n) {
  if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(n);
}
