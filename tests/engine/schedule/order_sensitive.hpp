#pragma once
// Values whose float sum depends on the order of the additions (a wide dynamic range): a check of
// "the same bits" on them can fail.
#include <cstdint>
#include <vector>

namespace phaco::test {

inline std::vector<float> order_sensitive_values(size_t n, uint32_t seed) {
  std::vector<float> x(n);
  uint32_t state = seed;
  for (float& v : x) {
    state = state * 1664525u + 1013904223u;
    const float mag = (state >> 28) == 0 ? 1.0e6f : 1.0e-3f;
    v = mag * (static_cast<float>(state >> 8) / 16777216.0f - 0.3f);
  }
  return x;
}

// Left to right, the order no tree of chunks gives.
inline float linear_sum(const std::vector<float>& x) {
  float s = 0;
  for (float v : x) s += v;
  return s;
}

}  // namespace phaco::test
