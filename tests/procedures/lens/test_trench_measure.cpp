// The trench measures against bands of known width, depth and angle.
#include <gtest/gtest.h>

#include <cmath>

#include "procedures/lens/trench_measure.hpp"

namespace phaco::lens {
namespace {

const NucleusShape kNucleus{3.29, 1.26, -1.89};

// A band of removed cubes (0.05 mm) along `angle_deg` through the origin: `width` across,
// `length` along, from the nucleus's anterior surface down to depth `depth` below it.
void add_band(std::vector<RemovedElement>& out, double angle_deg, double width, double length,
              double depth, uint32_t stroke, Vec3 offset = Vec3::Zero()) {
  const double h = 0.05, a = angle_deg * M_PI / 180.0;
  const Vec3 u(std::cos(a), std::sin(a), 0), n(-std::sin(a), std::cos(a), 0);
  for (double s = -length / 2 + h / 2; s < length / 2; s += h) {
    for (double w = -width / 2 + h / 2; w < width / 2; w += h) {
      const Vec3 p = offset + s * u + w * n;
      const double top = nucleus_anterior_z(kNucleus, p.x(), p.y());
      for (double z = top - h / 2; z > top - depth; z -= h)
        out.push_back({Vec3(p.x(), p.y(), z), h * h * h, stroke});
    }
  }
}

TEST(TrenchMeasure, TwoPerpendicularBandsGiveTheirWidthsDepthsAndAngle) {
  std::vector<RemovedElement> removed;
  add_band(removed, 0, 1.6, 5.0, 2.0, 0);
  add_band(removed, 90, 1.4, 4.0, 1.5, 1);
  const TrenchReport r = measure_trenches(removed, kNucleus);
  ASSERT_EQ(r.trenches.size(), 2u);
  EXPECT_NEAR(r.crossing_angle_deg, 90.0, 0.5);
  EXPECT_NEAR(r.trenches[0].width_mm, 1.6, 0.1);
  EXPECT_NEAR(r.trenches[1].width_mm, 1.4, 0.1);
  EXPECT_NEAR(r.trenches[0].length_mm, 5.0, 0.3);
  // The deepest 2 % of cube centres lies within a cube of the band's floor.
  const double thickness = kNucleus.anterior_mm - kNucleus.posterior_mm;
  EXPECT_NEAR(r.trenches[0].depth_mm, 2.0, 0.1);
  EXPECT_NEAR(r.trenches[0].depth_fraction, 2.0 / thickness, 0.1 / thickness);
  EXPECT_NEAR(r.trenches[1].depth_mm, 1.5, 0.1);
  EXPECT_NEAR(std::abs(r.trenches[0].axis.x()), 1.0, 1e-3);
}

TEST(TrenchMeasure, PassesAlongOneLineAreOneTrenchAndAnObliqueOneIsAnother) {
  std::vector<RemovedElement> removed;
  add_band(removed, 0, 1.0, 5.0, 1.0, 0);
  add_band(removed, 2, 1.0, 4.0, 1.8, 1, Vec3(0.0, 0.2, 0));  // deepening pass, slightly off
  add_band(removed, 45, 1.0, 3.0, 1.0, 2);
  const TrenchReport r = measure_trenches(removed, kNucleus);
  ASSERT_EQ(r.trenches.size(), 2u);
  EXPECT_EQ(r.trenches[0].strokes.size(), 2u);
  EXPECT_NEAR(r.crossing_angle_deg, 45.0, 3.0);
}

TEST(TrenchMeasure, TouchesBelowTheMinimumVolumeAreNotTrenches) {
  std::vector<RemovedElement> removed;
  add_band(removed, 30, 1.5, 5.0, 1.0, 0);
  removed.push_back({Vec3(2, 2, 0.5), 1e-4, 7});
  const TrenchReport r = measure_trenches(removed, kNucleus);
  ASSERT_EQ(r.trenches.size(), 1u);
  EXPECT_EQ(r.crossing_angle_deg, 0.0);
  EXPECT_GT(r.volume_removed_mm3,
            r.trenches[0].volume_mm3);  // the touch still counts as removed volume
}

TEST(TrenchMeasure, RejectsANucleusWithoutThickness) {
  EXPECT_THROW(measure_trenches({}, NucleusShape{3.0, 0.0, -1.0}), std::invalid_argument);
  EXPECT_TRUE(measure_trenches({}, kNucleus).trenches.empty());
}

}  // namespace
}  // namespace phaco::lens
