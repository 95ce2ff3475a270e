#pragma once
// A 64-bit hash of simulation state, for determinism checks and to tie a figure to a run.
// Hashes bytes, so two states hash equal only if they are bit-identical (−0.0 ≠ +0.0, as wanted:
// a different summation order shows up). Not cryptographic.
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>

namespace phaco {

class StateHash {
 public:
  void add_bytes(const void* data, size_t n) {
    const auto* p = static_cast<const uint8_t*>(data);
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
      uint64_t w;
      std::memcpy(&w, p + i, 8);
      mix(w);
    }
    uint64_t tail = 0;
    if (n > i) std::memcpy(&tail, p + i, n - i);  // an empty span may have a null data()
    mix(tail ^ (uint64_t{n - i} << 56));
    length_ += n;
  }
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void add(std::span<const T> values) { add_bytes(values.data(), values.size_bytes()); }
  template <class T>
  requires std::is_trivially_copyable_v<T>
  void add_value(const T& v) { add_bytes(&v, sizeof(T)); }
  void add_string(std::string_view s) { add_bytes(s.data(), s.size()); }

  uint64_t value() const { return finalize(state_ ^ length_); }
  std::string hex() const;

 private:
  // splitmix64's finaliser: a cheap full-avalanche mix.
  static constexpr uint64_t finalize(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  void mix(uint64_t w) { state_ = finalize(state_ ^ (w + 0x9E3779B97F4A7C15ull)) * 3 + 1; }

  uint64_t state_ = 0x6A09E667F3BCC909ull;
  uint64_t length_ = 0;
};

}  // namespace phaco
