// A fragment held at the tip (issue 19 item 5): its weight, drag and inertia felt as a load.
// The model and its orders of magnitude: components/held_fragment.hpp.
//
// Backward Euler of m·a = −k_h·(x − P) − c_h·(v − V_P) − drag·v + W over one tick, solved for the
// new velocity in closed form (the system is linear and isotropic: a scalar divide):
//   v' = (m·v/dt − k_h·(x − P) + c_h·V_P + W) / (m/dt + dt·k_h + c_h + drag),   x' = x + dt·v'.
// c_h = 2·√(k_h·m), critical: the attachment does not ring, whatever the mass.
#include <algorithm>
#include <cmath>

#include "systems/haptic_model/proxy_planes.hpp"

namespace phaco::haptic_model::detail {

Vec3 held_load(const HeldFragment& fragment, const Vec3& proxy, const Vec3& proxy_velocity,
               const HapticSettings& settings, HeldLoadState& state) {
  const double m = std::max(0.0, double(fragment.mass_kg));
  const double kh = std::max(0.0, settings.held_stiffness_mn_per_mm);
  const Vec3 weight(fragment.weight_mn[0], fragment.weight_mn[1], fragment.weight_mn[2]);
  if (!fragment.held || !(kh > 0) || !std::isfinite(m) || !std::isfinite(weight.norm())) {
    state = {};
    return Vec3::Zero();
  }
  if (!state.live) {  // hanging at rest relative to the tip: the load starts at the weight
    state.live = true;
    state.x = proxy + weight / kh;
    // A proxy that was just placed (a new slot) has a meaningless first difference; no hand moves
    // a tip inside the eye at 1 m/s.
    state.v = proxy_velocity.norm() < 1e3 ? proxy_velocity : Vec3::Zero();
  }
  const double dt = settings.dt_s;
  const double ch = 2.0 * std::sqrt(kh * m);
  const double drag = std::max(0.0, double(fragment.drag_mn_s_per_mm));
  // m is in kg, forces in mN, lengths in mm: kg·mm/s² = mN, so m enters as is.
  const Vec3 v = (m / dt * state.v - kh * (state.x - proxy) + ch * proxy_velocity + weight) /
                 (m / dt + dt * kh + ch + drag);
  state.x += dt * v;
  state.v = v;
  Vec3 load = kh * (state.x - proxy) + ch * (v - proxy_velocity);
  const double limit = fragment.hold_limit_mn, mag = load.norm();
  if (limit > 0 && mag > limit) load *= limit / mag;
  if (!std::isfinite(load.norm())) {
    state = {};
    return Vec3::Zero();
  }
  state.load = load;
  return load;
}

}  // namespace phaco::haptic_model::detail
