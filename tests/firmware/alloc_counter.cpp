// Counting allocation hooks for the no-heap-after-start-up test: replaces the
// global operator new/delete and malloc/calloc/realloc for this test binary.
#include "alloc_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define UWBNAV_ALLOC_HOOKS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define UWBNAV_ALLOC_HOOKS 0
#endif
#endif
#ifndef UWBNAV_ALLOC_HOOKS
#define UWBNAV_ALLOC_HOOKS 1
#endif

namespace {
std::atomic<bool> g_armed{false};
std::atomic<unsigned long> g_count{0};
inline void note() {
  if (g_armed.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
}
}  // namespace

namespace alloc_counter {
bool hooks_active() { return UWBNAV_ALLOC_HOOKS != 0; }
void arm() {
  g_count = 0;
  g_armed = true;
}
unsigned long disarm() {
  g_armed = false;
  return g_count.load();
}
}  // namespace alloc_counter

#if UWBNAV_ALLOC_HOOKS
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void __libc_free(void*);

void* malloc(size_t n) {
  note();
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t m) {
  note();
  return __libc_calloc(n, m);
}
void* realloc(void* p, size_t n) {
  note();
  return __libc_realloc(p, n);
}
void free(void* p) { __libc_free(p); }
}

void* operator new(size_t n) {
  note();
  void* p = __libc_malloc(n ? n : 1);
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
void* operator new[](size_t n) { return operator new(n); }
void* operator new(size_t n, const std::nothrow_t&) noexcept {
  note();
  return __libc_malloc(n ? n : 1);
}
void* operator new[](size_t n, const std::nothrow_t&) noexcept { return operator new(n, std::nothrow); }
void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, size_t) noexcept { __libc_free(p); }
#endif
