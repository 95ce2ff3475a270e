// Global operator new/delete replacements for the whole test binary. Kept in their own file so the
// compiler never inlines them into a caller and sees new paired with free.
#include "tests/engine/schedule/alloc_counter.hpp"

#include <atomic>
#include <cstddef>
#include <cstdlib>
#include <new>

#if defined(__SANITIZE_ADDRESS__)
#define PHACO_COUNT_ALLOCATIONS 0
#else
#define PHACO_COUNT_ALLOCATIONS 1
#endif

namespace {

std::atomic<bool> g_counting{false};
std::atomic<long> g_count{0};

[[maybe_unused]] void* counted_alloc(std::size_t size, std::size_t align) {
  // Relaxed: the test reads the count after joining the frame, which already synchronises.
  if (g_counting.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
  void* p = align > alignof(std::max_align_t)
                ? std::aligned_alloc(align, (size + align - 1) / align * align)
                : std::malloc(size ? size : 1);
  if (!p) throw std::bad_alloc();
  return p;
}

}  // namespace

namespace phaco::test {

bool allocation_counting_available() {
  return PHACO_COUNT_ALLOCATIONS;
}
long allocations_counted() {
  return g_count.load();
}
void start_counting_allocations() {
  g_count = 0;
  g_counting = true;
}
void stop_counting_allocations() {
  g_counting = false;
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
