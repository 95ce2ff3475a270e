// Global operator new/delete replacements for the whole test binary, counting only allocations
// made on threads that marked themselves (see alloc_counter.hpp). Kept in their own file so the
// compiler never inlines them into a caller and sees new paired with free (the pattern of
// tests/engine/schedule/alloc_counter.cpp).
#include "tests/engine/haptics/alloc_counter.hpp"

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define PHACO_COUNT_ALLOCATIONS 0
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define PHACO_COUNT_ALLOCATIONS 0
#endif
#endif
#ifndef PHACO_COUNT_ALLOCATIONS
#define PHACO_COUNT_ALLOCATIONS 1
#endif

namespace {

// constinit thread_local of a trivial type: no TLS initialisation call, so reading it from
// operator new cannot itself allocate or recurse.
constinit thread_local bool t_marked = false;
std::atomic<bool> g_window{false};
std::atomic<long> g_count{0};

[[maybe_unused]] void* counted_alloc(std::size_t size, std::size_t align) {
  // Relaxed: the test reads the count after stopping the loop (a join), which synchronises.
  if (t_marked && g_window.load(std::memory_order_relaxed))
    g_count.fetch_add(1, std::memory_order_relaxed);
  void* p = align > alignof(std::max_align_t)
                ? std::aligned_alloc(align, (size + align - 1) / align * align)
                : std::malloc(size ? size : 1);
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace

namespace phaco::test {

bool haptic_allocation_counting_available() {
  return PHACO_COUNT_ALLOCATIONS;
}
void count_allocations_on_this_thread(bool on) {
  t_marked = on;
}
void open_allocation_window() {
  g_count = 0;
  g_window = true;
}
void close_allocation_window() {
  g_window = false;
}
long allocations_on_marked_threads() {
  return g_count.load();
}

}  // namespace phaco::test

#if PHACO_COUNT_ALLOCATIONS
void* operator new(std::size_t size) {
  return counted_alloc(size, 0);
}
void* operator new[](std::size_t size) {
  return counted_alloc(size, 0);
}
void* operator new(std::size_t size, std::align_val_t a) {
  return counted_alloc(size, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t size, std::align_val_t a) {
  return counted_alloc(size, static_cast<std::size_t>(a));
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(size, 0);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted_alloc(size, 0);
  } catch (...) {
    return nullptr;
  }
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
#endif
