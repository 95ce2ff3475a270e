#include "engine/haptics/loop_stats.hpp"

#include <algorithm>
#include <bit>

namespace phaco {

namespace {

// The recorder is the only writer, so increments are a relaxed load and store: no locked
// read-modify-write instruction on the 1 kHz path.
void bump(std::atomic<int64_t>& a, int64_t by) {
  a.store(a.load(std::memory_order_relaxed) + by, std::memory_order_relaxed);
}

}  // namespace

DurationHistogram::DurationHistogram() : bins_(new std::atomic<uint64_t>[kBins]) {
  reset();
}

int64_t DurationHistogram::bin_of(int64_t us) {
  if (us < kFineBins) return us < 0 ? 0 : us;
  const int msb = 63 - std::countl_zero(static_cast<uint64_t>(us));  // ≥ 11
  if (msb >= kMaxExponent) return kBins - 1;
  const int shift = msb - 6;  // keep the top 7 bits: 64 + sub
  const int64_t sub = (us >> shift) - kSubBins;
  return kFineBins + static_cast<int64_t>(msb - 11) * kSubBins + sub;
}

int64_t DurationHistogram::bin_low_us(int64_t bin) {
  if (bin < kFineBins) return bin;
  const int64_t octave = (bin - kFineBins) / kSubBins;
  const int64_t sub = (bin - kFineBins) % kSubBins;
  return (kSubBins + sub) << (octave + 11 - 6);
}

int64_t DurationHistogram::bin_width_us(int64_t bin) {
  if (bin < kFineBins) return 1;
  return int64_t{1} << ((bin - kFineBins) / kSubBins + 11 - 6);
}

void DurationHistogram::record(int64_t ns) {
  // Floor to whole µs (negative values go to bin 0 through bin_of).
  auto& bin = bins_[static_cast<std::size_t>(bin_of(ns / 1000))];
  bin.store(bin.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  const int64_t n = count_.load(std::memory_order_relaxed);
  if (n == 0 || ns < min_ns_.load(std::memory_order_relaxed))
    min_ns_.store(ns, std::memory_order_relaxed);
  if (n == 0 || ns > max_ns_.load(std::memory_order_relaxed))
    max_ns_.store(ns, std::memory_order_relaxed);
  bump(sum_ns_, ns);
  count_.store(n + 1, std::memory_order_relaxed);
}

void DurationHistogram::reset() {
  for (int64_t i = 0; i < kBins; ++i) bins_[i].store(0, std::memory_order_relaxed);
  count_.store(0, std::memory_order_relaxed);
  sum_ns_.store(0, std::memory_order_relaxed);
  min_ns_.store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
}

DurationSummary DurationHistogram::summary() const {
  DurationSummary s;
  // Relaxed throughout: see the header (approximate while recording, exact after a join).
  const int64_t count = count_.load(std::memory_order_relaxed);
  if (count == 0) return s;
  const double min_us = static_cast<double>(min_ns_.load(std::memory_order_relaxed)) * 1e-3;
  const double max_us = static_cast<double>(max_ns_.load(std::memory_order_relaxed)) * 1e-3;
  s.count = count;
  s.mean_us = static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) * 1e-3 /
              static_cast<double>(count);
  s.min_us = min_us;
  s.max_us = max_us;

  // The bins' own total, so ranks are consistent with the bins even mid-run.
  uint64_t total = 0;
  for (int64_t i = 0; i < kBins; ++i) total += bins_[i].load(std::memory_order_relaxed);
  if (total == 0) return s;
  // Nearest rank ⌈p·n⌉ in integer per-mille arithmetic, so p99.9 of 1000 samples is rank 999.
  auto percentile = [&](uint64_t per_mille) {
    const uint64_t rank = std::max<uint64_t>(1, (per_mille * total + 999) / 1000);
    uint64_t seen = 0;
    for (int64_t i = 0; i < kBins; ++i) {
      seen += bins_[i].load(std::memory_order_relaxed);
      if (seen >= rank) {
        const double mid = static_cast<double>(bin_low_us(i)) + 0.5 * bin_width_us(i);
        return std::clamp(mid, min_us, max_us);
      }
    }
    return max_us;
  };
  s.p50_us = percentile(500);
  s.p99_us = percentile(990);
  s.p999_us = percentile(999);
  return s;
}

void DurationHistogram::merge(const DurationHistogram& other) {
  // Relaxed throughout: the same single writer as record() (see the header).
  const int64_t n_other = other.count_.load(std::memory_order_relaxed);
  if (n_other == 0) return;
  for (int64_t i = 0; i < kBins; ++i) {
    const uint64_t add = other.bins_[i].load(std::memory_order_relaxed);
    if (add > 0)
      bins_[i].store(bins_[i].load(std::memory_order_relaxed) + add, std::memory_order_relaxed);
  }
  const int64_t n = count_.load(std::memory_order_relaxed);
  const int64_t other_min = other.min_ns_.load(std::memory_order_relaxed);
  const int64_t other_max = other.max_ns_.load(std::memory_order_relaxed);
  if (n == 0 || other_min < min_ns_.load(std::memory_order_relaxed))
    min_ns_.store(other_min, std::memory_order_relaxed);
  if (n == 0 || other_max > max_ns_.load(std::memory_order_relaxed))
    max_ns_.store(other_max, std::memory_order_relaxed);
  bump(sum_ns_, other.sum_ns_.load(std::memory_order_relaxed));
  count_.store(n + n_other, std::memory_order_relaxed);
}

std::vector<DurationHistogram::Bin> DurationHistogram::occupied_bins() const {
  std::vector<Bin> out;
  for (int64_t i = 0; i < kBins; ++i) {
    const uint64_t n = bins_[i].load(std::memory_order_relaxed);
    if (n > 0) out.push_back({bin_low_us(i), bin_width_us(i), n});
  }
  return out;
}

void LoopStats::record_tick(int64_t period_ns, int64_t lateness_ns, int64_t compute_ns,
                            int64_t spin_ns) {
  if (period_ns >= 0) period_.record(period_ns);
  lateness_.record(lateness_ns);
  compute_.record(compute_ns);
  spin_.record(spin_ns);
  bump(ticks_, 1);
}

void LoopStats::record_overrun(int64_t missed) {
  bump(overruns_, 1);
  bump(missed_, missed);
}

void LoopStats::reset() {
  period_.reset();
  lateness_.reset();
  compute_.reset();
  spin_.reset();
  ticks_.store(0, std::memory_order_relaxed);
  overruns_.store(0, std::memory_order_relaxed);
  missed_.store(0, std::memory_order_relaxed);
}

LoopStatsSnapshot LoopStats::snapshot() const {
  LoopStatsSnapshot s;
  s.period = period_.summary();
  s.lateness = lateness_.summary();
  s.compute = compute_.summary();
  s.spin = spin_.summary();
  // Relaxed: statistics only.
  s.ticks = ticks_.load(std::memory_order_relaxed);
  s.overruns = overruns_.load(std::memory_order_relaxed);
  s.missed_deadlines = missed_.load(std::memory_order_relaxed);
  return s;
}

}  // namespace phaco
