// Implicit Euler (Eigen CG) on membranes: spring Jacobian, stability with the real capsule
// material at the frame step, static equilibrium of a pinned patch, first order in dt.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>

#include "tests/systems/deform/implicit_fixtures.hpp"

namespace phaco {
namespace {

using deform::ImplicitCache;
using implicit_test::Body;
using implicit_test::make_capsule;
using implicit_test::make_grid;

constexpr double kFrameStep = 1.0 / 120.0;

// --- spring Jacobian ---------------------------------------------------------------------------

void expect_jacobian_matches_differences(SpringLaw law, double rest) {
  const double d[3] = {0.7, -0.4, 0.25}, k = 3.0, h = 1e-6;
  const deform::SpringForceJacobian j =
      deform::spring_force_jacobian(d[0], d[1], d[2], rest, k, law);
  static constexpr int kIndex[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  for (int b = 0; b < 3; ++b) {  // ∂f_i/∂x_j column b by central differences
    double dp[3] = {d[0], d[1], d[2]}, dm[3] = {d[0], d[1], d[2]};
    dp[b] += h, dm[b] -= h;
    const auto fp = deform::spring_force_jacobian(dp[0], dp[1], dp[2], rest, k, law).force_on_i;
    const auto fm = deform::spring_force_jacobian(dm[0], dm[1], dm[2], rest, k, law).force_on_i;
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(j.k[kIndex[a][b]], (fp[a] - fm[a]) / (2 * h), 1e-6) << a << b;
  }
}

TEST(SpringJacobian, MatchesFiniteDifferencesInTension) {
  expect_jacobian_matches_differences(SpringLaw::Linear, 0.6);  // l ≈ 0.84 > rest
  expect_jacobian_matches_differences(SpringLaw::Quadratic, 0.6);
}

TEST(SpringJacobian, CompressionKeepsTheBlockPositiveSemidefinite) {
  for (SpringLaw law : {SpringLaw::Linear, SpringLaw::Quadratic}) {
    const auto j =
        deform::spring_force_jacobian(0.5, 0.0, 0.0, 1.0, 2.0, law);  // half its rest length
    EXPECT_LT(j.force_on_i[0], 0.0);                                  // pushes i away from j
    Eigen::Matrix3d m;
    m << j.k[0], j.k[1], j.k[2], j.k[1], j.k[3], j.k[4], j.k[2], j.k[4], j.k[5];
    const Eigen::Vector3d ev = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(m).eigenvalues();
    EXPECT_GE(ev.minCoeff(), 0.0);
    EXPECT_DOUBLE_EQ(j.k[3], 0.0);  // transverse term clamped to zero
    EXPECT_DOUBLE_EQ(j.k[0], law == SpringLaw::Linear ? 2.0 : 2.0 * 2.0 * 0.5);
  }
}

// --- stability with the capsule's real material ---------------------------------------------

TEST(ImplicitEuler, StableAtFrameStepWithCapsuleMaterial) {
  for (int level : {0, 1, 2}) {
    Body b = make_capsule(level, 2000.0, 0.02);
    b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
    // A kick: every free particle starts at 50 mm/s toward the lens.
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i)
      if (b.particles.kind[i] == ParticleKind::Free) b.particles.vz[i] = -50.0f;
    const double k_over_m = springs::max_stiffness_over_mass(b.springs, b.particles);
    EXPECT_GT(k_over_m * kFrameStep * kFrameStep, 1e5)
        << "the explicit limit is far below the frame step";
    ImplicitCache cache;
    double energy = implicit_test::total_energy(b);
    const int steps = level == 2 ? 5 : 20;  // level 1 blew up at frame 16 before the line search
    for (int s = 0; s < steps; ++s) {
      auto m = b.membrane();
      deform::implicit_euler_step(m, kFrameStep, cache);
      ASSERT_TRUE(implicit_test::all_finite(b.particles)) << "level " << level << " step " << s;
      const double e = implicit_test::total_energy(b);
      EXPECT_LE(e, energy + 1e-9 * std::fabs(energy) + 1e-12) << "level " << level << " step " << s;
      energy = e;
    }
    std::printf(
        "[ figures  ] level %d: %u unknowns, k·dt²/m = %.2g, CG iterations last step %d, total "
        "%llu\n",
        level, cache.stats.unknowns, k_over_m * kFrameStep * kFrameStep, cache.stats.cg_iterations,
        static_cast<unsigned long long>(cache.stats.cg_iterations_total));
  }
}

// --- static equilibrium --------------------------------------------------------------------

// Newton on Σ f = 0 over the free particles, dense (small patches only).
std::vector<double> static_equilibrium(const Body& b) {
  const Particles& p = b.particles;
  std::vector<int> unknown(p.slots.size(), -1);
  std::vector<uint32_t> free;
  for (uint32_t i = 0; i < p.slots.size(); ++i)
    if (p.kind[i] == ParticleKind::Free)
      unknown[i] = static_cast<int>(free.size()), free.push_back(i);
  const int n = static_cast<int>(free.size());
  std::vector<double> x(3 * p.slots.size());
  for (uint32_t i = 0; i < p.slots.size(); ++i)
    x[3 * i] = p.x[i], x[3 * i + 1] = p.y[i], x[3 * i + 2] = p.z[i];
  for (int it = 0; it < 50; ++it) {
    Eigen::VectorXd f = Eigen::VectorXd::Zero(3 * n);
    Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(3 * n, 3 * n);
    for (int u = 0; u < n; ++u)
      for (int a = 0; a < 3; ++a) f[3 * u + a] = b.dynamics.gravity_mm_s2[a] / p.inv_mass[free[u]];
    for (uint32_t e = 0; e < b.springs.slots.size(); ++e) {
      const uint32_t i = b.springs.i[e], j = b.springs.j[e];
      const auto s = deform::spring_force_jacobian(
          x[3 * j] - x[3 * i], x[3 * j + 1] - x[3 * i + 1], x[3 * j + 2] - x[3 * i + 2],
          b.springs.rest_length[e], b.springs.stiffness[e], b.dynamics.law);
      Eigen::Matrix3d k;
      k << s.k[0], s.k[1], s.k[2], s.k[1], s.k[3], s.k[4], s.k[2], s.k[4], s.k[5];
      const int ui = unknown[i], uj = unknown[j];
      for (int a = 0; a < 3; ++a) {
        if (ui >= 0) f[3 * ui + a] += s.force_on_i[a];
        if (uj >= 0) f[3 * uj + a] -= s.force_on_i[a];
      }
      if (ui >= 0) jac.block<3, 3>(3 * ui, 3 * ui) -= k;
      if (uj >= 0) jac.block<3, 3>(3 * uj, 3 * uj) -= k;
      if (ui >= 0 && uj >= 0)
        jac.block<3, 3>(3 * ui, 3 * uj) += k, jac.block<3, 3>(3 * uj, 3 * ui) += k;
    }
    if (f.norm() < 1e-13) break;
    const Eigen::VectorXd dx = jac.ldlt().solve(-f);
    for (int u = 0; u < n; ++u)
      for (int a = 0; a < 3; ++a) x[3 * free[u] + a] += dx[3 * u + a];
  }
  return x;
}

TEST(ImplicitEuler, ConvergesToTheStaticEquilibriumOfAPinnedPatch) {
  // 9 × 9 patch, 0.25 mm spacing, pre-stretched 5 %, 1 mg per node under 10 g.
  Body b = make_grid(9, 0.25, 1e-6, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.05});
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -98100.0f};
  b.dynamics.viscosity_per_s = 5.0f;
  const std::vector<double> reference = static_equilibrium(b);
  ImplicitCache cache;
  cache.settings.cg_tolerance = 1e-10;
  for (int s = 0; s < 300; ++s) {
    auto m = b.membrane();
    deform::implicit_euler_step(m, 0.01, cache);
  }
  double max_error = 0.0, max_deflection = 0.0;
  for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
    max_deflection = std::max(max_deflection, std::fabs(reference[3 * i + 2]));
    max_error = std::max({max_error, std::fabs(b.particles.x[i] - reference[3 * i]),
                          std::fabs(b.particles.y[i] - reference[3 * i + 1]),
                          std::fabs(b.particles.z[i] - reference[3 * i + 2])});
  }
  std::printf("[ figures  ] equilibrium: max deflection %.4g mm, max error %.3g mm\n",
              max_deflection, max_error);
  EXPECT_GT(max_deflection, 0.01);
  EXPECT_LT(max_error, 1e-4 * max_deflection);
}

