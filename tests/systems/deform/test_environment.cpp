// Seed 001's correction step: particles are kept out of the lens and inside the posterior cornea.
#include <gtest/gtest.h>

#include <cmath>

#include "tests/systems/deform/deform_fixtures.hpp"

namespace phaco {
namespace {

using deform_test::Body;

deform::Environment lens_and_cornea() {
  deform::Environment env;
  env.has_lens = true;
  env.has_cornea = true;
  return env;
}

TEST(Environment, ParticlesInsideTheLensGoBackToItsSurfaceAlongTheNormal) {
  Body b;
  b.environment = lens_and_cornea();
  struct Case {
    double x, y, z;
  };
  // Just under the anterior surface, under the posterior surface, near the equator, deep, the
  // centre.
  const Case cases[] = {
      {1.0, 0.5, 1.70}, {-2.0, 1.0, -2.30}, {4.60, 0.0, 0.10}, {0.5, 0.2, 0.3}, {0.0, 0.0, 0.0}};
  for (const Case& c : cases) deform_test::add_particle(b, c.x, c.y, c.z, ParticleKind::Free, 1e-6);
  for (uint32_t i = 0; i < b.particles.slots.size(); ++i)
    b.particles.vz[i] = b.particles.z[i] >= 0 ? -5.0f : 5.0f;
  b.particles.vx[0] = 3.0f;  // a tangential-ish component that must survive in part
  deform::Membrane m = b.membrane();
  EXPECT_EQ(deform::apply_environment(m), 5u);
  const deform::Environment& env = b.environment;
  for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
    const double q = deform::lens_level(env, b.particles.x[i], b.particles.y[i], b.particles.z[i]);
    EXPECT_NEAR(q, 1.0, 1e-5) << "case " << i;
    // Outward normal at the corrected point: the velocity no longer points into the lens.
    const double r2 = env.lens_radius_mm * env.lens_radius_mm;
    const double c = b.particles.z[i] >= 0 ? env.lens_anterior_mm : env.lens_posterior_mm;
    const double n[3] = {b.particles.x[i] / r2, b.particles.y[i] / r2, b.particles.z[i] / (c * c)};
    const double vn =
        b.particles.vx[i] * n[0] + b.particles.vy[i] * n[1] + b.particles.vz[i] * n[2];
    EXPECT_GE(vn, -1e-5) << "case " << i;
  }
  // Shallow cases moved (nearly) along the normal: the correction is parallel to ∇q.
  for (uint32_t i : {0u, 1u, 2u}) {
    const double d[3] = {b.particles.x[i] - cases[i].x, b.particles.y[i] - cases[i].y,
                         b.particles.z[i] - cases[i].z};
    const double r2 = env.lens_radius_mm * env.lens_radius_mm;
    const double c = cases[i].z >= 0 ? env.lens_anterior_mm : env.lens_posterior_mm;
    const double g[3] = {cases[i].x / r2, cases[i].y / r2, cases[i].z / (c * c)};
    const double dn = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]),
                 gn = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
    const double cosine = (d[0] * g[0] + d[1] * g[1] + d[2] * g[2]) / (dn * gn);
    EXPECT_GT(cosine, 0.99) << "case " << i;
  }
  EXPECT_GT(b.particles.vx[0], 0.0f);  // the tangential motion is kept
}

TEST(Environment, ParticlesBeyondTheCorneaComeBackAndLoseOutwardSpeed) {
  Body b;
  b.environment = lens_and_cornea();
  const deform::Environment& env = b.environment;
  deform_test::add_particle(b, 0.0, 0.0, env.cornea_centre_z_mm + env.cornea_radius_mm + 0.2,
                            ParticleKind::Free, 1e-6);
  deform_test::add_particle(b, 3.0, 0.0, 3.0, ParticleKind::Free,
                            1e-6);  // inside the chamber: untouched
  deform_test::add_particle(b, 0.0, 0.0, 5.5, ParticleKind::Anchored,
                            0);  // held by a tool: untouched
  b.particles.vz[0] = 7.0f, b.particles.vx[0] = 2.0f;
  deform::Membrane m = b.membrane();
  EXPECT_EQ(deform::apply_environment(m), 1u);
  EXPECT_NEAR(b.particles.z[0], env.cornea_centre_z_mm + env.cornea_radius_mm, 1e-5);
  EXPECT_EQ(b.particles.vz[0], 0.0f);
  EXPECT_EQ(b.particles.vx[0], 2.0f);
  EXPECT_EQ(b.particles.z[1], 3.0f);
  EXPECT_EQ(b.particles.z[2], 5.5f);
}

// The capsule pushed down onto the lens by a load never ends a step inside it.
TEST(Environment, LoadedCapsuleStaysOnTheLens) {
  Body b = deform_test::make_capsule(0, 20.0, 0.02);
  b.environment = lens_and_cornea();
  b.dynamics.integrator = Integrator::SymplecticEuler;
  b.dynamics.mass_scale = 1.0e4f;
  b.dynamics.damping_per_s = 200.0f;
  const uint32_t centre = deform_test::centre_particle(b);
  b.loads.push_back({centre, 0.0f, 0.0f, -0.5f});
  deform::DeformState st;
  uint32_t corrections = 0;
  for (int s = 0; s < 300; ++s) {
    deform::Membrane m = b.membrane();
    const auto report = deform::step(m, 5e-5, st);
    corrections += report.environment_corrections;
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
      ASSERT_GE(
          deform::lens_level(b.environment, b.particles.x[i], b.particles.y[i], b.particles.z[i]),
          1.0 - 1e-5)
          << "step " << s << " particle " << i;
    }
  }
  EXPECT_GT(corrections, 0u);  // the lens did push back
  EXPECT_TRUE(deform_test::all_finite(b.particles));
}

}  // namespace
}  // namespace phaco
