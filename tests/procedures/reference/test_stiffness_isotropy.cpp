// Area-weighted against uniform springs on an irregular sheet (seed 000 §5.1's claim). Measured
// figures (level 1, 2k vertices, edge-length CV 0.20) are in docs/membrane_accuracy.md.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "procedures/reference/stiffness_isotropy.hpp"

namespace phaco::reference {
namespace {

IsotropyRow run(StiffnessWeighting w) {
  IsotropyCase c;
  c.layout = DiscLayout::Irregular;
  c.weighting = w;
  c.level = 1;
  const IsotropyRow r = stiffness_isotropy(c);
  std::cout << (w == StiffnessWeighting::AreaWeighted ? "area" : "uniform") << ": E mean "
            << r.youngs_mean << " (" << r.youngs_mean_error * 100 << " % vs E·h), spread "
            << r.youngs_spread * 100 << " %, Poisson " << r.poisson_ratio << "\n";
  EXPECT_EQ(r.directions.size(), 6u);
  EXPECT_LT(r.worst_residual_mn, 1e-11);
  EXPECT_LT(r.fit_residual, 1e-3);  // the response is linear in the strain
  return r;
}

TEST(StiffnessIsotropy, AreaWeightingGivesTheLatticePoissonRatio) {
  const IsotropyRow area = run(StiffnessWeighting::AreaWeighted);
  const IsotropyRow uniform = run(StiffnessWeighting::Uniform);
  // Both are isotropic to about 1 % on a statistically uniform irregular mesh (measured 1.1 %
  // and 0.8 %): the direction is not where they differ.
  EXPECT_LT(area.youngs_spread, 0.02);
  EXPECT_LT(uniform.youngs_spread, 0.02);
  // The central-force lattice's ν = 1/3 is kept by area weighting (measured 0.334) and lost by
  // uniform springs (0.264).
  EXPECT_NEAR(area.poisson_ratio, 1.0 / 3.0, 0.01);
  EXPECT_LT(uniform.poisson_ratio, 0.30);
  // Both are softer than E·h; area weighting more so (measured −12.2 % against −7.6 %): its
  // affine (upper-bound) stiffness is exactly E·h, and the irregular nodes' non-affine
  // relaxation takes the rest, while uniform springs start stiffer on a jittered mesh.
  EXPECT_GT(area.youngs_mean_error, -0.15);
  EXPECT_LT(area.youngs_mean_error, -0.09);
  EXPECT_GT(uniform.youngs_mean_error, -0.10);
  EXPECT_LT(uniform.youngs_mean_error, -0.05);
}

TEST(StiffnessIsotropy, NearEquilateralLatticeIsCloseToTheContinuum) {
  // Near-equilateral rings, area weighted: ν ≈ 1/3, E within 7 % of E·h, no direction preferred.
  IsotropyCase c;
  c.layout = DiscLayout::Isotropic;
  c.level = 1;
  const IsotropyRow r = stiffness_isotropy(c);
  EXPECT_NEAR(r.poisson_ratio, 1.0 / 3.0, 0.01);
  EXPECT_LT(r.youngs_spread, 0.01);
  EXPECT_NEAR(r.youngs_mean / 26.0, 1.0, 0.07);  // measured −5.9 %
}

}  // namespace
}  // namespace phaco::reference
