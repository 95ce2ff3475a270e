#pragma once
// The sweep's figures per level (issue 17 item 7): CG iterations per stepped frame, physics refresh
// per cut, the cornea's worst cut frame, frame p50/p99/max on 1 and 2 threads, the 2-thread
// speed-up and the error against the reference; their charts; the issue-17 targets judged from
// them; and the reading of a missed target, made only of measured figures.
#include <filesystem>
#include <string>
#include <vector>

#include "perf/plot.hpp"
#include "perf/sweep/sweep_data.hpp"

namespace phaco::perf {

// CG iterations per stepped frame of the capsule: physics.capsule.cg_iterations_per_step_mean when
// the run reports it, else cg_iterations_total / frames_stepped. NaN without a capsule or steps.
double cg_iterations_per_step(const SweepPointResult& r);

// The 2-thread speed-up of the mean frame: one's mean / two's mean; NaN when either is missing.
double speedup(const SweepRow* one, const SweepRow* two);

struct LevelFigures {
  int level = 0;
  double elements = 0;  // the drill's own body (sweep_data.hpp)
  double cg_per_step = 0;
  double refresh_ms_mean = 0, refresh_ms_max = 0;  // capsule physics refresh per cut
  double refresh_springs = 0;        // springs a refresh patched (added + removed), mean per cut
  double refresh_ms_per_spring = 0;  // refresh_ms_mean / refresh_springs
  double cut_edit_ms_max = 0;        // the capsule cut's edit alone, worst
  double cornea_cut_max_ms = 0;      // the cornea_cut system's worst frame
  double p50_1 = 0, p99_1 = 0, max_1 = 0, mean_1 = 0;
  double p50_2 = 0, p99_2 = 0, max_2 = 0, mean_2 = 0;
  // The 2-thread speed-up of the mean frame: the mean over the level's paired runs (1-thread mean
  // / 2-thread mean of the same repetition) and its 95 % interval; one pair without repeats.
  double speedup = 0, speedup_lo = 0, speedup_hi = 0;
  int speedup_pairs = 0;
  double error_pct = 0;  // default methods, 1 thread, against the reference
};

// "1.42× [1.30–1.55], 5": the speed-up, its 95 % interval and its pairs ("1.42×" from one pair).
std::string speedup_text(const LevelFigures& g);

// The default methods' figures of a drill at each level 0..max_level that ran (NaN where a figure
// does not apply or a point is missing).
std::vector<LevelFigures> level_figures(const std::vector<SweepRow>& rows, const std::string& drill,
                                        int max_level);

// Power-law fit of a figure against elements over the levels lo..hi present.
PowerFit slope_over_levels(const std::vector<LevelFigures>& figures, double LevelFigures::*value,
                           int lo, int hi);

// The per-level tables, one per drill (markdown).
std::string level_tables_md(const std::vector<SweepRow>& rows,
                            const std::vector<std::string>& drills, int max_level);

struct LevelChartFiles {
  std::string cg, refresh, speedup;  // "" when not drawn (no data)
};
// sweep_cg_iterations.png (CG iterations per stepped frame against level), sweep_refresh.png
// (physics refresh per cut and the cornea's worst cut frame against elements, log-log, fitted
// slopes), sweep_speedup.png (2-thread speed-up against level with the 1.5× and 0.95× lines).
LevelChartFiles draw_level_charts(const std::vector<SweepRow>& rows,
                                  const std::filesystem::path& results_dir, int max_level);

// A drill's points on 1 thread (every variant and level but `skip_variant` and the scaling
// variants, finite error > 0) and, when there are at least two, those on the speed-against-error
// Pareto front, cheapest first.
struct DrillFront {
  std::vector<const SweepRow*> points;
  std::vector<const SweepRow*> front;
};
DrillFront drill_front(const std::vector<SweepRow>& rows, const std::string& drill,
                       const std::string& skip_variant);

// The Pareto front of a drill's points on 1 thread (every variant and level but `skip_variant`,
// finite error > 0), cheapest first, and whether the default methods at level 3 lie on it; names
// any integrator alternative on the front when the default is not (markdown paragraph).
std::string pareto_md(const std::vector<SweepRow>& rows, const std::string& drill,
                      const std::string& skip_variant);

// The default methods' outcome before issue 17 (perf/results/sweep_baseline.json): per drill and
// level, its accuracy metrics; the accuracy target compares against its error.
struct Baseline {
  std::string source;                    // where the metrics came from
  std::vector<SweepPointResult> points;  // config.drill, config.level, metrics
};
// Empty when the file is missing; an InputError naming it when it is not a baseline.
Baseline load_baseline(const std::filesystem::path& path);

// The issue-17 rows of the Targets table, judged from the points; `baseline` gives the accuracy
// target's "today's default", measured against the same reference as the rows' errors.
std::string issue17_targets_md(const std::vector<SweepRow>& rows,
                               const std::vector<std::string>& drills, int max_level,
                               const std::vector<SweepRow>& baseline_rows);

// Statements about each missed issue-17 target, each made of figures the points hold.
std::string why_missed_md(const std::vector<SweepRow>& rows, const std::vector<std::string>& drills,
                          int max_level, const std::vector<SweepRow>& baseline_rows);

// Thread scaling by dispatch, per drill at the levels the scaling variants ran: the 2-thread
// speed-up of the frame mean with the executor's Auto dispatch, with the flow graph every frame,
// and without the haptic thread, and the share of 2-thread frames Auto ran serially (markdown
// table; "" when no scaling variant ran).
std::string frame_dispatch_md(const std::vector<SweepRow>& rows,
                              const std::vector<std::string>& drills);

// Where the host put the vCPUs for a 2-thread point, from its round trips before and after the
// frames (SweepPointResult): near when both were under kNearRoundTripNs, apart when both were over
// kApartRoundTripNs, else moved (or not measured). Session 40's VM: 112–117 ns near, 440–480 apart.
inline constexpr double kNearRoundTripNs = 250.0, kApartRoundTripNs = 300.0;
enum class Placement { Near, Apart, Moved };
Placement placement_of(const SweepPointResult& r);

// The capsulorhexis speed-up pair by pair at each level: each pair's ratio, the steps the 2-thread
// run took on its team of two, and where the vCPUs were; then the pairs' median speed-up by
// placement (markdown; "" without pairs).
std::string speedup_pairs_md(const std::vector<SweepRow>& rows, int max_level);

}  // namespace phaco::perf
