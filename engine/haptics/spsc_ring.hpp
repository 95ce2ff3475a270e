#pragma once
// Bounded single-producer / single-consumer ring (DESIGN.md §5: haptic thread → simulation, the
// device samples; the simulation drains it at the start of its frame). Wait-free on both sides:
// a push into a full ring fails at once and is counted, it never waits for the consumer.
//
//   producer line: head_ (next slot to write)  + tail_cache_ (last tail it saw)  + dropped_
//   consumer line: tail_ (next slot to read)   + head_cache_ (last head it saw)
//
// Indices run on forever (64 bits: no wrap in practice) and are masked into the ring, so "full"
// is head − tail == Capacity and every slot is used. Each side keeps a cached copy of the other's
// index and reloads it only when the cache says full (producer) or empty (consumer), so in the
// common case a push or pop touches no cache line the other thread writes (the idea of rigtorp's
// SPSCQueue, written afresh here).
//
// Storage is inline (std::array), so the ring allocates nothing at all; T should be small plain
// data (a device sample) because it is copied in and out.
#include <array>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "engine/haptics/cache_line.hpp"

namespace phaco {

template <class T, std::size_t Capacity>
class SpscRing {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0,
                "SpscRing capacity must be a power of two");
  static_assert(std::is_nothrow_copy_assignable_v<T>, "push/pop copy T and must not throw");

 public:
  SpscRing() = default;
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  static constexpr std::size_t capacity() { return Capacity; }

  // Producer: false (and the drop counted) when the ring is full.
  bool try_push(const T& value) {
    // Relaxed: head_ is written by this thread only.
    const uint64_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ == Capacity) {
      // Acquire: the consumer's reads of the slot we are about to reuse happened before it
      // advanced tail_ (its release store).
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ == Capacity) {
        // Relaxed: a statistic; only this thread writes it, readers want an approximate count.
        dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
        return false;
      }
    }
    slots_[head & kMask] = value;
    // Release: the slot's contents become visible before the consumer can see the new head.
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  // Consumer: false when the ring is empty.
  bool try_pop(T& out) {
    // Relaxed: tail_ is written by this thread only.
    const uint64_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      // Acquire: pairs with the producer's release of head_, so the slot's contents are visible.
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    assert(head_cache_ - tail <= Capacity && "the producer overran the consumer");
    out = slots_[tail & kMask];
    // Release: our read of the slot is done before the producer may overwrite it.
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  // Consumer: pops everything present now, calling fn(const T&) for each in order; returns how
  // many. For the simulation's drain at the start of its frame.
  template <class Fn>
  std::size_t drain(Fn&& fn) {
    std::size_t n = 0;
    T value;
    while (try_pop(value)) {
      fn(static_cast<const T&>(value));
      ++n;
    }
    return n;
  }

  // Any thread: the number of elements, exact only when both sides are idle.
  std::size_t size_approx() const {
    // Acquire on tail_: what the consumer saw of head_ before storing this tail happens before the
    // head_ load below, so head >= tail (coherence); the clamp guards the arithmetic anyway.
    const uint64_t tail = tail_.load(std::memory_order_acquire);
    // Relaxed: an estimate; no slot contents are read on its strength.
    const uint64_t head = head_.load(std::memory_order_relaxed);
    return head > tail ? static_cast<std::size_t>(head - tail) : 0;
  }

  // Any thread: pushes refused because the ring was full, since construction.
  uint64_t dropped() const {
    // Relaxed: a statistic (see try_push).
    return dropped_.load(std::memory_order_relaxed);
  }

 private:
  static constexpr uint64_t kMask = Capacity - 1;

  // Producer's line.
  alignas(kCacheLine) std::atomic<uint64_t> head_{0};
  uint64_t tail_cache_ = 0;
  std::atomic<uint64_t> dropped_{0};
  // Consumer's line.
  alignas(kCacheLine) std::atomic<uint64_t> tail_{0};
  uint64_t head_cache_ = 0;
  // The slots start on their own line so the first one does not share the consumer's.
  alignas(kCacheLine) std::array<T, Capacity> slots_{};
};

}  // namespace phaco
