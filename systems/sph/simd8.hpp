#pragma once
// Eight floats / eight ints as GCC/Clang vector extensions: SIMD on any target without
// intrinsics (two SSE registers on baseline x86-64, one AVX register in an avx2 clone). The
// arithmetic per lane is the same in every clone (no FMA is enabled), so results do not depend on
// which clone runs, and a lane computes the same bits as the scalar expression written the same
// way. Shared by the neighbour passes (neighbours.cpp, contact.cpp); internal to them.
#include <cstdint>
#include <cstring>

// GCC notes that 32-byte vector arguments change the ABI without AVX; these helpers are internal
// and inlined, so no ABI boundary is crossed.
#pragma GCC diagnostic ignored "-Wpsabi"

namespace phaco::sph::simd8 {

typedef float F8 __attribute__((vector_size(32)));
typedef int32_t I8 __attribute__((vector_size(32)));

inline F8 load8(const float* p) {
  F8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline I8 load8(const uint32_t* p) {
  I8 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline F8 splat(float v) {
  return F8{v, v, v, v, v, v, v, v};
}

inline I8 splat(int32_t v) {
  return I8{v, v, v, v, v, v, v, v};
}

// −1 in lanes l with first + l < end (the valid candidates of a last, partial block).
inline I8 below(uint32_t first, uint32_t end) {
  const I8 lane = {0, 1, 2, 3, 4, 5, 6, 7};
  return (static_cast<int32_t>(first) + lane) < static_cast<int32_t>(end);
}

inline bool any(I8 mask) {
  uint64_t w[4];
  std::memcpy(w, &mask, sizeof w);
  return (w[0] | w[1] | w[2] | w[3]) != 0;
}

}  // namespace phaco::sph::simd8
