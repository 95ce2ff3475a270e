#pragma once
// The sweep's plan (issue 9, issue 22 item 1): its options, the method alternatives each drill's
// scene can choose, and the points to run: a mesh warm-up per (drill, level, layout), then every
// level on each thread count, the thread-scaling variants, the alternatives at a few levels, and
// the capsulorhexis repeats that the 2-thread speed-up is averaged over.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "perf/studies.hpp"
#include "perf/sweep/sweep_point.hpp"

namespace phaco::perf {

struct Variant {
  std::string label;  // "key=value"
  std::string layout;
  std::map<std::string, std::string> methods;
  int max_level = 99;  // not above this level: the whole capsule's implicit step every frame
                       // (no active set) takes minutes per drill beyond the default level
  bool quick = true;   // also in --quick (CI): not the slow ones (20 s and more at level 1)
};

// The alternatives a drill's scene can choose (docs/ARCHITECTURE.md, `methods`); the others
// (force propagation, Horn vs polar, SPH cell order, Bullet) are measured on their own systems
// in the membrane and lens sections.
std::vector<Variant> variants_of(const std::string& drill);

// The sweep's own options (docs/perf_sweep.md, `phaco-perf sweep --help`).
struct SweepArgs {
  int max_level = 0;
  std::vector<std::string> drills = {"capsulorhexis", "phaco_sculpting", "corneal_incision"};
  bool replot = false;
  bool reference = false;        // make perf/results/sweep_reference.json instead of sweeping
  int reference_level = -1;      // --reference-level
  int reference_dt_divisor = 0;  // --reference-dt-divisor
  int speedup_reps = 0;          // --speedup-reps (0: the default, 5; --quick 1)
};
SweepArgs parse_sweep_args(const StudyOptions& options);

// The mesh cache: $PHACO_CACHE_DIR when set (CI shares the tests' cache), else the results' own.
std::filesystem::path sweep_cache_dir(const std::filesystem::path& results_dir);

// What a sweep ran and how: saved with its points (sweep_points.json) so that --replot redraws the
// same report.
struct SweepRun {
  std::string command, load;
  int max_level = 0;
  std::vector<std::string> drills;
  std::vector<int> threads, variant_levels;
  // The capsulorhexis default points at every level on 1 and 2 threads run this many times in all
  // (the first is the level's own point; the others are "repeat k" points at the plan's end).
  int speedup_reps = 1;
  std::vector<std::string> run_failures;  // points that did not run to their end
  bool replot = false;                    // the report is redrawn from saved points
};

struct SweepPlan {
  std::vector<SweepPointConfig> warm;    // mesh warm-ups, not measured
  std::vector<SweepPointConfig> points;  // measured, in this order
};
SweepPlan plan_sweep(const SweepRun& run, bool quick, const std::filesystem::path& scenarios,
                     const std::filesystem::path& cache);

// A point's identity across thread counts (the state hash check), and its name in messages.
std::string point_key(const SweepPointConfig& c);
std::string point_label(const SweepPointConfig& c);

}  // namespace phaco::perf
