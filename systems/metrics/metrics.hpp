#pragma once
// Performance figures of a drill run from its per-frame samples (seed 000 §6.4 and Fig. 11: "the
// average, standard deviation and the maximum value" of the contact force and of the tool tip's
// speed, with their distribution; seed 003 §IV.B: time, lens hits, regrasps). Free functions over
// plain numbers, with no knowledge of the scene: the scene's Metrics-phase system
// (procedures/scene/drill_metrics) feeds them.
//
//   RunningStats   Welford's one-pass mean and variance (population: Σ(x − x̄)² / n), min, max —
//                  stable for long runs, O(1) per sample, no allocation.
//   Histogram      fixed bins over [lo, hi); samples below lo count in the first bin, at or above
//                  hi in the last (the figure's tails stay visible, nothing is dropped).
//   Kinematics     a tool tip's path: path length Σ|p_k − p_{k−1}| and speed |Δp| / Δt per frame.
//   decimate       every series to at most N samples, evenly spaced in index, first and last kept.
//
// Reads: samples given by the caller. Writes: only its own structs. add()/add_position() neither
// allocate nor throw (hot path: once per frame per hand).
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "engine/core/math.hpp"

namespace phaco::metrics {

struct RunningStats {
  uint64_t count = 0;
  double mean = 0;
  double m2 = 0;  // Σ (x − mean)², updated by Welford's recurrence
  double min = 0, max = 0;

  void add(double x);
  double variance() const { return count ? m2 / static_cast<double>(count) : 0.0; }  // population
  double stddev() const;
};

struct Histogram {
  double lo = 0, hi = 1;
  std::vector<uint64_t> counts;  // bin k holds [lo + k·w, lo + (k+1)·w), w = (hi − lo) / bins

  double bin_width() const {
    return counts.empty() ? 0.0 : (hi - lo) / static_cast<double>(counts.size());
  }
  // Bin edges, bins + 1 values from lo to hi.
  std::vector<double> edges() const;
  uint64_t total() const;
};

// Throws std::invalid_argument unless bins > 0 and hi > lo (both finite).
Histogram make_histogram(double lo, double hi, uint32_t bins);
void add(Histogram& h, double x);
// A histogram of `values` over [0, max(values)] (a max of 0 gives [0, 1)) with `bins` bins, as seed
// 000 Fig. 11 draws speed and force: from zero to the largest sample.
Histogram histogram_from_zero(std::span<const double> values, uint32_t bins);

// A tool tip over a run, one position per frame.
struct Kinematics {
  double path_length_mm = 0;
  RunningStats speed_mm_s;  // per frame: |p_k − p_{k−1}| / dt
  Vec3 last = Vec3::Zero();
  bool started = false;
};

// Adds the tip position at the end of a frame of length dt_s (> 0); returns the frame's speed
// (mm/s; 0 for the first position, which only starts the path and adds no speed sample).
double add_position(Kinematics& k, const Vec3& p, double dt_s);

// Σ |p_k − p_{k−1}| of a polyline, mm.
double polyline_length(std::span<const Vec3> points);

// Indices of at most max_samples samples of an n-sample series, evenly spaced, the first and the
// last included; all of 0..n−1 when n ≤ max_samples. max_samples < 2 keeps the first (and, if
// max_samples is 0, nothing).
std::vector<size_t> decimation_indices(size_t n, size_t max_samples);

template <class T>
std::vector<T> decimate(std::span<const T> series, std::span<const size_t> indices) {
  std::vector<T> out;
  out.reserve(indices.size());
  for (size_t i : indices) out.push_back(series[i]);
  return out;
}

// The default cap on a report's series (the run report contract: ≤ 2000 samples).
inline constexpr size_t kMaxSeriesSamples = 2000;

}  // namespace phaco::metrics
