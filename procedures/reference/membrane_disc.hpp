#pragma once
// The analytic membrane (issue 3's first accuracy reference). A flat circular membrane of radius
// R, pinned at its rim, under isotropic tension T (mN/mm), with a small point force F at its
// centre, deflects as
//
//     w(r) = F·ln(R/r) / (2π·T)        (T∇²w = −F·δ, w(R) = 0)
//
// away from the load. The spring network is the membrane: flat disc (flat_disc.hpp), springs by
// springs::build_springs with a pre-stretch (rest length (1 − p)·mesh length). Procedure:
//
//  1. relax in plane (static_solve, z held) with the rim pinned: an irregular mesh, or one whose
//     spring weights do not balance exactly, moves a little;
//  2. measure T from the network, not from the answer: the virial T = Σ_e t_e·l_e / (2A) (t
//     tension, A the disc's area), which is the mean of the two principal stresses; its radial
//     and hoop parts Σ t·l·(n̂·r̂)²/A and Σ t·l·(n̂·θ̂)²/A show how isotropic the stress is;
//  3. load the centre vertex with F = 2π·T·load_scale·R along −z and solve the full 3D static
//     equilibrium (Newton, converged to 1e-9·F);
//  4. compare w at every free vertex with r ≥ r_core = core_edges × mean edge length with the
//     formula, pointwise relative error |w − w_a|/w_a; vertices within r_core of the rim are left
//     out of that relative measure as w_a → 0 there, and reported in the scaled error
//     |w − w_a| / w_a(r_core) instead.
//
// The small load keeps the problem linear (slopes ≈ load_scale·R/r ≪ √prestretch).
#include <cstdint>
#include <span>
#include <vector>

#include "components/springs.hpp"
#include "procedures/reference/flat_disc.hpp"

namespace phaco::reference {

// How the pre-tension is set.
//  UniformPrestretch  every rest length (1 − p)·mesh length (springs::build_springs): the
//                     engine's setting. The tension it gives is isotropic and uniform only on an
//                     equilateral lattice.
//  Cotangent          each spring's rest length is chosen so its force density is
//                     t/l = T0·(cot α + cot β)/2 (α, β the angles opposite the edge), T0 =
//                     (3/2)·p·E·h, the equilateral lattice's tension at pre-stretch p. For a flat
//                     mesh this network is in equilibrium as built, its stress is exactly T0·I,
//                     and its out-of-plane stiffness is the linear finite-element Laplacian of
//                     T0·∇²: the consistent membrane.
enum class Pretension : uint8_t { UniformPrestretch, Cotangent };

const char* to_string(Pretension p);

struct MembraneCase {
  int level = 3;  // disc of 1000·2^level vertices (level 3 = the capsule's default, 8k)
  DiscLayout layout = DiscLayout::Isotropic;
  StiffnessWeighting weighting = StiffnessWeighting::AreaWeighted;
  SpringLaw law = SpringLaw::Linear;
  Pretension pretension = Pretension::UniformPrestretch;
  double radius_mm = 4.5;  // the capsule's radius
  double prestretch = 0.05;
  double sheet_modulus_mn_mm = 26.0;  // E·h, capsule: 2000 kPa × 0.013 mm
  double load_scale = 1e-4;           // F/(2πT), in units of R
  double core_edges = 3.0;            // excluded core radius, in mean edge lengths
  double core_radius_mm = 0.0;        // > 0: a fixed core instead (for convergence orders, where
                                      // a core of a few edges would shrink with h)
  bool keep_samples = false;          // fill MembraneProfileRow::samples
};

struct ProfileSample {
  double r_mm, w_mm, w_analytic_mm;
};

struct MembraneProfileRow {
  int level = 0;
  DiscLayout layout{};
  StiffnessWeighting weighting{};
  SpringLaw law{};
  Pretension pretension{};
  uint32_t vertices = 0, springs = 0;
  double mean_edge_mm = 0.0;
  double tension_mn_mm = 0.0;         // virial
  double tension_radial_mn_mm = 0.0;  // radial part of the virial stress
  double tension_hoop_mn_mm = 0.0;    // hoop part
  double load_mn = 0.0;
  double core_radius_mm = 0.0;
  double max_rel_error = 0.0;     // max |w − w_a|/w_a, r_core ≤ r ≤ R − r_core
  double rms_rel_error = 0.0;     // same set, root mean square
  double max_scaled_error = 0.0;  // max |w − w_a| / w_a(r_core), all free r ≥ r_core
  double centre_deflection_mm = 0.0;
  int relax_iterations = 0, load_iterations = 0;
  double residual_mn = 0.0;  // of the loaded solve
  bool converged = false;
  std::vector<ProfileSample> samples;  // every free vertex, when asked for
};

MembraneProfileRow membrane_profile(const MembraneCase& c);

// Every combination, in the order levels × layouts × weightings × laws; other fields from `base`.
std::vector<MembraneProfileRow> membrane_profile_study(
    std::span<const int> levels, std::span<const DiscLayout> layouts,
    std::span<const StiffnessWeighting> weightings, std::span<const SpringLaw> laws,
    const MembraneCase& base = {});

// Least-squares fit of log(error) = order·log(h) + log(constant) over rows of one layout,
// weighting and law (h = mean edge length).
struct OrderFit {
  double order = 0.0;
  double constant = 0.0;
  int points = 0;
};

OrderFit fit_order(std::span<const double> h, std::span<const double> error);

}  // namespace phaco::reference
