#include "perf/cohorts/cohort.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "engine/io/track.hpp"

namespace phaco::perf {

namespace {

struct Wave {
  double amplitude_mm = 0, hz = 0, phase = 0;
  double at(double t) const {
    return amplitude_mm * std::sin(2 * std::numbers::pi * hz * t + phase);
  }
};

double mean_of(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

double sd_of(const std::vector<double>& v, double mean) {
  double s = 0;
  for (double x : v) s += (x - mean) * (x - mean);
  return v.size() > 1 ? std::sqrt(s / static_cast<double>(v.size() - 1)) : 0.0;
}

}  // namespace

CohortSpec expert_spec() {
  return {};
}

CohortSpec novice_spec() {
  return {.tremor_transverse_rms_mm = 0.059,
          .tremor_axial_rms_mm = 0.021,
          .time_scale_spread = 0.15,
          .offset_sd_mm = 0.15};
}

Scenario cohort_member(const Scenario& base, const CohortSpec& spec, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> hz(spec.tremor_min_hz, spec.tremor_max_hz);
  std::uniform_real_distribution<double> phase(0.0, 2 * std::numbers::pi);
  std::uniform_real_distribution<double> scale(1 - spec.time_scale_spread,
                                               1 + spec.time_scale_spread);
  std::normal_distribution<double> offset(0.0, spec.offset_sd_mm);
  Scenario out = base;
  const double k = scale(rng);
  out.duration_s = base.duration_s * k;
  // A sinusoid's RMS is its amplitude / √2; the transverse RMS is over two axes.
  const double transverse = spec.tremor_transverse_rms_mm,
               axial = spec.tremor_axial_rms_mm * std::sqrt(2.0);
  for (HandTrack& h : out.hands) {
    const Wave u{transverse, hz(rng), phase(rng)}, v{transverse, hz(rng), phase(rng)},
        w{axial, hz(rng), phase(rng)};
    const Vec3 shift(offset(rng), offset(rng), offset(rng));
    const std::vector<TrackSample> track = h.track;
    h.track.clear();
    const auto n = static_cast<int64_t>(std::ceil(out.duration_s / base.dt_s));
    for (int64_t f = 0; f <= n; ++f) {
      const double t = static_cast<double>(f) * base.dt_s;
      const ToolPose p = sample_track(track, t / k);
      const Vec3 shaft = p.quat.normalized() * Vec3::UnitZ();
      const Vec3 a = shaft.unitOrthogonal(), b = shaft.cross(a);
      TrackSample s;
      s.t = t;
      s.pos = p.pos + shift + u.at(t) * a + v.at(t) * b + w.at(t) * shaft;
      s.quat = p.quat;
      s.grip = p.grip;
      s.pedal = p.pedal;
      h.track.push_back(s);
    }
  }
  return out;
}

double roc_auc(const std::vector<double>& positives, const std::vector<double>& negatives) {
  if (positives.empty() || negatives.empty()) return std::nan("");
  double wins = 0;
  for (double p : positives)
    for (double q : negatives) wins += p > q ? 1.0 : p == q ? 0.5 : 0.0;
  return wins / (static_cast<double>(positives.size()) * static_cast<double>(negatives.size()));
}

double contrasting_groups_cutoff(const std::vector<double>& experts,
                                 const std::vector<double>& novices, double min_sd) {
  if (experts.empty() || novices.empty()) return std::nan("");
  const double m1 = mean_of(novices), m2 = mean_of(experts);
  const double s1 = std::max(sd_of(novices, m1), min_sd), s2 = std::max(sd_of(experts, m2), min_sd);
  const double lo = std::min(m1, m2), hi = std::max(m1, m2);
  // N(x; m1, s1) = N(x; m2, s2): a x² + b x + c = 0 after taking logs.
  const double a = 1 / (s1 * s1) - 1 / (s2 * s2);
  const double b = 2 * (m2 / (s2 * s2) - m1 / (s1 * s1));
  const double c = m1 * m1 / (s1 * s1) - m2 * m2 / (s2 * s2) + 2 * std::log(s1 / s2);
  std::vector<double> roots;
  if (std::abs(a) < 1e-12) {
    if (std::abs(b) > 1e-12) roots.push_back(-c / b);
  } else if (const double d = b * b - 4 * a * c; d >= 0) {
    roots.push_back((-b + std::sqrt(d)) / (2 * a));
    roots.push_back((-b - std::sqrt(d)) / (2 * a));
  }
  for (double r : roots)
    if (r >= lo && r <= hi) return r;
  return 0.5 * (m1 + m2);
}

}  // namespace phaco::perf
