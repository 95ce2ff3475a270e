#pragma once
// Internal to systems/haptic_model: the local nodes' step (haptic_model.hpp, step 4): their forces
// (seed 003 §E.1–3, the forceps' coupling, the patch reaction) and one backward Euler step by
// Jacobi-preconditioned CG on the fixed arrays of the slot and the scratch: no allocation.
#include <array>
#include <cmath>
#include <cstdint>

#include "systems/haptic_model/haptic_model.hpp"

namespace phaco::haptic_model::detail {

inline Vec3 node(const HapticSlot& s, uint32_t i) {
  return {s.x[i], s.y[i], s.z[i]};
}

inline bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

// The nodes back to the published model's positions and velocities; the warm start cleared.
void reset_nodes(HapticSlot& s);

// One step of the local nodes (backward Euler, or symplectic Euler for comparison). Returns the CG
// iterations; false in `ok` when the result was not finite (the slot is then reset).
int integrate_nodes(HapticSlot& s, HapticScratch& sc, const Vec3& dev, double kc, double ks,
                    double r, const std::array<HapticContact, kHapticMaxContacts>& contacts,
                    uint32_t ncontacts, const HapticSettings& st, bool& ok);

}  // namespace phaco::haptic_model::detail
