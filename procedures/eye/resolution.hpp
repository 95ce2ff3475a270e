#pragma once
// Resolution levels: level L roughly doubles the element count of level L-1.
#include <cstdint>

namespace phaco::eye {

constexpr int kMinLevel = 0;
constexpr int kMaxLevel = 8;
constexpr int kDefaultLevel = 3;

// Targets the generators meet within about ±25 %.
struct Resolution {
  int level = kDefaultLevel;
  uint32_t capsule_vertices = 0;  // anterior capsule mesh
  uint32_t lens_tets = 0;         // tetrahedral lens
};

// capsule 1000·2^L vertices, lens 6250·2^L tets (L=3: 8k / 50k; L=7: 128k / 800k).
// Throws InputError outside [kMinLevel, kMaxLevel].
Resolution resolution_for_level(int level);

}  // namespace phaco::eye
