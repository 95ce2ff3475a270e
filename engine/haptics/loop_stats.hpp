#pragma once
// Timing statistics of the 1 kHz haptic loop (issue 6 item 1): the period between wake-ups, the
// wake-up lateness (wake time − deadline), the tick's own compute time, the time spun before each
// deadline, and overruns.
//
// Each distribution is a fixed histogram of microsecond bins, allocated once in the constructor,
// so recording never allocates, locks or calls the system:
//   [0, 2048) µs     1 µs bins (the period, 1000 µs, and lateness, tens of µs, live here)
//   [2048 µs, ~25 d) 64 bins per power of two (width 32 µs at 2 ms: ≤ 1.6 % relative)
// Exact count, sum, min and max are kept beside the bins. Percentiles are nearest-rank (the value
// with rank ⌈p·n⌉ of the sorted samples), reported as the middle of its bin clamped to the exact
// [min, max], so within half a bin width of the sorted-vector answer.
//
// Threads: one thread records (the loop thread); any thread may take a snapshot while it runs.
// Every counter is a relaxed atomic: the recorder is their only writer (plain load + store, no
// read-modify-write), and a snapshot taken mid-run is only approximately consistent across
// fields (one tick may be in the bins and not yet in the max, say), which is fine for monitoring.
// After the recorder thread is joined, a snapshot is exact.
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace phaco {

// One distribution's figures, microseconds.
struct DurationSummary {
  int64_t count = 0;
  double mean_us = 0;
  double min_us = 0;
  double p50_us = 0;
  double p99_us = 0;
  double p999_us = 0;
  double max_us = 0;
};

struct LoopStatsSnapshot {
  DurationSummary period;        // wake-up to wake-up of consecutive ticks
  DurationSummary lateness;      // wake-up time − deadline
  DurationSummary compute;       // the tick function's own time
  DurationSummary spin;          // time spun before the deadline (the wait's margin, its CPU cost)
  int64_t ticks = 0;             // ticks recorded (warm-up excluded)
  int64_t overruns = 0;          // ticks that woke after the following deadline had already passed
  int64_t missed_deadlines = 0;  // deadlines skipped by those overruns (no catch-up burst)
};

// A fixed-bin histogram of durations (ns in, µs out).
class DurationHistogram {
 public:
  static constexpr int64_t kFineBins = 2048;  // 1 µs each
  static constexpr int kSubBins = 64;         // per power of two beyond
  static constexpr int kMaxExponent = 41;     // beyond 2^41 µs everything lands in the last bin
  static constexpr int64_t kBins = kFineBins + (kMaxExponent - 11) * kSubBins;

  DurationHistogram();

  // Recorder thread only. Negative durations count in the first bin (min keeps the sign).
  void record(int64_t ns);
  // Not while a recorder is running.
  void reset();
  // Any thread.
  DurationSummary summary() const;
  // Adds `other`'s samples to this one's (bins, count, sum, min, max), as if this histogram had
  // recorded them too: the summary of a merge is the summary of one histogram fed both sample
  // sets, exactly (tests/engine/haptics/test_loop_stats.cpp). For a figure pooled over several
  // loops, e.g. the haptic period over a whole procedure's steps (apps/trainer). Thread: this
  // histogram's recorder, or any thread while none runs (it writes as record() does); `other` may
  // be recording meanwhile (its figures then approximate, as summary()'s are). Not with itself.
  void merge(const DurationHistogram& other);
  // The occupied bins as (low edge µs, width µs, count), in order: for histogram charts.
  struct Bin {
    int64_t low_us = 0, width_us = 1;
    uint64_t count = 0;
  };
  std::vector<Bin> occupied_bins() const;

  // Bin arithmetic, exposed for tests.
  static int64_t bin_of(int64_t us);
  static int64_t bin_low_us(int64_t bin);
  static int64_t bin_width_us(int64_t bin);

 private:
  std::unique_ptr<std::atomic<uint64_t>[]> bins_;
  std::atomic<int64_t> count_{0};
  std::atomic<int64_t> sum_ns_{0};
  std::atomic<int64_t> min_ns_{0};
  std::atomic<int64_t> max_ns_{0};
};

// The loop's three distributions and overrun counters.
class LoopStats {
 public:
  // period_ns < 0: no previous tick to measure a period from.
  void record_tick(int64_t period_ns, int64_t lateness_ns, int64_t compute_ns, int64_t spin_ns = 0);
  // One overrun that skipped `missed` deadlines.
  void record_overrun(int64_t missed);
  void reset();  // not while recording
  LoopStatsSnapshot snapshot() const;
  const DurationHistogram& period() const { return period_; }

 private:
  DurationHistogram period_, lateness_, compute_, spin_;
  std::atomic<int64_t> ticks_{0}, overruns_{0}, missed_{0};
};

}  // namespace phaco
