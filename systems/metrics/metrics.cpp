#include "systems/metrics/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace phaco::metrics {

void RunningStats::add(double x) {
  ++count;
  const double delta = x - mean;
  mean += delta / static_cast<double>(count);
  m2 += delta * (x - mean);  // Welford: uses the old and the new mean, no cancellation
  if (count == 1) {
    min = max = x;
  } else {
    min = std::min(min, x);
    max = std::max(max, x);
  }
}

double RunningStats::stddev() const {
  return std::sqrt(std::max(0.0, variance()));
}

std::vector<double> Histogram::edges() const {
  std::vector<double> e(counts.size() + 1);
  const double w = bin_width();
  for (size_t k = 0; k < e.size(); ++k) e[k] = lo + w * static_cast<double>(k);
  if (!counts.empty()) e.back() = hi;  // exact, not lo + bins·w rounded
  return e;
}

uint64_t Histogram::total() const {
  uint64_t n = 0;
  for (uint64_t c : counts) n += c;
  return n;
}

Histogram make_histogram(double lo, double hi, uint32_t bins) {
  if (bins == 0 || !std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo))
    throw std::invalid_argument("histogram needs bins > 0 and finite hi > lo");
  Histogram h;
  h.lo = lo, h.hi = hi;
  h.counts.assign(bins, 0);
  return h;
}

void add(Histogram& h, double x) {
  if (h.counts.empty() || std::isnan(x)) return;
  const double f = (x - h.lo) / (h.hi - h.lo) * static_cast<double>(h.counts.size());
  // Clamp before the cast: out-of-range doubles to integers are undefined.
  const double k = std::clamp(std::floor(f), 0.0, static_cast<double>(h.counts.size() - 1));
  ++h.counts[static_cast<size_t>(k)];
}

Histogram histogram_from_zero(std::span<const double> values, uint32_t bins) {
  double top = 0;
  for (double v : values) top = std::max(top, v);
  Histogram h = make_histogram(0.0, top > 0 ? top : 1.0, bins);
  for (double v : values) add(h, v);
  return h;
}

double add_position(Kinematics& k, const Vec3& p, double dt_s) {
  if (!k.started) {
    k.started = true;
    k.last = p;
    return 0.0;
  }
  const double step = (p - k.last).norm();
  k.last = p;
  k.path_length_mm += step;
  const double speed = dt_s > 0 ? step / dt_s : 0.0;
  k.speed_mm_s.add(speed);
  return speed;
}

double polyline_length(std::span<const Vec3> points) {
  double length = 0;
  for (size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  return length;
}

std::vector<size_t> decimation_indices(size_t n, size_t max_samples) {
  std::vector<size_t> idx;
  if (n == 0 || max_samples == 0) return idx;
  if (n <= max_samples) {
    idx.resize(n);
    for (size_t i = 0; i < n; ++i) idx[i] = i;
    return idx;
  }
  if (max_samples == 1) return {0};
  idx.resize(max_samples);
  // i·(n−1)/(m−1) rounded: evenly spaced, strictly increasing (n > m), ends exact. Integer
  // arithmetic so the choice is the same on every machine.
  for (size_t i = 0; i < max_samples; ++i)
    idx[i] = (i * (n - 1) + (max_samples - 1) / 2) / (max_samples - 1);
  return idx;
}

}  // namespace phaco::metrics
