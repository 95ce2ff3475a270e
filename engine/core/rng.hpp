#pragma once
// Counter-based random numbers: Philox4x32-10 (Salmon et al., "Parallel random numbers: as easy
// as 1, 2, 3", SC 2011). A draw is a pure function of (seed, stream, frame, element, draw), so a
// parallel system gets the same numbers whichever thread handles an element, and a replay of a
// run gets the same numbers as the run.
#include <array>
#include <cstdint>

namespace phaco {

using PhiloxCounter = std::array<uint32_t, 4>;
using PhiloxKey = std::array<uint32_t, 2>;

constexpr PhiloxCounter philox4x32_10(PhiloxCounter ctr, PhiloxKey key) {
  constexpr uint32_t kM0 = 0xD2511F53u, kM1 = 0xCD9E8D57u;
  constexpr uint32_t kW0 = 0x9E3779B9u, kW1 = 0xBB67AE85u;
  for (int round = 0; round < 10; ++round) {
    if (round > 0) {
      key[0] += kW0;
      key[1] += kW1;
    }
    const uint64_t p0 = uint64_t{kM0} * ctr[0];
    const uint64_t p1 = uint64_t{kM1} * ctr[2];
    ctr = {static_cast<uint32_t>(p1 >> 32) ^ ctr[1] ^ key[0], static_cast<uint32_t>(p1),
           static_cast<uint32_t>(p0 >> 32) ^ ctr[3] ^ key[1], static_cast<uint32_t>(p0)};
  }
  return ctr;
}

class CounterRng {
 public:
  // `stream` separates independent uses (e.g. erosion vs. tear jitter) under one scenario seed.
  constexpr explicit CounterRng(uint64_t seed, uint32_t stream = 0)
      : key_{static_cast<uint32_t>(seed),
             static_cast<uint32_t>(seed >> 32) ^ (stream * 0x9E3779B9u)},
        stream_(stream) {}

  constexpr PhiloxCounter bits(uint64_t frame, uint32_t element, uint32_t draw = 0) const {
    return philox4x32_10({static_cast<uint32_t>(frame), static_cast<uint32_t>(frame >> 32), element,
                          draw ^ (stream_ << 16)},
                         key_);
  }
  // Uniform in [0, 1), 24 bits of resolution (exact in float).
  constexpr float uniform(uint64_t frame, uint32_t element, uint32_t draw = 0) const {
    return static_cast<float>(bits(frame, element, draw)[0] >> 8) * 0x1.0p-24f;
  }
  // Uniform in [0, 1), 53 bits.
  constexpr double uniform_double(uint64_t frame, uint32_t element, uint32_t draw = 0) const {
    const PhiloxCounter b = bits(frame, element, draw);
    const uint64_t v = (uint64_t{b[0]} << 21) ^ (uint64_t{b[1]} >> 11);
    return static_cast<double>(v & ((uint64_t{1} << 53) - 1)) * 0x1.0p-53;
  }

 private:
  PhiloxKey key_;
  uint32_t stream_;
};

}  // namespace phaco
