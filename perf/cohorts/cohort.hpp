#pragma once
// Cohorts of scripted trainees for the score-validation study (issue 20 item 4; phaco-perf
// cohorts): each member is a scripted run — the drill's expert, or one of its novices — replayed
// with what differs between two people doing the same thing:
//   tremor   physiological hand tremor added to the tip: a sinusoid per axis at 8–12 Hz (random
//            frequency and phase per member and axis), RMS transverse to the shaft 35 µm for
//            experts and 59 µm for novices, axial 13 and 21 µm (FBG-sensorised forceps on porcine
//            eyes; the figures);
//   timing   the whole track played faster or slower by a factor drawn per member;
//   technique the whole track shifted by a small random offset (where the hands work).
// The tremor needs samples faster than it: the track is resampled at the scenario's step.
#include <cstdint>
#include <vector>

#include "engine/io/scenario.hpp"

namespace phaco::perf {

struct CohortSpec {
  double tremor_transverse_rms_mm = 0.035;  // |transverse| RMS over both axes
  double tremor_axial_rms_mm = 0.013;
  double tremor_min_hz = 8, tremor_max_hz = 12;
  double time_scale_spread = 0.05;  // the factor is uniform in [1 − s, 1 + s]
  double offset_sd_mm = 0.05;       // per axis, normal
};

CohortSpec expert_spec();  // 35 / 13 µm, ±5 % time, 0.05 mm
CohortSpec novice_spec();  // 59 / 21 µm, ±15 % time, 0.15 mm

// `base` replayed by member `seed` of a cohort of `spec` (deterministic in the seed).
Scenario cohort_member(const Scenario& base, const CohortSpec& spec, uint64_t seed);

// The probability that a random positive scores above a random negative (ties count half): the
// area under the ROC curve, by the Mann–Whitney statistic. NaN if either group is empty.
double roc_auc(const std::vector<double>& positives, const std::vector<double>& negatives);

// The contrasting-groups pass/fail score (Thomsen 2015): where the normal densities fitted to the
// two groups cross between their means (standard deviations floored at `min_sd`, since a scripted
// group may score alike); the midpoint of the means when they do not cross there. NaN if a group
// is empty.
double contrasting_groups_cutoff(const std::vector<double>& experts,
                                 const std::vector<double>& novices, double min_sd = 1.0);

}  // namespace phaco::perf
