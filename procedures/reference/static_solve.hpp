#pragma once
// Static equilibrium of a spring network: the "converged" reference every fast method (force
// propagation, damped dynamics, mass scaling) is measured against.
//
// Minimises E(x) = Σ_e U(l_e) − Σ_p f_p·x_p over the free particles, U' = k·(l − l0) (linear) or
// k·(l − l0)·|l − l0| (quadratic, seed 000 §5.1), by Newton's method in double precision: the
// Hessian block of a spring is U''·n̂n̂ᵀ + (U'/l)·(I − n̂n̂ᵀ), with the transverse term clamped at
// zero for compressed springs (projected Newton: the step stays a descent direction), factorised
// by Eigen's SimplicialLDLT (a Levenberg shift when the factorisation fails), and a backtracking
// line search on E. Fixed particles (anchored, scripted) keep their positions; `planar` holds
// every z, for in-plane problems where a flat sheet has no transverse stiffness.
//
// Converged means the largest net force on a free particle is below tolerance_mn.
#include <cstdint>
#include <vector>

#include "components/particles.hpp"
#include "components/springs.hpp"
#include "engine/core/math.hpp"

namespace phaco::reference {

struct StaticNetwork {
  std::vector<Vec3> x;               // mm: the initial guess in, the equilibrium out
  std::vector<uint8_t> fixed;        // 1: position imposed
  std::vector<Vec3> external_force;  // mN per particle; empty = none
  std::vector<uint32_t> i, j;        // spring ends
  std::vector<double> rest_length;   // mm
  std::vector<double> stiffness;     // Linear: mN/mm; Quadratic: mN/mm²
  SpringLaw law = SpringLaw::Linear;
  bool planar = false;  // z held for every particle
};

// Positions from the particles; fixed = kind is not Free; live springs only.
StaticNetwork network_from(const Particles& particles, const Springs& springs, SpringLaw law);

struct StaticSettings {
  double tolerance_mn = 1e-10;  // largest net force on a free particle at convergence
  int max_iterations = 60;
};

struct StaticResult {
  bool converged = false;
  int iterations = 0;
  double residual_mn = 0.0;  // largest net force on a free particle
  double energy = 0.0;       // µJ (mN·mm), at the solution
};

StaticResult solve_static(StaticNetwork& network, const StaticSettings& settings = {});

// Net force (springs + external) on every particle, mN; fixed particles included (their
// negative is the support's reaction).
std::vector<Vec3> net_forces(const StaticNetwork& network);

// Tension of every spring (mN, positive when stretched).
std::vector<double> spring_tensions(const StaticNetwork& network);

}  // namespace phaco::reference
