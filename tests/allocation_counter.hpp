// Counts every operator new of the test binary that includes this header (include it in exactly
// one source file per binary): the hot-path tests check that warm solves and integrations
// allocate nothing per iteration or step.
#pragma once

#include <atomic>
#include <cstdlib>
#include <new>

inline std::atomic<long> g_allocations{0};

// Out of line: inlined, GCC pairs the malloc below with the free of operator delete and warns
// (-Wmismatched-new-delete) at every delete of the including file.
__attribute__((noinline)) void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
__attribute__((noinline)) void operator delete(void* p) noexcept { std::free(p); }
__attribute__((noinline)) void operator delete(void* p, std::size_t) noexcept { std::free(p); }