// --- order of accuracy in dt --------------------------------------------------------------

// One spring (k = 1 mN/mm, rest 1 mm) holding 1 g to an anchor, released 0.2 mm stretched:
// x(t) = 1 + 0.2·cos(ω·t), ω = √(k/m).
double single_spring_error(int steps, double t_end) {
  Body b;
  table_append(b.particles, 2);
  b.particles.x[1] = 1.2f;
  b.particles.kind[0] = ParticleKind::Anchored;
  b.particles.inv_mass[1] = 1000.0f;
  const uint32_t e = table_add(b.springs);
  b.springs.i[e] = 0, b.springs.j[e] = 1, b.springs.rest_length[e] = 1.0f,
  b.springs.stiffness[e] = 1.0f;
  b.blocks = springs::plan_blocks(b.springs, 2);
  ImplicitCache cache;
  cache.settings.cg_tolerance = 1e-12;
  for (int s = 0; s < steps; ++s) {
    auto m = b.membrane();
    deform::implicit_euler_step(m, t_end / steps, cache);
  }
  const double omega = std::sqrt(1000.0);
  return std::fabs(b.particles.x[1] - (1.0 + 0.2 * std::cos(omega * t_end)));
}

TEST(ImplicitEuler, FirstOrderInTheTimeStep) {
  // One full period: the amplitude error (first order) shows, the phase error (second) does not.
  const double t_end = 2.0 * M_PI / std::sqrt(1000.0);
  double previous = single_spring_error(100, t_end);
  for (int steps : {200, 400, 800}) {
    const double error = single_spring_error(steps, t_end);
    const double order = std::log2(previous / error);
    std::printf("[ figures  ] dt = %.3g s: error %.3g mm, order %.3f\n", t_end / steps, error,
                order);
    EXPECT_NEAR(order, 1.0, 0.15);
    previous = error;
  }
}

}  // namespace
}  // namespace phaco
