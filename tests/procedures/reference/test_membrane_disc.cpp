// The analytic membrane: w(r) = F·ln(R/r)/(2πT) for a pinned disc under tension T and a central
// point force. Figures measured for these tolerances are in docs/membrane_accuracy.md.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <numbers>
#include <vector>

#include "procedures/reference/flat_disc.hpp"
#include "procedures/reference/membrane_disc.hpp"
#include "tests/support/sanitizers.hpp"

namespace phaco::reference {
namespace {

TEST(FlatDisc, MeetsTheTargetWithValidTrianglesAndACircularRim) {
  for (DiscLayout layout : {DiscLayout::Curvilinear, DiscLayout::Isotropic, DiscLayout::Irregular})
    for (int level = 0; level <= 3; ++level) {
      const uint32_t target = 1000u << level;
      const FlatDisc d = make_flat_disc(4.5, target, layout);
      const auto n = static_cast<double>(d.mesh.vertices.size());
      EXPECT_NEAR(n / target, 1.0, 0.1) << to_string(layout) << " L" << level;
      EXPECT_GT(min_signed_area(d.mesh), 0.0);
      EXPECT_EQ(d.mesh.vertices[0], Vec3::Zero());
      double area = 0.0;
      for (const auto& t : d.mesh.triangles) {
        const Vec3 &a = d.mesh.vertices[t[0]], &b = d.mesh.vertices[t[1]],
                   &c = d.mesh.vertices[t[2]];
        area += 0.5 * (b - a).cross(c - a).z();
      }
      EXPECT_NEAR(area / (std::numbers::pi * 4.5 * 4.5), 1.0, 0.01);  // inscribed polygon
      uint32_t rim = 0;
      for (size_t v = 0; v < d.rim.size(); ++v) {
        if (!d.rim[v]) continue;
        ++rim;
        EXPECT_NEAR(d.mesh.vertices[v].head<2>().norm(), 4.5, 1e-12);
      }
      EXPECT_GT(rim, 40u);
    }
}

TEST(FlatDisc, IrregularLayoutIsDeterministicPerSeed) {
  const FlatDisc a = make_flat_disc(4.5, 1000, DiscLayout::Irregular, 7);
  const FlatDisc b = make_flat_disc(4.5, 1000, DiscLayout::Irregular, 7);
  const FlatDisc c = make_flat_disc(4.5, 1000, DiscLayout::Irregular, 8);
  EXPECT_EQ(a.mesh.vertices, b.mesh.vertices);
  EXPECT_NE(a.mesh.vertices, c.mesh.vertices);
  EXPECT_EQ(a.mesh.triangles, c.mesh.triangles);
}

MembraneProfileRow run(int level, DiscLayout layout, Pretension pretension,
                       SpringLaw law = SpringLaw::Linear, double core_radius = 0.0) {
  MembraneCase c;
  c.level = level, c.layout = layout, c.pretension = pretension, c.law = law;
  c.core_radius_mm = core_radius;
  const MembraneProfileRow r = membrane_profile(c);
  std::cout << to_string(layout) << " " << to_string(pretension) << " L" << level
            << " V=" << r.vertices << " T=" << r.tension_mn_mm << " (radial "
            << r.tension_radial_mn_mm << ", hoop " << r.tension_hoop_mn_mm
            << ") scaled err=" << r.max_scaled_error << " pointwise=" << r.max_rel_error << "\n";
  EXPECT_TRUE(r.converged);
  EXPECT_LE(r.residual_mn, 1e-8 * r.load_mn);
  return r;
}

// The accuracy studies below solve discs of up to 8k vertices to equilibrium: 24–37 s each under
// ASan (4–6 s in Release). What they check is accuracy, which is Release's to check; the same
// solve runs under ASan in CurvilinearPrestretchIsAnisotropicAndMisses and LoadIsInTheLinearRange.
constexpr const char* kAccuracyOnlyInRelease = "Release only: an accuracy study (see above)";

// The engine's pre-stretch on the near-equilateral layout at the default level (8k vertices):
// within 2 % (measured 1.79 % linear, 1.52 % quadratic; the error sits at the core edge and comes
// from the pre-stress not being uniform, see the next tests).
TEST(AnalyticMembrane, DefaultLevelIsotropicWithinTwoPercent) {
  if (test::kUnderAsan) GTEST_SKIP() << kAccuracyOnlyInRelease;
  for (SpringLaw law : {SpringLaw::Linear, SpringLaw::Quadratic}) {
    const MembraneProfileRow r = run(3, DiscLayout::Isotropic, Pretension::UniformPrestretch, law);
    EXPECT_GT(r.vertices, 7000u);
    EXPECT_LT(r.max_scaled_error, 0.02);
    EXPECT_LT(r.rms_rel_error, 0.02);  // measured 1.1 % and 1.7 %
  }
}

// With the pre-tension balanced by cotangent weights the network is the consistent membrane:
// every layout within 0.5 % (measured at level 3: 0.27 %, 0.11 %, 0.22 %; levels 2/3/2 here to
// keep the test short).
TEST(AnalyticMembrane, CotangentPretensionIsAccurateOnEveryLayout) {
  if (test::kUnderAsan) GTEST_SKIP() << kAccuracyOnlyInRelease;
  for (DiscLayout layout :
       {DiscLayout::Curvilinear, DiscLayout::Isotropic, DiscLayout::Irregular}) {
    const MembraneProfileRow r =
        run(layout == DiscLayout::Isotropic ? 3 : 2, layout, Pretension::Cotangent);
    EXPECT_NEAR(r.tension_mn_mm, 1.5 * 0.05 * 26.0, 1e-6);
    EXPECT_NEAR(r.tension_radial_mn_mm / r.tension_hoop_mn_mm, 1.0, 0.001);
    EXPECT_LT(r.max_scaled_error, 0.005);
    EXPECT_LT(r.max_rel_error, 0.005);
  }
}

// Why the rings-and-spokes capsule layout misses: a uniform pre-stretch leaves its hoop tension
// ~12 % above the radial one, and the formula assumes an isotropic T (measured error 18 %).
TEST(AnalyticMembrane, CurvilinearPrestretchIsAnisotropicAndMisses) {
  const MembraneProfileRow r = run(3, DiscLayout::Curvilinear, Pretension::UniformPrestretch);
  EXPECT_GT((r.tension_hoop_mn_mm - r.tension_radial_mn_mm) / r.tension_mn_mm, 0.08);
  EXPECT_GT(r.max_scaled_error, 0.10);
}

// Convergence order over levels 0–3 with a fixed core (R/8): measured 2.0 for the consistent
// membrane. (The engine's uniform pre-stretch stalls at a 1.3 % floor instead: the stress error
// does not shrink with h.)
TEST(AnalyticMembrane, ErrorFallsWithResolutionAtSecondOrder) {
  if (test::kUnderAsan) GTEST_SKIP() << kAccuracyOnlyInRelease;
  std::vector<double> h, err;
  for (int level = 0; level <= 3; ++level) {
    const MembraneProfileRow r =
        run(level, DiscLayout::Isotropic, Pretension::Cotangent, SpringLaw::Linear, 4.5 / 8);
    h.push_back(r.mean_edge_mm);
    err.push_back(r.max_scaled_error);
  }
  const OrderFit fit = fit_order(h, err);
  std::cout << "order " << fit.order << " over " << fit.points << " levels\n";
  EXPECT_EQ(fit.points, 4);
  EXPECT_GT(fit.order, 1.6);
  EXPECT_LT(err.back(), err.front() / 4);
}

// The load is small enough to be linear: halving it leaves the relative profile error unchanged.
TEST(AnalyticMembrane, LoadIsInTheLinearRange) {
  MembraneCase c;
  c.level = 1;
  const double e1 = membrane_profile(c).max_scaled_error;
  c.load_scale *= 0.5;
  const double e2 = membrane_profile(c).max_scaled_error;
  EXPECT_NEAR(e1, e2, 1e-4);
}

}  // namespace
}  // namespace phaco::reference
