// Force propagation against the static equilibrium for a grasp on a pre-stretched, pinned disc
// (level 1, 2k vertices, 26 layers from the centre to the rim). Figures in
// docs/membrane_accuracy.md.
#include <gtest/gtest.h>

#include <iostream>

#include "procedures/reference/propagation_error.hpp"

namespace phaco::reference {
namespace {

TEST(PropagationError, FallsWithLayersAndReachesEquilibriumWhenItCoversThePatch) {
  PropagationCase c;
  c.level = 1;
  c.layers = {0, 4, 16, 32};
  c.sweeps = {64};
  c.relaxation = 1.8;
  c.tolerance_mm = 1e-6;
  const PropagationStudy s = propagation_error_study(c);
  ASSERT_EQ(s.rows.size(), 4u);
  EXPECT_LT(s.reference_residual_mn, 1e-10);
  EXPECT_GT(s.grasped, 4u);
  for (const PropagationErrorRow& r : s.rows)
    std::cout << "layers " << r.max_layers << " reached " << r.layers_reached << " touched "
              << r.nodes_touched << " updates " << r.node_updates << " rms " << r.rms_rel << " max "
              << r.max_rel << "\n";
  // Error falls as the front widens (measured rms 0.205, 0.180, 0.083, 0.0006 of the grasp move).
  for (size_t k = 1; k < s.rows.size(); ++k) EXPECT_LT(s.rows[k].rms_rel, s.rows[k - 1].rms_rel);
  EXPECT_GT(s.rows[0].rms_rel, 0.1);    // doing nothing is far off
  EXPECT_LT(s.rows[3].rms_rel, 0.005);  // covering the disc converges
  EXPECT_LT(s.rows[3].max_rel, 0.01);
  EXPECT_EQ(s.rows[3].nodes_touched, s.rows[3].vertices);
  EXPECT_LT(s.rows[1].nodes_touched, s.rows[1].vertices / 10);  // 4 layers: a small patch
}

}  // namespace
}  // namespace phaco::reference
