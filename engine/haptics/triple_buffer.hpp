#pragma once
// Triple buffer: wait-free handoff of the newest value from one producer thread to one consumer
// thread (DESIGN.md §5: simulation → haptic thread, the haptic model; seed 003 §III.C–D: the
// 1 kHz force loop must never wait for the slower mesh update).
//
//   producer owns `write_`          consumer owns `read_`
//          │ publish(): exchange           │ acquire(): exchange (only when fresh)
//          ▼                               ▼
//        ┌──────── middle_ = index | fresh bit (one atomic byte) ────────┐
//
// Three slots: the producer fills its slot in place, then swaps it with the middle one in one
// atomic exchange and marks it fresh; the consumer, when the middle is fresh, swaps its slot with
// the middle one. Neither side ever waits, loops or copies a T (T may be ~62 KiB, such as
// phaco::HapticModel); if the producer publishes twice before the consumer looks, the older one is
// simply overwritten (newest wins). The write slot holds stale data from an earlier publish: the
// producer must write every field it relies on.
//
// Reads/writes: only the slots and the three indices below. Allocation: the three slots, in the
// constructor only.
#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "engine/haptics/cache_line.hpp"

namespace phaco {

template <class T>
class TripleBuffer {
 public:
  // The three slots are value-initialised T (T{}: zeros for plain numbers), allocated here once.
  TripleBuffer() : slots_(new Slot[3]()) {}
  TripleBuffer(const TripleBuffer&) = delete;
  TripleBuffer& operator=(const TripleBuffer&) = delete;

  // Producer: the slot to fill (in place) before publish().
  T& write_slot() { return slots_[write_].value; }

  // Producer: makes the write slot the newest and takes the old middle slot as the next one to
  // fill. One atomic exchange: wait-free.
  void publish() {
    // acq_rel: release makes this slot's contents visible to the consumer that acquires it;
    // acquire makes the consumer's last reads of the slot we get back happen before we overwrite
    // it.
    const uint8_t old =
        middle_.exchange(static_cast<uint8_t>(write_ | kFresh), std::memory_order_acq_rel);
    write_ = old & kIndexMask;
    // The three indices are always a permutation of 0, 1, 2 (each side owns one slot); the
    // producer may check its own against the consumer's only in a test, so here: in range.
    assert(write_ < 3);
  }

  // Consumer: takes the newest slot if one was published since the last acquire. Returns true
  // when read_slot() now refers to a different (newer) value.
  bool acquire() {
    // Relaxed: only a hint; if it misses a publish that just happened, the next tick sees it. The
    // exchange below is what orders the slot's contents.
    if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return false;
    // acq_rel: acquire sees the producer's writes to the slot it published; release hands our old
    // slot back only after our reads of it are done. Only the consumer clears kFresh, so the
    // middle is still fresh here (the producer may have swapped in an even newer slot: fine).
    const uint8_t old = middle_.exchange(read_, std::memory_order_acq_rel);
    assert((old & kFresh) && "only the consumer clears the fresh bit");
    read_ = old & kIndexMask;
    assert(read_ < 3);
    return true;
  }

  // Consumer: the slot it holds (default T until the first successful acquire).
  const T& read_slot() const { return slots_[read_].value; }

 private:
  static constexpr uint8_t kIndexMask = 0x3;
  static constexpr uint8_t kFresh = 0x4;  // the middle slot was published and not yet taken

  // Each slot on its own cache lines, so the producer writing one never invalidates the line the
  // consumer is reading from another.
  struct alignas(kCacheLine) Slot {
    T value;
  };

  std::unique_ptr<Slot[]> slots_;
  // Each index on its own line: write_ is touched by the producer only, read_ by the consumer only,
  // middle_ by both.
  alignas(kCacheLine) uint8_t write_ = 0;
  alignas(kCacheLine) std::atomic<uint8_t> middle_{1};
  alignas(kCacheLine) uint8_t read_ = 2;

  static_assert(std::atomic<uint8_t>::is_always_lock_free);
};

}  // namespace phaco
