#pragma once
// Area-weighted against uniform springs (seed 000 §5.1 claims k = (a1 + a2)/l² is "more accurate
// than the conventional methods in simulating uniformly elastic surface"). A uniformly elastic
// sheet is isotropic: its stiffness must not depend on the direction it is pulled in.
//
// Test: a flat disc (no pre-stretch, linear springs) gets a small uniaxial strain ε along the
// direction d(θ): every rim vertex is moved by ε·(d·x)·d, the interior relaxes (static_solve, in
// plane). The sheet's stress is the virial σ = Σ_e t_e·l_e·n̂n̂ᵀ / A. From it:
//
//   constrained modulus   M(θ) = d·σ·d / ε          (continuum: E·h / (1 − ν²) = 9/8·E·h)
//   Young's modulus       E(θ) = 1 / (mᵀ·S·m)       S = C⁻¹, C the 3×3 (Voigt) stiffness fitted
//                                                    to all directions' stresses by least squares,
//                                                    m = (cos²θ, sin²θ, cosθ·sinθ): the modulus a
//                                                    strip pulled along θ would show (reaction
//                                                    force / strain / width)
//
// Limit: a disc measures the sheet's average response. A ring layout's local anisotropy (radial
// against hoop, membrane_disc.hpp's stress check shows it) averages out over all orientations, so
// the directional spread here speaks for statistically uniform meshes such as the irregular one.
// (A virial over a small window was tried for the local response; its edge noise, about
// 2h/window radius, swamped the signal.)
//
// The reference is the continuum a triangular spring lattice represents: E·h with Poisson ratio
// 1/3 (central-force lattice). For each weighting: mean over directions, spread (max − min)/mean,
// and the mean's error against E·h.
#include <cstdint>
#include <span>
#include <vector>

#include "components/springs.hpp"
#include "procedures/reference/flat_disc.hpp"

namespace phaco::reference {

struct IsotropyCase {
  DiscLayout layout = DiscLayout::Irregular;
  StiffnessWeighting weighting = StiffnessWeighting::AreaWeighted;
  int level = 1;  // 1000·2^level vertices
  double radius_mm = 4.5;
  double sheet_modulus_mn_mm = 26.0;  // E·h
  double strain = 1e-3;
  std::vector<double> angles_deg = {0, 30, 60, 90, 120, 150};
  uint64_t seed = 7;  // irregular layout
};

struct IsotropyDirection {
  double angle_deg = 0.0;
  double constrained_modulus_mn_mm = 0.0;  // M(θ)
  double youngs_modulus_mn_mm = 0.0;       // E(θ) from the fitted stiffness
};

struct IsotropyRow {
  DiscLayout layout{};
  StiffnessWeighting weighting{};
  int level = 0;
  uint32_t vertices = 0;
  double edge_length_cv = 0.0;  // std/mean of the edge lengths (how irregular)
  std::vector<IsotropyDirection> directions;
  double youngs_mean = 0.0, youngs_spread = 0.0;  // spread = (max − min)/mean
  double constrained_mean = 0.0, constrained_spread = 0.0;
  double poisson_ratio = 0.0;           // −S12/S11 averaged with −S12/S22
  double continuum_youngs_mn_mm = 0.0;  // E·h
  double youngs_mean_error = 0.0;       // (youngs_mean − E·h)/(E·h)
  double fit_residual = 0.0;            // relative misfit of the linear stiffness fit
  double worst_residual_mn = 0.0;       // of the static solves
};

IsotropyRow stiffness_isotropy(const IsotropyCase& c);

// Every layout × weighting, other fields from `base`.
std::vector<IsotropyRow> stiffness_isotropy_study(std::span<const DiscLayout> layouts,
                                                  std::span<const StiffnessWeighting> weightings,
                                                  const IsotropyCase& base = {});

}  // namespace phaco::reference
