// phaco-perf sweep (issue 9): the whole trainer under the harness. Each drill's scripted expert is
// run to its end at every resolution level (0..8: up to 256k capsule vertices and 1.6M lens
// tets), on 1 and 2 simulation threads, with the 1 kHz haptic thread ticking beside the frames;
// and again at a few levels with each method alternative the scene can choose (integrators,
// spring stiffness, capsule layout, active set, spring law; broadphase, narrowphase and lens
// model). Each point runs in its own process (perf/sweep/sweep_point.hpp). Accuracy is the
// drill's scored outcome against its converged reference (perf/sweep/sweep_reference.hpp).
//
// The jobs are in perf/sweep/: the plan (sweep_plan), the checks a CI run relies on
// (sweep_checks), the raw figures (sweep_figures), and the section (sweep_report, sweep_levels,
// sweep_charts). This file runs them in order.
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"
#include "perf/sweep/sweep_checks.hpp"
#include "perf/sweep/sweep_figures.hpp"
#include "perf/sweep/sweep_plan.hpp"
#include "perf/sweep/sweep_reference.hpp"
#include "perf/sweep/sweep_report.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

// The run's own settings from the options: levels, drills, thread counts, the alternatives'
// levels, and the command that reproduces it.
SweepRun new_run(const SweepArgs& args, const StudyOptions& options) {
  SweepRun run;
  run.max_level = args.max_level;
  run.drills = args.drills;
  run.load = load_note();
  run.threads = {1, 2};
  if (const int hw = int(std::thread::hardware_concurrency()); hw > 2) run.threads.push_back(hw);
  run.variant_levels = options.quick ? std::vector<int>{1} : std::vector<int>{1, 3, 5};
  run.speedup_reps = args.speedup_reps > 0 ? args.speedup_reps : options.quick ? 1 : 5;
  run.command =
      std::string("phaco-perf sweep") + (options.quick ? " --quick" : "") +
      (run.max_level != (options.quick ? 3 : eye::kMaxLevel)
           ? " --max-level " + std::to_string(run.max_level)
           : "") +
      (args.speedup_reps > 0 ? " --speedup-reps " + std::to_string(run.speedup_reps) : "");
  return run;
}

// Runs the plan, each point in its own process; a point that fails is recorded, not fatal.
std::vector<SweepRow> measure(SweepRun& run, const StudyOptions& options, const fs::path& dir,
                              Progress& progress) {
  const fs::path cache = sweep_cache_dir(dir);
  const fs::path work = dir / ".sweep";
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  // The plan: a warm-up per (drill, level, layout) builds the meshes into the cache, so that no
  // measured point pays for (or keeps the memory of) mesh generation.
  const SweepPlan plan = plan_sweep(run, options.quick, eye::data_dir() / "scenarios", cache);
  progress = Progress(int(plan.warm.size() + plan.points.size()) + 1);
  for (const auto& w : plan.warm) {
    progress.step("sweep: meshes for " + w.drill + " level " + std::to_string(w.level) +
                  (w.capsule_layout.empty() ? "" : " " + w.capsule_layout));
    const SweepPointResult r = run_sweep_point_isolated(w, exe, work);
    if (!r.ok) run.run_failures.push_back("building " + point_label(w) + ": " + r.error);
  }
  std::vector<SweepRow> rows;
  for (const auto& c : plan.points) {
    progress.step("sweep: " + point_label(c));
    SweepRow row;
    row.r = run_sweep_point_isolated(c, exe, work);
    if (!row.r.ok) run.run_failures.push_back(point_label(c) + ": " + row.r.error);
    row.elements = drill_elements(row.r);
    rows.push_back(std::move(row));
  }
  return rows;
}

}  // namespace

void run_sweep(const StudyOptions& options) {
  const SweepArgs args = parse_sweep_args(options);
  const fs::path dir = options.out_dir / "results";
  if (args.reference) {
    make_sweep_reference({.drills = args.drills,
                          .level = args.reference_level,
                          .dt_divisor = args.reference_dt_divisor,
                          .results_dir = dir,
                          .data_dir = eye::data_dir(),
                          .cache_dir = sweep_cache_dir(dir),
                          .exe = fs::read_symlink("/proc/self/exe")});
    return;
  }
  // --replot redraws the report from the points a sweep saved (sweep_points.json): new readings
  // and charts without measuring again; the figures stay those of the run that measured them.
  Progress progress(1);
  std::vector<SweepRow> rows;
  SweepRun run;
  if (args.replot) {
    run = read_saved_sweep(dir, rows);
  } else {
    run = new_run(args, options);
    rows = measure(run, options, dir, progress);
  }
  progress.step("sweep: accuracy, checks, charts");

  // Accuracy: every point against its drill's converged reference where one is current; the
  // checks' bounds against the run's own finest level (convergence, as CI has always checked).
  const SweepAccuracy accuracy = assess_accuracy(rows, run.drills, dir, run.max_level);
  std::vector<std::string> failures = run.run_failures;
  check_points(rows, accuracy, run.drills, run.max_level, failures);
  write_sweep_figures(rows, run, dir);
  write_section(dir, "sweep", sweep_section_md(rows, run, accuracy, failures, dir));
  progress.finish();

  if (!failures.empty()) {
    std::string all_failures;
    for (const auto& e : failures) all_failures += "\n  " + e;
    throw CheckFailed("sweep: " + std::to_string(failures.size()) + " check(s) failed (also in " +
                      (dir / "sweep.md").string() + "):" + all_failures);
  }
}

}  // namespace phaco::perf
