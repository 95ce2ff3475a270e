// Static equilibrium (the reference every fast method is measured against): exact answers on
// small networks for both spring laws, residual below tolerance, fixed particles kept.
#include <gtest/gtest.h>

#include <cmath>

#include "procedures/reference/static_solve.hpp"

namespace phaco::reference {
namespace {

// 0 fixed at the origin, then `count` free particles along x; force F on the last.
StaticNetwork chain(int count, double rest, double k, SpringLaw law, double force) {
  StaticNetwork net;
  net.law = law;
  for (int p = 0; p <= count; ++p) {
    net.x.push_back(Vec3(rest * p, 0.01 * p * p, 0.0));  // a bent, unstretched start
    net.fixed.push_back(p == 0);
    if (p > 0) {
      net.i.push_back(p - 1), net.j.push_back(p);
      net.rest_length.push_back(rest), net.stiffness.push_back(k);
    }
  }
  net.external_force.assign(net.x.size(), Vec3::Zero());
  net.external_force.back() = Vec3(force, 0.0, 0.0);
  return net;
}

TEST(StaticSolve, SpringsInSeriesStretchByForceOverStiffness) {
  for (SpringLaw law : {SpringLaw::Linear, SpringLaw::Quadratic}) {
    StaticNetwork net = chain(3, 0.5, 20.0, law, 0.8);
    const StaticResult r = solve_static(net, {1e-12, 60});
    ASSERT_TRUE(r.converged);
    EXPECT_LE(r.residual_mn, 1e-12);
    // Linear: extension F/k per spring; quadratic F = k·ext²: ext = √(F/k).
    const double ext = law == SpringLaw::Linear ? 0.8 / 20.0 : std::sqrt(0.8 / 20.0);
    EXPECT_NEAR(net.x[3].x(), 3 * (0.5 + ext), 1e-12);
    EXPECT_NEAR(net.x[3].y(), 0.0, 1e-12);
    EXPECT_EQ(net.x[0], Vec3::Zero());
  }
}

TEST(StaticSolve, PretensionedStringUnderTransverseLoad) {
  // Ends fixed at ±L, middle particle loaded by F along z: 2·t·w/l = F, t = k(l − l0), l = √(L² +
  // w²).
  const double L = 1.0, l0 = 0.9, k = 10.0, F = 0.3;
  StaticNetwork net;
  net.x = {Vec3(-L, 0, 0), Vec3(0, 0, 0), Vec3(L, 0, 0)};
  net.fixed = {1, 0, 1};
  net.i = {0, 1}, net.j = {1, 2};
  net.rest_length = {l0, l0}, net.stiffness = {k, k};
  net.external_force = {Vec3::Zero(), Vec3(0, 0, F), Vec3::Zero()};
  const StaticResult r = solve_static(net, {1e-13, 60});
  ASSERT_TRUE(r.converged);
  double lo = 0.0, hi = 1.0;  // bisection on the exact equation
  for (int it = 0; it < 200; ++it) {
    const double w = 0.5 * (lo + hi), l = std::hypot(L, w);
    (2.0 * k * (l - l0) * w / l < F ? lo : hi) = w;
  }
  EXPECT_NEAR(net.x[1].z(), lo, 1e-12);
  const auto f = net_forces(net);
  EXPECT_LT(f[1].norm(), 1e-12);
  EXPECT_NEAR(f[0].z() + f[2].z(), F, 1e-12);  // the springs pull the supports with the load
}

TEST(StaticSolve, PlanarHoldsZAndSolvesInPlane) {
  StaticNetwork net = chain(4, 0.25, 5.0, SpringLaw::Linear, 0.1);
  for (Vec3& x : net.x) x.z() = 0.3;
  net.external_force.back() = Vec3(0.1, 0.0, 0.5);  // the z part is ignored when planar
  net.planar = true;
  const StaticResult r = solve_static(net, {1e-12, 60});
  ASSERT_TRUE(r.converged);
  for (const Vec3& x : net.x) EXPECT_EQ(x.z(), 0.3);
  EXPECT_NEAR(net.x[4].x(), 4 * (0.25 + 0.1 / 5.0), 1e-12);
}

TEST(StaticSolve, CompressedSpringsStillConverge) {
  // A square with a diagonal, squeezed: some springs compressed (transverse term clamped).
  StaticNetwork net;
  net.x = {Vec3(0, 0, 0), Vec3(0.9, 0, 0), Vec3(0.9, 0.9, 0), Vec3(0, 0.9, 0)};
  net.fixed = {1, 0, 0, 1};
  net.i = {0, 1, 2, 0, 0}, net.j = {1, 2, 3, 3, 2};
  net.rest_length = {1, 1, 1, 1, std::sqrt(2.0)};
  net.stiffness = {3, 3, 3, 3, 3};
  net.planar = true;
  const StaticResult r = solve_static(net, {1e-12, 80});
  EXPECT_TRUE(r.converged);
  EXPECT_LE(r.residual_mn, 1e-12);
}

}  // namespace
}  // namespace phaco::reference
