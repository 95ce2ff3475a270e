#pragma once
// Mass points of a deformable body (cornea, capsule...), hot per-frame state as float SoA.
// 29 bytes per particle (target ≤ 64, issue 3).
#include <cstdint>
#include <vector>

#include "engine/core/table.hpp"

namespace phaco {

// Seed 001 §3.4: anchored particles never move, scripted ones follow a tool, free ones integrate.
enum class ParticleKind : uint8_t { Free = 0, Anchored = 1, Scripted = 2 };

struct Particles {
  SlotIndex slots;
  std::vector<float> x, y, z;     // mm
  std::vector<float> vx, vy, vz;  // mm/s
  std::vector<float> inv_mass;    // 1/kg; 0 for anchored
  std::vector<ParticleKind> kind;

  template <class F>
  void for_each_column(F&& f) {
    f(x), f(y), f(z), f(vx), f(vy), f(vz), f(inv_mass), f(kind);
  }
};

}  // namespace phaco
