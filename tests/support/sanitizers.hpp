#pragma once
// Test sizes under AddressSanitizer. scripts/test.sh runs every test twice: in Release, at full
// size, and under ASan+UBSan, which looks for memory errors on the same code paths and runs them
// 5–20× slower. Fuzz loops there run a fraction of their cases, so CI stays well under its
// 45-minute limit; the Release pass keeps the full counts.
#include <algorithm>

namespace phaco::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kUnderAsan = true;
#else
inline constexpr bool kUnderAsan = false;
#endif

// n in Release; n / divisor (at least 1) under ASan.
constexpr int asan_scaled(int n, int divisor) {
  return kUnderAsan ? std::max(1, n / divisor) : n;
}

}  // namespace phaco::test
