// LoopStats / DurationHistogram: bin arithmetic, and percentiles of synthetic data against the
// nearest-rank answer of a sorted vector.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <thread>
#include <vector>

#include "engine/haptics/loop_stats.hpp"

namespace phaco {
namespace {

using H = DurationHistogram;

TEST(DurationHistogram, BinsCoverEveryMicrosecondOnceAndInOrder) {
  int64_t previous = -1;
  for (int64_t us = 0; us < 300'000; us += (us < 5000 ? 1 : 7)) {
    const int64_t b = H::bin_of(us);
    ASSERT_GE(b, previous) << us;
    ASSERT_LE(H::bin_low_us(b), us) << us;
    ASSERT_LT(us, H::bin_low_us(b) + H::bin_width_us(b)) << us;
    previous = b;
  }
  EXPECT_EQ(H::bin_width_us(H::bin_of(1999)), 1);  // 1 µs resolution up to ~2 ms
  EXPECT_EQ(H::bin_of(2047) + 1, H::bin_of(2048));
  EXPECT_LE(H::bin_width_us(H::bin_of(10'000)), 10'000 / 64);  // ≤ 1.6 % beyond
  EXPECT_EQ(H::bin_of(int64_t{1} << 50), H::kBins - 1);        // clamped, not out of range
}

// The reference: nearest rank ⌈p·n⌉ of the sorted samples, p in per mille.
double reference_us(const std::vector<int64_t>& sorted, uint64_t per_mille) {
  const uint64_t n = sorted.size();
  const uint64_t rank = std::max<uint64_t>(1, (per_mille * n + 999) / 1000);
  return static_cast<double>(sorted[rank - 1]) * 1e-3;
}

void expect_close_to_reference(const DurationSummary& s, std::vector<int64_t> samples) {
  std::sort(samples.begin(), samples.end());
  ASSERT_EQ(s.count, static_cast<int64_t>(samples.size()));
  EXPECT_DOUBLE_EQ(s.min_us, static_cast<double>(samples.front()) * 1e-3);
  EXPECT_DOUBLE_EQ(s.max_us, static_cast<double>(samples.back()) * 1e-3);
  const double sum =
      static_cast<double>(std::accumulate(samples.begin(), samples.end(), int64_t{0}));
  EXPECT_NEAR(s.mean_us, sum * 1e-3 / static_cast<double>(samples.size()), 1e-6);
  for (auto [per_mille, got] : {std::pair{500u, s.p50_us}, {990u, s.p99_us}, {999u, s.p999_us}}) {
    const double ref = reference_us(samples, per_mille);
    // Within half the width of the bin holding the reference value.
    const double half_width =
        0.5 * static_cast<double>(H::bin_width_us(H::bin_of(static_cast<int64_t>(ref))));
    EXPECT_NEAR(got, ref, half_width + 1e-9) << "per mille " << per_mille;
  }
}

TEST(DurationHistogram, PercentilesMatchSortedReference) {
  std::mt19937_64 rng(6);
  // A loop-like period: 1 ms ± a few µs, a tail of preempted ticks at 1.1–9 ms.
  std::normal_distribution<double> jitter(1'000'000.0, 4'000.0);
  std::uniform_real_distribution<double> tail(1'100'000.0, 9'000'000.0);
  std::vector<int64_t> period;
  for (int i = 0; i < 20'000; ++i)
    period.push_back(static_cast<int64_t>(i % 97 == 0 ? tail(rng) : jitter(rng)));
  // Lateness-like: exponential, tens of µs, plus a few ms-long outliers.
  std::exponential_distribution<double> late(1.0 / 30'000.0);
  std::vector<int64_t> lateness;
  for (int i = 0; i < 12'345; ++i)
    lateness.push_back(static_cast<int64_t>(i % 1000 == 7 ? 4'000'000.0 + i : late(rng)));

  for (const auto* samples : {&period, &lateness}) {
    H h;
    for (int64_t ns : *samples) h.record(ns);
    expect_close_to_reference(h.summary(), *samples);
  }
}

TEST(DurationHistogram, SmallSetsAndReset) {
  H h;
  EXPECT_EQ(h.summary().count, 0);
  h.record(1'234'567);  // one sample: every percentile is it
  DurationSummary s = h.summary();
  EXPECT_EQ(s.count, 1);
  EXPECT_DOUBLE_EQ(s.p50_us, 1234.567);
  EXPECT_DOUBLE_EQ(s.p999_us, 1234.567);
  expect_close_to_reference(s, {1'234'567});
  h.reset();
  EXPECT_EQ(h.summary().count, 0);
  expect_close_to_reference((h.record(5'000), h.record(7'000), h.summary()), {5'000, 7'000});
}

TEST(DurationHistogram, OccupiedBinsHoldEverySampleInOrder) {
  H h;
  EXPECT_TRUE(h.occupied_bins().empty());
  for (int64_t ns : {999'400, 999'900, 1'000'200, 1'000'700, 1'000'700, 3'000'000}) h.record(ns);
  const auto bins = h.occupied_bins();
  ASSERT_EQ(bins.size(), 3u);  // 1 µs bins 999 and 1000, then a 32 µs bin holding 3000
  uint64_t total = 0;
  for (size_t i = 0; i < bins.size(); ++i) {
    total += bins[i].count;
    if (i > 0) {
      EXPECT_GE(bins[i].low_us, bins[i - 1].low_us + bins[i - 1].width_us);
    }
  }
  EXPECT_EQ(total, 6u);
  EXPECT_EQ(bins[0].low_us, 999);
  EXPECT_EQ(bins[0].count, 2u);
  EXPECT_EQ(bins[1].low_us, 1000);
  EXPECT_EQ(bins[1].count, 3u);
  EXPECT_EQ(bins[2].count, 1u);
  EXPECT_LE(bins[2].low_us, 3000);
  EXPECT_GT(bins[2].low_us + bins[2].width_us, 3000);
}

void expect_same_summary(const DurationSummary& got, const DurationSummary& want) {
  EXPECT_EQ(got.count, want.count);
  EXPECT_DOUBLE_EQ(got.mean_us, want.mean_us);
  EXPECT_DOUBLE_EQ(got.min_us, want.min_us);
  EXPECT_DOUBLE_EQ(got.p50_us, want.p50_us);
  EXPECT_DOUBLE_EQ(got.p99_us, want.p99_us);
  EXPECT_DOUBLE_EQ(got.p999_us, want.p999_us);
  EXPECT_DOUBLE_EQ(got.max_us, want.max_us);
}

// The procedure's pooled haptic period (apps/trainer --stats): merging two loops' histograms
// gives what one histogram fed both sample sets gives, and a mixture's p99 is neither part's.
TEST(DurationHistogram, MergeEqualsOneHistogramFedBothSampleSets) {
  std::mt19937_64 rng(20);
  // A quiet step (1 ms ± a few µs, a rare long tick) and a loaded one (later wake-ups, a tail to
  // 40 µs late, a core taken away for 6 ms): different shapes, so a wrong merge shows.
  std::normal_distribution<double> quiet(1'000'000, 3'000), loaded(1'004'000, 9'000);
  std::uniform_real_distribution<double> u(0, 1);
  H a, b, both;
  for (int i = 0; i < 20'000; ++i) {
    const auto ns = static_cast<int64_t>(u(rng) < 0.003 ? 1'300'000 : quiet(rng));
    a.record(ns), both.record(ns);
  }
  for (int i = 0; i < 7'000; ++i) {
    const auto ns = static_cast<int64_t>(u(rng) < 0.02 ? 1'040'000 : loaded(rng));
    b.record(ns), both.record(ns);
  }
  b.record(6'000'000), both.record(6'000'000);
  b.record(-2'000), both.record(-2'000);  // a negative duration keeps its sign in min

  H pooled;
  pooled.merge(a);
  pooled.merge(b);
  expect_same_summary(pooled.summary(), both.summary());
  // In the other order, into a histogram that already holds samples, and with an empty one (a
  // step without ticks) between: the order does not matter.
  H into_b;
  into_b.merge(b);
  into_b.merge(H{});
  into_b.merge(a);
  expect_same_summary(into_b.summary(), both.summary());
  // Bin for bin, too.
  const auto pb = pooled.occupied_bins(), bb = both.occupied_bins();
  ASSERT_EQ(pb.size(), bb.size());
  for (size_t i = 0; i < pb.size(); ++i) {
    EXPECT_EQ(pb[i].low_us, bb[i].low_us) << i;
    EXPECT_EQ(pb[i].count, bb[i].count) << i;
  }
  // A mixture's quantile lies between its parts' and here differs from both: the pooled p99 is
  // not the worst part's p99 (the figure --stats wrote over a procedure before stop 36).
  const double pa = a.summary().p99_us, pbq = b.summary().p99_us, pp = pooled.summary().p99_us;
  EXPECT_GE(pp, std::min(pa, pbq));
  EXPECT_LE(pp, std::max(pa, pbq));
  EXPECT_NE(pp, std::max(pa, pbq));
  EXPECT_EQ(pooled.summary().count, 27'002);
}

TEST(LoopStats, CountsTicksOverrunsAndMissedDeadlines) {
  LoopStats stats;
  stats.record_tick(-1, 20'000, 50'000);  // first tick: no period
  stats.record_tick(1'000'000, 30'000, 60'000);
  stats.record_tick(3'500'000, 2'530'000, 60'000);
  stats.record_overrun(2);
  LoopStatsSnapshot s = stats.snapshot();
  EXPECT_EQ(s.ticks, 3);
  EXPECT_EQ(s.period.count, 2);
  EXPECT_EQ(s.lateness.count, 3);
  EXPECT_EQ(s.compute.count, 3);
  EXPECT_EQ(s.overruns, 1);
  EXPECT_EQ(s.missed_deadlines, 2);
  EXPECT_DOUBLE_EQ(s.period.max_us, 3500.0);
  EXPECT_NEAR(s.compute.mean_us, 170.0 / 3.0, 1e-9);
  stats.reset();
  EXPECT_EQ(stats.snapshot().ticks, 0);
  EXPECT_EQ(stats.snapshot().overruns, 0);
}

TEST(LoopStats, SnapshotWhileRecordingIsExactAfterJoin) {
  LoopStats stats;
  constexpr int kTicks = 50'000;
  std::thread recorder([&] {
    for (int i = 0; i < kTicks; ++i) stats.record_tick(1'000'000 + i % 50, i % 40'000, 1'000);
  });
  int64_t last_seen = 0;
  bool went_backwards = false;
  for (int i = 0; i < 200; ++i) {
    const int64_t now = stats.snapshot().ticks;
    went_backwards |= now < last_seen;
    last_seen = now;
  }
  recorder.join();
  EXPECT_FALSE(went_backwards);
  const LoopStatsSnapshot s = stats.snapshot();
  EXPECT_EQ(s.ticks, kTicks);
  EXPECT_EQ(s.period.count, kTicks);
  EXPECT_DOUBLE_EQ(s.period.max_us, 1000.049);
}

}  // namespace
}  // namespace phaco
