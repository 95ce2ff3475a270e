#pragma once
// Per-cell state of the lens as moving mass points (seed 002 §4: one particle per simplex cell,
// at its tetrahedron's barycentre), hot per-frame state as float SoA. 33 bytes per cell.
// The cell's index is its id: the tools' random draws and removal lists are keyed by it, so ids
// stay fixed for the life of the lens (removal clears `alive`, it does not compact).
//
// The systems take CellSpans, not LensCells, so the same functions run over any owner's columns
// (the simplex cells, a test's handful of points).
#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/invariants.hpp"

namespace phaco {

struct LensCells {
  std::vector<float> x, y, z;     // mm
  std::vector<float> vx, vy, vz;  // mm/s
  std::vector<float> mass;        // kg
  std::vector<uint8_t> alive;     // 1 while the cell exists, 0 once removed
  std::vector<float> hardness;    // 0 (soft cortex) .. 1 (hard nucleus), dimensionless
  std::vector<uint8_t> contact;   // 1 when an environment constraint moved the cell this frame

  uint32_t size() const { return static_cast<uint32_t>(x.size()); }
  void resize(uint32_t n) {
    for (auto* c : {&x, &y, &z, &vx, &vy, &vz, &mass, &hardness}) c->resize(n, 0.0f);
    alive.resize(n, 1);
    contact.resize(n, 0);
  }
  template <class F>
  void for_each_column(F&& f) {
    f(x), f(y), f(z), f(vx), f(vy), f(vz), f(mass), f(alive), f(hardness), f(contact);
  }
};

// A view of cell columns of equal length; what the lens tools read and write.
struct CellSpans {
  std::span<float> x, y, z;         // mm
  std::span<float> vx, vy, vz;      // mm/s
  std::span<const float> mass;      // kg
  std::span<const uint8_t> alive;   // 0 = skip the cell
  std::span<const float> hardness;  // 0..1

  uint32_t size() const { return static_cast<uint32_t>(x.size()); }
  // Every column of one length: the lens tools assert it in debug builds (a view made of columns
  // of two tables would be read past the shorter one's end).
  bool in_step() const { return same_size(x, y, z, vx, vy, vz, mass, alive, hardness); }
};

inline CellSpans cell_spans(LensCells& c) {
  return {c.x, c.y, c.z, c.vx, c.vy, c.vz, c.mass, c.alive, c.hardness};
}

}  // namespace phaco
