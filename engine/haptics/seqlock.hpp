#pragma once
// A seqlock for one writer thread and one reader thread (issue 6 item 4: the UDP bridge's I/O
// thread and the 1 kHz haptic thread). Thread-safety: store() from the one writer, load() and
// version() from the one reader, concurrently; neither waits nor allocates.
#include <array>
#include <atomic>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace phaco {

// Single writer, single reader, the value copied through atomic words so that a torn read is a
// detected retry rather than a data race (and ThreadSanitizer agrees). The reader never waits: it
// tries a few times and otherwise keeps what it had; the writer holds the odd count for ~20 ns.
template <typename T>
class Seqlock {
  static_assert(std::is_trivially_copyable_v<T>);
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;

 public:
  // Thread: the one writer.
  void store(const T& v) noexcept {
    uint64_t w[kWords] = {};
    std::memcpy(w, &v, sizeof(T));
    // Relaxed: this thread is the only writer of seq_.
    const uint32_t s = seq_.load(std::memory_order_relaxed);
    // Even between stores; odd here means a second writer is inside store() (one writer only).
    assert((s & 1u) == 0 && "Seqlock::store from two threads");
    seq_.store(s + 1, std::memory_order_relaxed);
    // Release fence: the odd count is visible before any new word is.
    std::atomic_thread_fence(std::memory_order_release);
    // Relaxed: ordered by the fence above and the release store below.
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(w[i], std::memory_order_relaxed);
    // Release: the words are visible before the even count that vouches for them.
    seq_.store(s + 2, std::memory_order_release);
  }

  // False when never written or when every try met a write. Thread: the one reader.
  bool load(T& out) const noexcept {
    for (int attempt = 0; attempt < 4; ++attempt) {
      // Acquire: pairs with the writer's final release store; the words read below are at least
      // as new as this count.
      const uint32_t s0 = seq_.load(std::memory_order_acquire);
      if (s0 == 0) return false;  // never written
      if (s0 & 1u) continue;      // a write in progress
      uint64_t w[kWords];
      // Relaxed: validated by the count re-check below.
      for (std::size_t i = 0; i < kWords; ++i) w[i] = words_[i].load(std::memory_order_relaxed);
      // Acquire fence: the word loads complete before the re-check (pairs with the writer's
      // release fence).
      std::atomic_thread_fence(std::memory_order_acquire);
      // Relaxed: ordered by the fence above.
      if (seq_.load(std::memory_order_relaxed) == s0) {
        std::memcpy(&out, w, sizeof(T));
        return true;
      }
    }
    return false;
  }

  // Changes on every store. Thread: any (one atomic load). Acquire: a reader that sees a new
  // version then loads the new value.
  uint32_t version() const noexcept { return seq_.load(std::memory_order_acquire); }

 private:
  std::atomic<uint32_t> seq_{0};
  std::array<std::atomic<uint64_t>, kWords> words_{};
};

}  // namespace phaco
