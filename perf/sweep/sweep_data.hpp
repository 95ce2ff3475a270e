#pragma once
// The issue-9 sweep's points once measured, and what the study derives from them: each point's
// element count on the chart's axis, its accuracy error against its drill's reference point, and
// the checks a --quick run in CI enforces (perf/study_sweep.cpp).
#include <map>
#include <string>
#include <vector>

#include "perf/sweep/sweep_point.hpp"

namespace phaco::perf {

struct SweepRow {
  SweepPointResult r;
  double elements =
      0;  // the drill's own body: capsule vertices, lens tets at the start, cornea vertices
  double error_pct = 0;  // accuracy against the drill's reference point (NaN: a metric is missing)
  std::string error_detail;  // which metric is furthest off, e.g. "rhexis.diameter_mm 5.31 vs 5.33"
};

// The thread-scaling variants: the default methods without the haptic thread, with the
// executor's flow graph every frame, and the default again (repeats). They measure threads, not
// methods, so speed-against-accuracy fronts and method tables leave them out.
inline constexpr const char* kNoHapticsVariant = "no haptic thread";
inline constexpr const char* kGraphEveryFrameVariant = "flow graph every frame";
// The 2-thread speed-up's repetitions (issue 17 item 7): the default points of a level run again,
// "repeat 2", "repeat 3", ..., so that the speed-up is a mean of paired runs with its interval, not
// one pair (single runs of the same point differ by up to 40 % on this machine).
inline constexpr const char* kRepeatVariantPrefix = "repeat ";
inline bool is_repeat_variant(const std::string& v) {
  return v.rfind(kRepeatVariantPrefix, 0) == 0;
}
inline std::string repeat_variant(int repetition) {
  return kRepeatVariantPrefix + std::to_string(repetition);
}
inline bool is_scaling_variant(const std::string& v) {
  return v == kNoHapticsVariant || v == kGraphEveryFrameVariant || is_repeat_variant(v);
}

// The drill's own element count for the charts' x axis.
double drill_elements(const SweepPointResult& r);
const char* drill_elements_name(const std::string& drill);

// The metrics a drill's accuracy is judged on, each compared relative to the reference's value.
const std::vector<std::string>& accuracy_metrics(const std::string& drill);

// 100·max over accuracy_metrics of |m − m_ref| / |m_ref|; NaN when a metric is missing.
double accuracy_error_pct(const SweepPointResult& r, const SweepPointResult& reference,
                          std::string* detail = nullptr);

// One of a point's metrics (report.metrics[name]); NaN when absent or not a number.
double point_metric(const SweepPointResult& r, const std::string& name);

// A number from a point's physics summary (report.physics[body][key]); NaN when absent.
double physics_number(const SweepPointResult& r, const std::string& body, const std::string& key);
// The capsule's physics refresh per spring it patched (mean per cut over springs per cut), NaN
// where the run did not count the springs (points saved before the count).
double refresh_ms_per_patched_spring(const SweepPointResult& r);

// A system's cost summary field (e.g. &CostSummary::max_ms); NaN when the system did not run.
double system_cost(const SweepPointResult& r, const std::string& name, double CostSummary::*field);

// The finished point of a drill at (level, threads, variant); nullptr when none.
const SweepRow* find_row(const std::vector<SweepRow>& rows, const std::string& drill, int level,
                         int threads, const std::string& variant = "default");

// Frame-cost charts per drill, the per-system stacked cost, speed against accuracy, thread scaling,
// haptic period histograms and bytes per element: results_dir/sweep_*.png. Returns the file names
// written, for the markdown.
struct SweepChartFiles {
  std::map<std::string, std::string> frame_cost;  // per drill
  std::map<std::string, std::string> systems;     // per drill
  std::map<std::string, std::string> pareto;      // per drill with method variants
  std::string threads, haptics, memory;
};
SweepChartFiles draw_sweep_charts(const std::vector<SweepRow>& rows,
                                  const std::filesystem::path& results_dir);

}  // namespace phaco::perf
