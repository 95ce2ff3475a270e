#pragma once
// How one deformable body moves: its integrator, spring law, damping and environment forces.
// Plain data; the deform systems read it.
#include <array>
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "components/springs.hpp"

namespace phaco {

enum class Integrator : uint8_t {
  ExplicitEuler,      // x += v·dt; v += a·dt (from the old state)
  SymplecticEuler,    // v += a·dt; x += v·dt
  SemiImplicit001,    // seed 001 §3.4: velocity implicit (linearised), position explicit from it
  ImplicitEuler,      // backward Euler, one Newton step solved by Eigen CG (warm-started)
  ImplicitPredictor,  // seed 004: approximate implicit step, linear system's inverse precomputed
                      // (Desbrun 1999)
  Xpbd,  // compliant constraints (Macklin 2016), a modern alternative the seeds did not have
};

constexpr std::string_view to_string(Integrator i) {
  switch (i) {
    case Integrator::ExplicitEuler:
      return "explicit_euler";
    case Integrator::SymplecticEuler:
      return "symplectic_euler";
    case Integrator::SemiImplicit001:
      return "semi_implicit_001";
    case Integrator::ImplicitEuler:
      return "implicit_euler";
    case Integrator::ImplicitPredictor:
      return "implicit_predictor";
    case Integrator::Xpbd:
      return "xpbd";
  }
  return "unknown";
}

constexpr std::optional<Integrator> parse_integrator(std::string_view s) {
  for (Integrator i :
       {Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::SemiImplicit001,
        Integrator::ImplicitEuler, Integrator::ImplicitPredictor, Integrator::Xpbd}) {
    if (to_string(i) == s) return i;
  }
  return std::nullopt;
}

struct Dynamics {
  Integrator integrator = Integrator::ImplicitEuler;
  SpringLaw law = SpringLaw::Linear;
  float damping_per_s = 0.0f;  // f = −m·damping·v (seed 003 k_d, seed 004 γ), 1/s
  float viscosity_per_s =
      0.0f;  // viscoelastic medium, f = −m·viscosity·v (seed 003 k_v, seed 001), 1/s
  std::array<float, 3> gravity_mm_s2 = {0.0f, 0.0f, 0.0f};  // patient supine: (0, 0, −9810)
  float glue_stiffness_mn_mm =
      0.0f;  // seed 001: weak positional springs holding the capsule on the lens
  float mass_scale =
      1.0f;  // > 1 fakes heavier particles so an explicit step survives (error reported)
  uint16_t substeps = 1;          // per frame
  float max_speed_mm_s = 1.0e4f;  // beyond it a step counts as diverged
};

// Rest positions of the glue springs, one per particle (mm); empty when the body has no glue.
struct Glue {
  std::vector<float> x, y, z;
};

// What a body's stepping did this frame and over the run (for reports and tests).
struct DynamicsStatus {
  uint64_t steps = 0;
  uint64_t divergences = 0;  // steps whose result exceeded the bounds (then recovered)
  uint64_t fallbacks = 0;    // recoveries that switched to a stable integrator
  uint16_t substeps_in_use = 1;
  Integrator in_use = Integrator::ImplicitEuler;
  float max_speed_mm_s = 0.0f;
};

}  // namespace phaco
