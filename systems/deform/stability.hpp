#pragma once
// Stability maps: the largest time step at which each integrator stays stable, as a function of
// spring stiffness k and particle mass m (issue 3 item 6).
//
// A trial runs an integrator, unguarded (integrate_once), for `steps` steps on a small test body
// of unit spacing whose free particles start displaced by 0.01 in a fixed pseudo-random pattern
// (every mode excited) and at rest, with no gravity and no load. It is stable when every state
// stays finite, no particle travels more than a quarter of the spacing (beyond that the body is
// out of the linear regime the question is about: a spring folding through its anchor would cap
// a growing mode and fake stability), and the
// largest energy (kinetic + elastic) over the trial's second half is at most `growth_bound` times
// the largest over its first half: a bounded oscillation passes however large its swing (a
// symplectic step near its limit swings the true energy by (1 + ω·dt/2)/(1 − ω·dt/2)), a growing
// mode does not. The largest stable dt
// is found by bisection in log(ω·dt), ω = √(k/m), between min_omega_dt and max_omega_dt.
//
// Theory it is checked against (tests): on one spring-mass, symplectic Euler is stable iff
// ω·dt < 2; explicit Euler multiplies the energy by exactly 1 + ω²dt² per step, so without
// damping it is unstable at every dt — over a finite trial it "passes" only while
// (1 + ω²dt²)^(steps/2) ≤ growth_bound, i.e. ω·dt ≲ √(2·ln(bound)/steps), a limit that shrinks to
// zero as the trial lengthens (reported, not hidden); with damping c it is stable for dt < c/ω².
// The seed-001 scheme, implicit Euler, the predictor and XPBD come out stable over the whole range.
//
// Reads/writes only its own test bodies.
#include <cstdint>
#include <span>
#include <vector>

#include "components/dynamics.hpp"

namespace phaco::deform {

enum class ProbeBody : uint8_t {
  SpringMass,  // one free particle on one spring to an anchor: ω_max = √(k/m)
  Patch,  // a square grid (patch_side² particles, triangulated), rim anchored: ω_max ≈ √(8k/m)
};

struct StabilityProbe {
  ProbeBody body = ProbeBody::Patch;
  uint32_t patch_side = 6;
  SpringLaw law = SpringLaw::Linear;
  double damping_per_s = 0.0;
  uint32_t steps = 200;
  double growth_bound = 2.0;
  double min_omega_dt = 1.0e-2,
         max_omega_dt = 1.0e3;  // below 1e-2 float positions stall (dt·v < ulp)
  int bisections = 24;
  uint16_t xpbd_iterations = 4;
};

struct StabilityResult {
  double dt_max_s = 0.0;             // largest stable step found (0 if none in the range)
  double omega_per_s = 0.0;          // √(k/m)
  bool stable_everywhere = false;    // stable at max_omega_dt/ω: dt_max_s is that bound
  bool unstable_everywhere = false;  // unstable at min_omega_dt/ω
  double omega_dt() const { return dt_max_s * omega_per_s; }
};

bool is_stable(Integrator integrator, double k_mn_mm, double mass_kg, double dt_s,
               const StabilityProbe& probe = {});

StabilityResult largest_stable_dt(Integrator integrator, double k_mn_mm, double mass_kg,
                                  const StabilityProbe& probe = {});

// cells[ik * mass_values.size() + im] for k_values[ik], mass_values[im].
struct StabilityMap {
  Integrator integrator = Integrator::ExplicitEuler;
  std::vector<double> k_values, mass_values;  // mN/mm, kg
  std::vector<StabilityResult> cells;
};

StabilityMap stability_map(Integrator integrator, std::span<const double> k_values,
                           std::span<const double> mass_values, const StabilityProbe& probe = {});

}  // namespace phaco::deform
