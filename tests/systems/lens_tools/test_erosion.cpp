// Phaco erosion by Russian roulette (seed 002 §6): deterministic draws, the removal rate the
// probability promises, nothing without ultrasound, nothing outside the cone.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "systems/lens_tools/erosion.hpp"
#include "tests/systems/lens_tools/cell_fixture.hpp"

namespace phaco::lens_tools {
namespace {

PhacoTip tip_down(double power = 1.0) {
  PhacoTip t;
  t.apex = Vec3(0.2, -0.1, 1.0);
  t.axis = Vec3(0, 0, -1);
  t.power = power;
  return t;
}

LensCells cloud(uint32_t n) {
  return test::box_cells(n, Vec3(-1.5, -1.5, -1.0), Vec3(1.5, 1.5, 2.5));
}

std::vector<uint32_t> run(LensCells& c, const PhacoTip& tip, const ErosionSettings& s,
                          uint64_t seed, uint64_t frame, double dt = 1.0 / 120) {
  ErosionScratch scratch;
  std::vector<uint32_t> removed;
  erode(cell_spans(c), tip, s, CounterRng(seed, 3), frame, dt, scratch, removed);
  return removed;
}

TEST(Erosion, WeightIsOneAtTheApexAndZeroAtTheThresholds) {
  const ErosionSettings s;
  EXPECT_DOUBLE_EQ(erosion_weight(0, 0, s), 1.0);
  EXPECT_DOUBLE_EQ(erosion_weight(s.reach_mm, 0, s), 0.0);
  EXPECT_DOUBLE_EQ(erosion_weight(0, s.half_angle_rad, s), 0.0);
  EXPECT_DOUBLE_EQ(erosion_weight(s.reach_mm * 1.01, 0, s), 0.0);
  EXPECT_DOUBLE_EQ(erosion_weight(0.5 * s.reach_mm, 0.5 * s.half_angle_rad, s), 0.25);
  EXPECT_GT(erosion_weight(0.2, 0.1, s), erosion_weight(0.3, 0.1, s));
  EXPECT_GT(erosion_weight(0.2, 0.1, s), erosion_weight(0.2, 0.2, s));
}

TEST(Erosion, TipFromPoseAimsOutOfTheShaftAndNeedsPedalThree) {
  ToolPose pose;
  pose.pos = Vec3(1, 2, 3);
  pose.quat = Quat(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()));
  pose.pedal = 3.0;
  const PhacoTip on = phaco_tip(pose, 0.7);
  EXPECT_TRUE(on.apex.isApprox(pose.pos));
  EXPECT_NEAR((on.axis - Vec3(0, 1, 0)).norm(), 0, 1e-12);
  EXPECT_DOUBLE_EQ(on.power, 0.7);
  pose.pedal = 2.99;
  EXPECT_DOUBLE_EQ(phaco_tip(pose, 0.7).power, 0.0);
}

TEST(Erosion, SameSeedSameRemovalsForAnyThreadCountAndFramesDiffer) {
  LensCells c = cloud(40000);
  const ErosionSettings s;
  std::vector<uint32_t> ref;
  test::with_threads(1, [&] { ref = run(c, tip_down(), s, 7, 5); });
  ASSERT_GT(ref.size(), 20u);
  EXPECT_TRUE(std::is_sorted(ref.begin(), ref.end()));
  EXPECT_EQ(std::adjacent_find(ref.begin(), ref.end()), ref.end());
  for (int threads : {2, 4}) {
    std::vector<uint32_t> again;
    test::with_threads(threads, [&] { again = run(c, tip_down(), s, 7, 5); });
    EXPECT_EQ(again, ref) << threads << " threads";
  }
  EXPECT_NE(run(c, tip_down(), s, 7, 6), ref);
  EXPECT_NE(run(c, tip_down(), s, 8, 5), ref);
}

TEST(Erosion, RemovedFractionMatchesTheProbability) {
  // Every cell at the same point: one probability p, a binomial count per frame.
  const uint32_t n = 20000;
  LensCells c = test::box_cells(n, Vec3(0.2, -0.1, 0.6), Vec3(0.2, -0.1, 0.6), 1, 5e-9f, 0.4f);
  const PhacoTip tip = tip_down(0.5);
  ErosionSettings s;
  s.rate_per_s = 30;
  const double dt = 1.0 / 60;
  const double p = removal_probability(Vec3f(0.2f, -0.1f, 0.6f), 0.4f, tip, s, dt);
  // p = k · power · (1 − h) · w · dt with w = (1 − 0.4/1) · 1
  EXPECT_NEAR(p, 30 * 0.5 * 0.6 * 0.6 * dt, 1e-6);
  double total = 0;
  const int frames = 10;
  for (int f = 0; f < frames; ++f) total += static_cast<double>(run(c, tip, s, 21, f, dt).size());
  const double trials = double(n) * frames;
  const double sigma = std::sqrt(trials * p * (1 - p));
  EXPECT_NEAR(total, trials * p, 5 * sigma);

  // Cells spread over the cone: the count matches Σ p within 5 σ.
  LensCells spread = cloud(60000);
  ErosionSettings fast;
  fast.rate_per_s = 400;
  double expected = 0, var = 0;
  for (uint32_t i = 0; i < spread.size(); ++i) {
    const double pi = removal_probability(Vec3f(spread.x[i], spread.y[i], spread.z[i]), 0.0f,
                                          tip_down(), fast, dt);
    expected += pi, var += pi * (1 - pi);
  }
  double got = 0;
  for (int f = 0; f < frames; ++f)
    got += static_cast<double>(run(spread, tip_down(), fast, 4, f, dt).size());
  EXPECT_GT(expected, 100.0);
  EXPECT_NEAR(got, frames * expected, 5 * std::sqrt(frames * var));
}

TEST(Erosion, NothingAtPowerZeroOrForHardOrDeadCells) {
  LensCells c = cloud(20000);
  ErosionSettings s;
  s.rate_per_s = 1e6;  // p = 1 wherever w > 0
  EXPECT_TRUE(run(c, tip_down(0.0), s, 7, 1).empty());
  ASSERT_FALSE(run(c, tip_down(1.0), s, 7, 1).empty());
  LensCells hard = c;
  std::fill(hard.hardness.begin(), hard.hardness.end(), 1.0f);
  EXPECT_TRUE(run(hard, tip_down(1.0), s, 7, 1).empty());
  LensCells dead = c;
  std::fill(dead.alive.begin(), dead.alive.end(), uint8_t{0});
  EXPECT_TRUE(run(dead, tip_down(1.0), s, 7, 1).empty());
}

TEST(Erosion, NothingOutsideTheCone) {
  LensCells c = cloud(60000);
  ErosionSettings s;
  s.rate_per_s = 1e9;  // p clamps to 1 wherever w > 1e-6
  s.half_angle_rad = 0.5;
  s.reach_mm = 0.8;
  const PhacoTip tip = tip_down();
  const auto removed = run(c, tip, s, 9, 2);
  std::vector<uint8_t> is_removed(c.size(), 0);
  for (uint32_t id : removed) is_removed[id] = 1;
  uint32_t inside_strictly = 0;
  for (uint32_t i = 0; i < c.size(); ++i) {
    const Vec3 d = Vec3(c.x[i], c.y[i], c.z[i]) - tip.apex;
    const double dist = d.norm();
    const double angle = dist > 0 ? std::acos(std::clamp(d.dot(tip.axis) / dist, -1.0, 1.0)) : 0.0;
    const bool outside = dist > s.reach_mm + 1e-5 || angle > s.half_angle_rad + 1e-5;
    const bool well_inside = dist < s.reach_mm - 1e-3 && angle < s.half_angle_rad - 1e-3;
    if (outside) {
      EXPECT_FALSE(is_removed[i]) << "cell " << i << " d " << dist << " angle " << angle;
    }
    if (well_inside) {
      EXPECT_TRUE(is_removed[i]) << "cell " << i;
    }
    inside_strictly += well_inside;
  }
  EXPECT_GT(inside_strictly, 100u);
}

}  // namespace
}  // namespace phaco::lens_tools
