// systems/metrics against hand-computed references: a straight path, a circle (2πr), the mean and
// standard deviation of known data, fixed-bin histograms, even decimation.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "systems/metrics/metrics.hpp"

namespace phaco::metrics {
namespace {

TEST(RunningStats, MeanStdMinMaxOfKnownData) {
  // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, population variance 4, std 2.
  RunningStats s;
  for (double x : {2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0}) s.add(x);
  EXPECT_EQ(s.count, 8u);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_NEAR(s.variance(), 4.0, 1e-12);
  EXPECT_NEAR(s.stddev(), 2.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.min, 2.0);
  EXPECT_DOUBLE_EQ(s.max, 9.0);
}

TEST(RunningStats, StableForALargeOffset) {
  // A naive Σx² − n·x̄² loses everything here; Welford keeps the spread of ±1 about 1e9.
  RunningStats s;
  for (int i = 0; i < 1000; ++i) s.add(1e9 + (i % 2 ? 1.0 : -1.0));
  EXPECT_NEAR(s.mean, 1e9, 1e-6);
  EXPECT_NEAR(s.stddev(), 1.0, 1e-6);
}

TEST(RunningStats, EmptyIsZero) {
  RunningStats s;
  EXPECT_EQ(s.stddev(), 0.0);
  EXPECT_EQ(s.mean, 0.0);
}

TEST(Kinematics, StraightPathAtConstantSpeed) {
  // 1 mm/s along a diagonal for 10 frames of 0.1 s: 1 mm, every speed sample 1 mm/s.
  Kinematics k;
  const Vec3 dir = Vec3(1, 2, 2) / 3.0;
  EXPECT_EQ(add_position(k, Vec3(1, 1, 1), 0.1), 0.0);
  for (int f = 1; f <= 10; ++f)
    EXPECT_NEAR(add_position(k, Vec3(1, 1, 1) + 0.1 * f * dir, 0.1), 1.0, 1e-12);
  EXPECT_NEAR(k.path_length_mm, 1.0, 1e-12);
  EXPECT_EQ(k.speed_mm_s.count, 10u);
  EXPECT_NEAR(k.speed_mm_s.mean, 1.0, 1e-12);
  EXPECT_NEAR(k.speed_mm_s.stddev(), 0.0, 1e-9);
  EXPECT_NEAR(k.speed_mm_s.max, 1.0, 1e-12);
}

TEST(Kinematics, CircleGivesTwoPiRWithinTheChordError) {
  // A circle of radius 2.5 mm in N chords: length 2N·r·sin(π/N) → 2πr; speed per frame the chord /
  // dt.
  const double r = 2.5, dt = 0.01;
  const int n = 3600;
  Kinematics k;
  std::vector<Vec3> pts;
  for (int i = 0; i <= n; ++i) {
    const double a = 2 * std::numbers::pi * i / n;
    pts.push_back({r * std::cos(a), r * std::sin(a), 1.8});
    add_position(k, pts.back(), dt);
  }
  const double chords = 2.0 * n * r * std::sin(std::numbers::pi / n);
  EXPECT_NEAR(k.path_length_mm, chords, 1e-9);
  EXPECT_NEAR(k.path_length_mm, 2 * std::numbers::pi * r, 2e-6);
  EXPECT_NEAR(polyline_length(pts), k.path_length_mm, 1e-9);
  EXPECT_NEAR(k.speed_mm_s.mean, chords / n / dt, 1e-9);
  EXPECT_NEAR(k.speed_mm_s.stddev(), 0.0, 1e-6);
}

TEST(Histogram, FixedBinsWithTailsInTheEndBins) {
  Histogram h = make_histogram(0.0, 10.0, 5);
  for (double x : {-1.0, 0.0, 1.99, 2.0, 5.0, 9.99, 10.0, 50.0}) add(h, x);
  EXPECT_EQ(h.counts, (std::vector<uint64_t>{3, 1, 1, 0, 3}));
  EXPECT_EQ(h.total(), 8u);
  const auto e = h.edges();
  ASSERT_EQ(e.size(), 6u);
  EXPECT_DOUBLE_EQ(e[0], 0.0);
  EXPECT_DOUBLE_EQ(e[2], 4.0);
  EXPECT_DOUBLE_EQ(e[5], 10.0);
  EXPECT_THROW(make_histogram(1.0, 1.0, 4), std::invalid_argument);
  EXPECT_THROW(make_histogram(0.0, 1.0, 0), std::invalid_argument);
}

TEST(Histogram, FromZeroSpansToTheLargestSample) {
  const std::vector<double> v = {0.0, 1.0, 2.0, 3.0, 4.0};
  const Histogram h = histogram_from_zero(v, 4);
  EXPECT_DOUBLE_EQ(h.hi, 4.0);
  EXPECT_EQ(h.counts, (std::vector<uint64_t>{1, 1, 1, 2}));  // the maximum lands in the last bin
  const Histogram zero = histogram_from_zero(std::vector<double>{0.0, 0.0}, 3);
  EXPECT_DOUBLE_EQ(zero.hi, 1.0);
  EXPECT_EQ(zero.counts[0], 2u);
}

TEST(Decimation, EvenEndsKeptAndCapped) {
  EXPECT_EQ(decimation_indices(5, 10), (std::vector<size_t>{0, 1, 2, 3, 4}));
  EXPECT_EQ(decimation_indices(11, 6), (std::vector<size_t>{0, 2, 4, 6, 8, 10}));
  EXPECT_TRUE(decimation_indices(0, 10).empty());
  EXPECT_TRUE(decimation_indices(10, 0).empty());
  EXPECT_EQ(decimation_indices(10, 1), (std::vector<size_t>{0}));
  for (size_t n : {2001u, 6841u, 100000u}) {
    const auto idx = decimation_indices(n, kMaxSeriesSamples);
    ASSERT_EQ(idx.size(), kMaxSeriesSamples);
    EXPECT_EQ(idx.front(), 0u);
    EXPECT_EQ(idx.back(), n - 1);
    for (size_t i = 1; i < idx.size(); ++i) {
      ASSERT_GT(idx[i], idx[i - 1]);
      // Evenly spaced: every gap within one of (n−1)/(m−1).
      const double gap = double(n - 1) / double(kMaxSeriesSamples - 1);
      EXPECT_LE(std::abs(double(idx[i] - idx[i - 1]) - gap), 1.0);
    }
  }
  const std::vector<int> series = {10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20};
  const auto idx = decimation_indices(series.size(), 3);
  EXPECT_EQ(decimate<int>(series, idx), (std::vector<int>{10, 15, 20}));
}

}  // namespace
}  // namespace phaco::metrics
