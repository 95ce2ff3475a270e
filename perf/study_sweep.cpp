// One file for now: the sweep's plan and its run (options, reference and per-level figures are
// already in perf/sweep/); splitting the rest by job is issue 22's first item.
// phaco-perf sweep (issue 9): the whole trainer under the harness. Each drill's scripted expert is
// run to its end at every resolution level (0..8: up to 256k capsule vertices and 1.6M lens
// tets), on 1 and 2 simulation threads, with the 1 kHz haptic thread ticking beside the frames;
// and again at a few levels with each method alternative the scene can choose (integrators,
// spring stiffness, capsule layout, active set, spring law; broadphase, narrowphase and lens
// model). Each point runs in its own process (perf/sweep/sweep_point.hpp). Accuracy is the
// drill's scored outcome against the finest level's (the converged reference, DESIGN.md §8).
//
// The issue's targets are judged here from the points, and the checks a CI run relies on are
// enforced: every point runs to its end, 1 and 2 threads give the same state hash, the default
// methods stay within their accuracy bounds and never diverge.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"
#include "perf/sweep/sweep_data.hpp"
#include "perf/sweep/sweep_levels.hpp"
#include "perf/sweep/sweep_reference.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

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
std::vector<Variant> variants_of(const std::string& drill) {
  std::vector<Variant> v;
  auto method = [&](const std::string& k, const std::string& value) {
    v.push_back({k + "=" + value, "", {{k, value}}});
  };
  if (drill == "capsulorhexis") {
    for (const char* i :
         {"implicit_predictor", "semi_implicit_001", "symplectic_euler", "explicit_euler", "xpbd"})
      method("capsule.integrator", i);
    method("capsule.stiffness", "uniform");
    method("capsule.spring_law", "quadratic");
    method("capsule.active_set", "off");
    v.back().max_level = 3;
    v.back().quick = false;
    v.push_back({"eye.capsule_layout=isotropic", "isotropic", {}});
  } else if (drill == "phaco_sculpting") {
    method("lens.broadphase", "dbvt");
    method("lens.narrowphase", "exact_gjk");
    method("lens.narrowphase", "exact_mpr");
    method("lens.model", "fragments");
    v.back().quick = false;
  }
  return v;
}

// Accuracy bounds the default methods must keep from level `from` up (checked in CI by --quick):
// the error of the drill's scored outcome against the reference level, percent.
struct Bound {
  int from_level;
  double max_error_pct;
};
Bound bound_of(const std::string& drill) {
  if (drill == "capsulorhexis") return {2, 10.0};
  if (drill == "phaco_sculpting") return {1, 15.0};
  return {1, 10.0};
}

// Points of the default methods without the haptic thread beside them (thread scaling).
constexpr const char* kNoHaptics = kNoHapticsVariant;
// ... and with the executor's flow graph every frame instead of its Auto dispatch.
constexpr const char* kGraphEveryFrame = kGraphEveryFrameVariant;

std::string key(const SweepPointConfig& c) {
  return c.drill + "/" + std::to_string(c.level) + "/" + c.variant;
}

std::string label(const SweepPointConfig& c) {
  return c.drill + " level " + std::to_string(c.level) + ", " + std::to_string(c.threads) +
         " thread" + (c.threads > 1 ? "s" : "") + (c.variant == "default" ? "" : ", " + c.variant);
}

std::string f(const char* format, double v) {
  return fmt_or_dash(format, v);
}

std::string met(bool ok) {
  return ok ? "**met**" : "**missed**";
}

// Why a target is missed: statements made only of the points' figures (which system has the
// slowest frame, iterations, the refresh's share, speed-ups, haptic periods), never a cause the
// figures do not show.
std::string why_targets_missed(const std::vector<SweepRow>& rows,
                               const std::vector<std::string>& drills, int max_level,
                               const std::vector<SweepRow>& baseline) {
  std::string md = "### Why a target is missed: what the figures show\n\n";
  md += why_missed_md(rows, drills, max_level, baseline);
  // The haptic period where it missed (the default level or the largest, 2 threads, long enough).
  for (const auto& row : rows) {
    const auto& r = row.r;
    if (!r.ok || r.config.variant != "default" || r.config.threads != 2 || r.haptic_ticks < 1000)
      continue;
    if (r.config.level != 3 && r.config.level != max_level) continue;
    if (r.period_p99_us <= 1020 && r.period_max_us <= 1500 && r.haptic_allocations <= 0) continue;
    md += "- **Haptic period**, " + r.config.drill + " level " + std::to_string(r.config.level) +
          ", 2 threads: p99 " + f("%.0f", r.period_p99_us) + " us, p99.9 " +
          f("%.0f", r.period_p999_us) + " us, max " + f("%.0f", r.period_max_us) + " us over " +
          fmt("%.0f", r.haptic_ticks) + " ticks, " + fmt("%.0f", r.haptic_overruns) +
          " overruns; SCHED_FIFO " +
          (r.haptic_fifo ? "granted" : "refused (" + r.haptic_detail + ")") +
          "; allocations on the haptic thread: " +
          (r.haptic_allocations < 0 ? std::string("not countable in this build")
                                    : fmt("%.0f", r.haptic_allocations)) +
          "; the frame's max in the same run " + f("%.1f", r.frame.max_ms) + " ms.\n";
  }
  // Sculpting at 1M tets and 60 Hz: the slowest system's share where the p99 misses.
  for (int l = max_level; l >= 0; --l) {
    const SweepRow* big = find_row(rows, "phaco_sculpting", l, 2);
    if (!big) continue;
    if (big->elements >= 1e6 && big->r.frame.p99_ms > 1000.0 / 60) {
      const auto& r = big->r;
      md += "- **Sculpting at level " + std::to_string(l) + "**: frame p99 " +
            f("%.1f", r.frame.p99_ms) + " ms; lens_sculpt p99 " +
            f("%.1f", system_cost(r, "lens_sculpt", &CostSummary::p99_ms)) + " ms.\n";
    }
    break;
  }
  return md + "\n";
}

// A committed results file: the out dir's, else the source tree's perf/results (a sweep into
// another --out-dir, e.g. CI's quick run, still measures against the committed reference).
fs::path results_file(const fs::path& dir, const char* name) {
  if (fs::exists(dir / name)) return dir / name;
  return fs::path(PHACO_SOURCE_DIR) / "perf" / "results" / name;
}

struct SweepAccuracy {
  std::map<std::string, AccuracyReference> references;  // what each drill's error_pct is against
  std::map<std::string, const SweepRow*> finest;  // the default methods' finest point per drill
  std::vector<SweepRow> baseline;  // the default before issue 17, against the same references
  std::string baseline_source;
};

// Sets every row's error against its drill's reference: the converged one of
// sweep_reference.json when its key matches today's inputs, else (labelled) the default methods
// at the finest level. The baseline's errors are taken against the same references.
SweepAccuracy assess_accuracy(std::vector<SweepRow>& rows, const std::vector<std::string>& drills,
                              const fs::path& dir, int finest_level) {
  SweepAccuracy a;
  for (const auto& row : rows)
    if (row.r.ok && row.r.config.variant == "default" && row.r.config.threads == 1 &&
        row.r.config.level == finest_level)
      a.finest[row.r.config.drill] = &row;
  const auto file = load_reference_file(results_file(dir, "sweep_reference.json"));
  for (const std::string& drill : drills) {
    std::string current;
    if (file && file->drills.count(drill))
      current =
          reference_key(file->drills.at(drill).recipe, reference_inputs(eye::data_dir(), drill));
    const auto it = a.finest.find(drill);
    a.references[drill] = choose_reference(drill, file ? &*file : nullptr, current,
                                           it == a.finest.end() ? nullptr : it->second);
  }
  measure_accuracy(rows, a.references);
  const Baseline b = load_baseline(results_file(dir, "sweep_baseline.json"));
  a.baseline_source = b.source;
  for (const auto& p : b.points) a.baseline.push_back(SweepRow{.r = p});
  measure_accuracy(a.baseline, a.references);
  return a;
}

// The sweep's own options (docs/perf_sweep.md, `phaco-perf sweep --help`).
struct SweepArgs {
  int max_level = 0;
  std::vector<std::string> drills = {"capsulorhexis", "phaco_sculpting", "corneal_incision"};
  bool replot = false;
  bool reference = false;        // make perf/results/sweep_reference.json instead of sweeping
  int reference_level = -1;      // --reference-level
  int reference_dt_divisor = 0;  // --reference-dt-divisor
};

SweepArgs parse_sweep_args(const StudyOptions& options) {
  SweepArgs a;
  a.max_level = options.quick ? 3 : eye::kMaxLevel;
  bool drills_given = false;
  auto number = [&](size_t& i, const char* what, int lo, int hi) {
    const int v = std::stoi(options.extra[++i]);
    if (v < lo || v > hi)
      throw InputError(std::string("sweep: ") + what + " out of " + std::to_string(lo) + ".." +
                       std::to_string(hi));
    return v;
  };
  for (size_t i = 0; i < options.extra.size(); ++i) {
    const std::string& o = options.extra[i];
    const bool has_value = i + 1 < options.extra.size();
    if (o == "--replot") {
      a.replot = true;
    } else if (o == "--reference") {
      a.reference = true;
    } else if (o == "--reference-level" && has_value) {
      a.reference_level = number(i, "--reference-level", 0, eye::kMaxLevel);
    } else if (o == "--reference-dt-divisor" && has_value) {
      a.reference_dt_divisor = number(i, "--reference-dt-divisor", 1, 64);
    } else if (o == "--max-level" && has_value) {
      a.max_level = number(i, "--max-level", 1, eye::kMaxLevel);
    } else if (o == "--drill" && has_value) {
      const std::string d = options.extra[++i];
      if (d != "capsulorhexis" && d != "phaco_sculpting" && d != "corneal_incision")
        throw InputError(
            "sweep: --drill expects capsulorhexis, phaco_sculpting or corneal_incision, got '" + d +
            "'");
      if (!drills_given) a.drills.clear(), drills_given = true;
      if (std::find(a.drills.begin(), a.drills.end(), d) == a.drills.end()) a.drills.push_back(d);
    } else {
      throw InputError("sweep: unknown option '" + o + "'");
    }
  }
  if ((a.reference_level >= 0 || a.reference_dt_divisor > 0) && !a.reference)
    throw InputError("sweep: --reference-level and --reference-dt-divisor go with --reference");
  return a;
}

// The mesh cache: $PHACO_CACHE_DIR when set (CI shares the tests' cache), else the results' own.
fs::path sweep_cache_dir(const fs::path& results_dir) {
  const char* env_cache = std::getenv("PHACO_CACHE_DIR");
  return env_cache && *env_cache ? fs::path(env_cache) : results_dir / ".mesh-cache";
}

}  // namespace

void run_sweep(const StudyOptions& options) {
  const SweepArgs args = parse_sweep_args(options);
  if (args.reference) {
    const fs::path dir = options.out_dir / "results";
    make_sweep_reference({.drills = args.drills,
                          .level = args.reference_level,
                          .dt_divisor = args.reference_dt_divisor,
                          .results_dir = dir,
                          .data_dir = eye::data_dir(),
                          .cache_dir = sweep_cache_dir(dir),
                          .exe = fs::read_symlink("/proc/self/exe")});
    return;
  }
  int max_level = args.max_level;
  std::vector<std::string> drills = args.drills;
  const bool replot = args.replot;
  std::string load = load_note();
  const fs::path dir = options.out_dir / "results";
  const fs::path cache = sweep_cache_dir(dir);
  const fs::path work = dir / ".sweep";
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const fs::path scenarios = eye::data_dir() / "scenarios";

  std::vector<int> threads = {1, 2};
  if (const int hw = int(std::thread::hardware_concurrency()); hw > 2) threads.push_back(hw);
  std::vector<int> levels;
  for (int l = 0; l <= max_level; ++l) levels.push_back(l);
  std::vector<int> variant_levels = options.quick ? std::vector<int>{1} : std::vector<int>{1, 3, 5};
  std::string cmd = std::string("phaco-perf sweep") + (options.quick ? " --quick" : "") +
                    (max_level != (options.quick ? 3 : eye::kMaxLevel)
                         ? " --max-level " + std::to_string(max_level)
                         : "");
  std::vector<std::string> failures;
  std::vector<SweepRow> rows;
  Progress progress(1);
  if (replot) {
    // The report redrawn from the points a sweep saved (sweep_points.json): new readings and charts
    // without measuring again. The figures stay those of the run that measured them.
    std::ifstream in(dir / "sweep_points.json");
    if (!in)
      throw InputError("sweep --replot: no " + (dir / "sweep_points.json").string() +
                       " to redraw from");
    nlohmann::json saved;
    try {
      saved = nlohmann::json::parse(in);
      cmd = saved.at("command").get<std::string>();
      load = saved.at("load").get<std::string>();
      max_level = saved.at("max_level");
      drills = saved.at("drills").get<std::vector<std::string>>();
      variant_levels = saved.at("variant_levels").get<std::vector<int>>();
      threads = saved.at("threads").get<std::vector<int>>();
      failures = saved.at("run_failures").get<std::vector<std::string>>();
      for (const auto& j : saved.at("points")) {
        SweepRow row;
        row.r = result_from_json(j);
        row.elements = drill_elements(row.r);
        rows.push_back(std::move(row));
      }
    } catch (const nlohmann::json::exception& e) {
      throw InputError("sweep --replot: " + (dir / "sweep_points.json").string() + ": " + e.what());
    }
  }
  const int reference_level = max_level;

  if (!replot) {
    // The plan: a warm-up per (drill, level, layout) builds the meshes into the cache, so that no
    // measured point pays for (or keeps the memory of) mesh generation.
    std::vector<SweepPointConfig> warm, plan;
    for (const std::string& drill : drills) {
      const fs::path scenario = scenarios / (drill + "_expert.json");
      for (int level : levels) {
        SweepPointConfig w{.drill = drill,
                           .scenario = scenario,
                           .level = level,
                           .warm_only = true,
                           .cache_dir = cache};
        warm.push_back(w);
        for (int t : threads) {
          SweepPointConfig c{.drill = drill,
                             .scenario = scenario,
                             .level = level,
                             .threads = t,
                             .cache_dir = cache};
          plan.push_back(c);
        }
      }
      // Thread scaling without the haptic thread, at the default level and the largest: how much
      // of the 2-thread figure the haptic thread takes.
      std::vector<int> scaling_levels = {std::min(3, max_level)};
      if (max_level > 3) scaling_levels.push_back(max_level);
      for (int level : scaling_levels) {
        for (int t : threads) {
          SweepPointConfig c{.drill = drill,
                             .scenario = scenario,
                             .level = level,
                             .threads = t,
                             .variant = kNoHaptics,
                             .haptics = false,
                             .cache_dir = cache};
          plan.push_back(c);
          c.variant = kGraphEveryFrame;
          c.haptics = true;
          c.graph_every_frame = true;
          plan.push_back(c);
        }
      }
      for (const Variant& v : variants_of(drill)) {
        for (int level : variant_levels) {
          if (level > max_level || level > v.max_level || (options.quick && !v.quick)) continue;
          if (!v.layout.empty()) {
            SweepPointConfig w{.drill = drill,
                               .scenario = scenario,
                               .level = level,
                               .capsule_layout = v.layout,
                               .warm_only = true,
                               .cache_dir = cache};
            warm.push_back(w);
          }
          SweepPointConfig c{.drill = drill,
                             .scenario = scenario,
                             .level = level,
                             .threads = 1,
                             .capsule_layout = v.layout,
                             .methods = v.methods,
                             .variant = v.label,
                             .cache_dir = cache};
          plan.push_back(c);
        }
      }
    }

    progress = Progress(int(warm.size() + plan.size()) + 1);
    for (const auto& w : warm) {
      progress.step("sweep: meshes for " + w.drill + " level " + std::to_string(w.level) +
                    (w.capsule_layout.empty() ? "" : " " + w.capsule_layout));
      const SweepPointResult r = run_sweep_point_isolated(w, exe, work);
      if (!r.ok) failures.push_back("building " + label(w) + ": " + r.error);
    }
    for (const auto& c : plan) {
      progress.step("sweep: " + label(c));
      SweepRow row;
      row.r = run_sweep_point_isolated(c, exe, work);
      if (!row.r.ok) failures.push_back(label(c) + ": " + row.r.error);
      row.elements = drill_elements(row.r);
      rows.push_back(std::move(row));
    }
  }
  progress.step("sweep: accuracy, checks, charts");
  const std::vector<std::string> run_failures = failures;  // saved with the points

  // Accuracy: every point against its drill's converged reference where one is current; the
  // checks' bounds against the run's own finest level (convergence, as CI has always checked).
  const SweepAccuracy accuracy = assess_accuracy(rows, drills, dir, reference_level);
  const auto& reference = accuracy.finest;

  // The checks (a --quick run in CI enforces them; so does every full run).
  std::map<std::string, std::string> hash_of;
  for (const auto& row : rows) {
    if (!row.r.ok) continue;
    const SweepPointConfig& c = row.r.config;
    auto [it, fresh] = hash_of.emplace(key(c), row.r.state_hash);
    if (!fresh && it->second != row.r.state_hash)
      failures.push_back(label(c) + ": state hash " + row.r.state_hash +
                         " differs from the 1-thread run's " + it->second +
                         " (runs must be bit-identical whatever the thread count)");
    if (!row.r.metrics.contains("score") || !row.r.metrics["score"].is_number())
      failures.push_back(label(c) + ": no score in the run's metrics");
    if (c.variant != "default") continue;
    const double divergences = physics_number(row.r, "capsule", "divergences");
    if (std::isfinite(divergences) && divergences > 0)
      failures.push_back(label(c) + ": the capsule diverged " + fmt("%.0f", divergences) +
                         " times");
    const Bound b = bound_of(c.drill);
    const auto fin = reference.find(c.drill);
    std::string detail;
    const double converge =
        fin != reference.end() ? accuracy_error_pct(row.r, fin->second->r, &detail) : std::nan("");
    if (c.level >= b.from_level && !(converge <= b.max_error_pct))
      failures.push_back(label(c) + ": accuracy error " + f("%.2f", converge) +
                         " % against level " + std::to_string(reference_level) +
                         " exceeds its bound " + fmt("%.0f", b.max_error_pct) + " % (" + detail +
                         ")");
  }
  if (reference.size() < drills.size())
    failures.push_back("a drill has no reference point (level " + std::to_string(reference_level) +
                       ", 1 thread)");

  // Raw figures.
  Table t;
  t.columns = {"drill",
               "level",
               "threads",
               "variant",
               "ok",
               "elements",
               "total_elements",
               "frames",
               "wall_s",
               "frame_p50_ms",
               "frame_p99_ms",
               "frame_max_ms",
               "frame_mean_ms",
               "haptic_fifo",
               "haptic_ticks",
               "period_p50_us",
               "period_p99_us",
               "period_p999_us",
               "period_max_us",
               "haptic_overruns",
               "haptic_allocations",
               "rss_before_mb",
               "rss_scene_mb",
               "rss_peak_mb",
               "bytes_per_element",
               "error_pct",
               "score",
               "state_hash",
               "error"};
  nlohmann::json all = nlohmann::json::array();
  for (const auto& row : rows) {
    const auto& r = row.r;
    const double score = r.metrics.contains("score") && r.metrics["score"].is_number()
                             ? r.metrics["score"].get<double>()
                             : std::nan("");
    t.add({r.config.drill,
           double(r.config.level),
           double(r.config.threads),
           r.config.variant,
           double(r.ok),
           row.elements,
           double(r.total_elements),
           double(r.frames),
           r.wall_s,
           r.frame.p50_ms,
           r.frame.p99_ms,
           r.frame.max_ms,
           r.frame.mean_ms,
           double(r.haptic_fifo),
           r.haptic_ticks,
           r.period_p50_us,
           r.period_p99_us,
           r.period_p999_us,
           r.period_max_us,
           r.haptic_overruns,
           r.haptic_allocations,
           r.rss_before_mb,
           r.rss_scene_mb,
           r.rss_peak_mb,
           r.bytes_per_element,
           row.error_pct,
           score,
           r.state_hash,
           r.error});
    nlohmann::json j = to_json(r);
    j["elements_axis"] = row.elements;
    j["error_pct"] =
        std::isfinite(row.error_pct) ? nlohmann::json(row.error_pct) : nlohmann::json(nullptr);
    all.push_back(j);
  }
  write_csv(t, dir / "sweep.csv");
  write_json(t, dir / "sweep.json");
  if (!replot) {
    const nlohmann::json saved = {{"command", cmd},
                                  {"load", load},
                                  {"max_level", max_level},
                                  {"drills", drills},
                                  {"variant_levels", variant_levels},
                                  {"threads", threads},
                                  {"run_failures", run_failures},
                                  {"points", all}};
    std::ofstream(dir / "sweep_points.json") << saved.dump() << '\n';  // compact: ~1 MB indented
  }
  const SweepChartFiles charts = draw_sweep_charts(rows, dir);

  auto find = [&](const std::string& drill, int level, int th,
                  const std::string& variant = "default") {
    return find_row(rows, drill, level, th, variant);
  };

  // ---- The section.
  std::string md = "## The whole trainer under load: the sweep (issues 9 and 17)\n\n";
  md += "Measured by `" + cmd + "`, " + load +
        (replot ? " (report redrawn by `phaco-perf sweep --replot`)" : "") +
        ". Each drill's scripted expert (`data/scenarios/<drill>_expert.json`) runs to its end at "
        "every resolution level 0.." +
        std::to_string(max_level) + " on " + std::to_string(threads.size()) +
        " thread counts, in a process of its own, while the 1 kHz haptic thread (SCHED_FIFO where "
        "granted, not pinned: it competes with the simulation's threads for the two cores) plays "
        "the expert's tool hand from a scripted device and computes forces from the model each "
        "frame publishes. The scene keeps following its scripted tracks, so a point's state hash "
        "is the same with and without the haptic thread. Frame time is the whole frame graph "
        "(every system of the drill's scene; rendering is measured by `phaco-perf trainer`). "
        "Memory is the point process's resident set: before the scene, after building it from the "
        "mesh cache, and its peak while stepping. Accuracy: the drill's scored outcome (" +
        "capsulorhexis: opening diameter and circularity; sculpting: volume removed, trench width "
        "and depth; incision: width and tunnel length) against its reference, the largest relative "
        "difference. The references (perf/results/sweep_reference.json, made by `phaco-perf sweep "
        "--reference`; docs/perf_sweep.md):\n\n";
  for (const std::string& drill : drills) {
    const auto& ref = accuracy.references.at(drill);
    md += "- " + drill + ": " + ref.label;
    for (const std::string& m : accuracy_metrics(drill))
      if (ref.point.metrics.contains(m) && ref.point.metrics[m].is_number())
        md += (m == accuracy_metrics(drill).front() ? ": " : ", ") + m + " " +
              fmt("%.3f", ref.point.metrics[m].get<double>());
    md += ".\n";
  }
  md +=
      "\nThe checks' accuracy bounds are judged against the run's own finest level instead "
      "(level " +
      std::to_string(reference_level) +
      "): they check convergence, and --quick "
      "stops at level 3.\n\n";

  if (!failures.empty()) {
    md += "**Checks failed:**\n\n";
    for (const auto& e : failures) md += "- " + e + "\n";
    md += "\n";
  } else {
    md +=
        "Checks passed: every point ran to its end; 1 and 2 threads gave the same state hash at "
        "every level and variant; the default methods never diverged and stayed within their "
        "accuracy bounds against level " +
        std::to_string(reference_level) + " (";
    for (const std::string& drill : drills) {
      const Bound b = bound_of(drill);
      md += (drill == drills.front() ? "" : ", ") + drill + " ≤ " + fmt("%.0f", b.max_error_pct) +
            " % from level " + std::to_string(b.from_level);
    }
    md += ").\n\n";
  }

  // Targets.
  md += "### Targets\n\n| target | figure | verdict |\n|---|---|---|\n";
  for (const std::string& drill : drills) {
    const SweepRow* d1 = find(drill, 3, 1);
    const SweepRow* d2 = find(drill, 3, 2);
    if (!d1 || !d2) continue;
    const double worst_p99 = std::max(d1->r.frame.p99_ms, d2->r.frame.p99_ms);
    md += "| default scene ≤ 4 ms per frame, " + drill + " (level 3) | p50 " +
          f("%.3f", d2->r.frame.p50_ms) + " ms, mean " + f("%.3f", d2->r.frame.mean_ms) +
          " ms, p99 " + f("%.2f", d2->r.frame.p99_ms) + " ms, max " +
          f("%.1f", d2->r.frame.max_ms) + " ms (2 threads); p99 " + f("%.2f", d1->r.frame.p99_ms) +
          " ms (1 thread) | " + met(worst_p99 <= 4.0) +
          (worst_p99 <= 4.0 ? "" : " at p99 by " + f("%.1f", worst_p99 - 4.0) + " ms") +
          (d2->r.frame.mean_ms <= 4.0 ? "; mean met" : "; mean missed") + " |\n";
  }
  for (const std::string& drill : {std::string("phaco_sculpting"), std::string("capsulorhexis")}) {
    if (std::find(drills.begin(), drills.end(), drill) == drills.end()) continue;
    const SweepRow* big = nullptr;
    for (int l = max_level; l >= 0 && !big; --l) big = find(drill, l, 2);
    if (!big) continue;
    const bool large = drill == "phaco_sculpting" ? big->elements >= 1e6 : big->elements >= 128000;
    const double hz = big->r.frame.p99_ms > 0 ? 1000.0 / big->r.frame.p99_ms : 0;
    md += "| " +
          std::string(drill == "phaco_sculpting" ? "1M lens tets" : "128k capsule vertices") +
          " ≥ 60 Hz with a tool active (" + drill + ", level " +
          std::to_string(big->r.config.level) + ": " + fmt("%.0f", big->elements) + " " +
          drill_elements_name(drill) + ", " + fmt("%.0f", double(big->r.total_elements)) +
          " elements in all) | p50 " + f("%.2f", big->r.frame.p50_ms) + " ms (" +
          f("%.0f", 1000.0 / big->r.frame.p50_ms) + " Hz), p99 " + f("%.1f", big->r.frame.p99_ms) +
          " ms (" + f("%.0f", hz) + " Hz), max " + f("%.0f", big->r.frame.max_ms) + " ms | " +
          (large ? met(hz >= 60)
                 : std::string("not reached: this run's largest level is too small")) +
          (large && hz < 60 ? " at p99 (" + fmt("%.0f", 60 - hz) + " Hz short); p50 " +
                                  std::string(big->r.frame.p50_ms <= 1000.0 / 60 ? "met" : "missed")
                            : "") +
          " |\n";
  }
  // Issue 17's targets (the 2-thread speed-up's replaces issue 9's 1.7× at level 3).
  md += issue17_targets_md(rows, drills, max_level, accuracy.baseline);
  // The haptic targets, judged where the frames ran long enough for the thread to tick a second
  // or more after its warm-up: the default level and the largest, 2 simulation threads.
  for (const std::string& drill : drills) {
    std::vector<const SweepRow*> pts;
    if (const SweepRow* p = find(drill, 3, 2)) pts.push_back(p);
    for (int l = max_level; l > 3; --l)
      if (const SweepRow* p = find(drill, l, 2)) {
        pts.push_back(p);
        break;
      }
    for (const SweepRow* p : pts) {
      const auto& r = p->r;
      const bool enough = r.haptic_ticks >= 1000;
      md +=
          "| haptic period p99 ≤ 1.02 ms, max ≤ 1.5 ms, no allocations, under full load (" + drill +
          ", level " + std::to_string(r.config.level) + ", 2 threads) | " +
          std::string(r.haptic_fifo ? "SCHED_FIFO" : "normal priority (" + r.haptic_detail + ")") +
          ", " + fmt("%.0f", r.haptic_ticks) + " ticks: p50 " + f("%.1f", r.period_p50_us) +
          " us, p99 " + f("%.1f", r.period_p99_us) + " us, max " + f("%.0f", r.period_max_us) +
          " us, " + fmt("%.0f", r.haptic_overruns) + " overruns, " +
          (r.haptic_allocations < 0 ? std::string("allocations not countable")
                                    : fmt("%.0f", r.haptic_allocations) + " allocations") +
          " | " +
          (enough
               ? "p99 " + met(r.period_p99_us <= 1020) + ", max " + met(r.period_max_us <= 1500) +
                     (r.period_max_us > 1500
                          ? " by " + fmt("%.1f", (r.period_max_us - 1500) / 1000) + " ms"
                          : "") +
                     ", allocations " + met(r.haptic_allocations == 0)
               : std::string("too short to judge: the whole drill ran in ") +
                     fmt("%.2f", r.wall_s) + " s") +
          " |\n";
    }
  }
  // Topology changes against mesh size: the capsulorhexis's cut edit and physics refresh, the
  // sculpt's tet removal, the incision's cornea cut; slopes of the worst frame against elements.
  std::vector<std::pair<std::string, PowerFit>> topo;
  {
    auto fit_of = [&](const std::string& drill, auto value) {
      std::vector<double> x, y;
      for (int l = 0; l <= max_level; ++l)
        if (const SweepRow* p = find(drill, l, 1)) {
          x.push_back(p->elements);
          y.push_back(value(p->r));
        }
      return fit_power_law(x, y);
    };
    if (find("capsulorhexis", 0, 1)) {
      topo.push_back({"capsulorhexis: cut edit, worst frame",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return physics_number(r, "capsule_cutting", "edit_ms_max");
                      })});
      topo.push_back({"capsulorhexis: physics refresh after a cut, mean",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return physics_number(r, "capsule_cutting", "physics_refresh_ms_mean");
                      })});
      topo.push_back({"capsulorhexis: capsule_cut system, worst frame",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return system_cost(r, "capsule_cut", &CostSummary::max_ms);
                      })});
    }
    if (find("phaco_sculpting", 0, 1))
      topo.push_back(
          {"sculpting: lens_sculpt time per removed tet (the drill's total over the tets removed)",
           fit_of("phaco_sculpting", [](const SweepPointResult& r) {
             const double removed =
                 r.metrics.contains("tets_removed") ? r.metrics["tets_removed"].get<double>() : 0.0;
             return removed > 0 ? system_cost(r, "lens_sculpt", &CostSummary::mean_ms) *
                                      double(r.frames) / removed
                                : std::nan("");
           })});
    if (find("phaco_sculpting", 0, 1))
      topo.push_back({"sculpting: lens_sculpt system (tet removal), p99",
                      fit_of("phaco_sculpting", [](const SweepPointResult& r) {
                        return system_cost(r, "lens_sculpt", &CostSummary::p99_ms);
                      })});
    if (find("corneal_incision", 0, 1))
      topo.push_back({"incision: cornea_cut system, worst frame",
                      fit_of("corneal_incision", [](const SweepPointResult& r) {
                        return system_cost(r, "cornea_cut", &CostSummary::max_ms);
                      })});
  }
  for (const auto& [name, fit] : topo) {
    md += "| topology changes flat in mesh size: " + name + " | slope " +
          (fit.ok ? fmt("%.2f", fit.slope) : std::string("-")) + " against elements (r² " +
          (fit.ok ? fmt("%.2f", fit.r2) : std::string("-")) + ", 1 thread, levels 0.." +
          std::to_string(max_level) + ") | " +
          (fit.ok ? met(fit.slope <= 0.25) : std::string("no data")) + " |\n";
  }
  md +=
      "\nA target is judged on the slow frames (p99, max) where it is a rate: a trainee feels "
      "those. \"Flat\" means a fitted slope ≤ 0.25 (cost × 1.19 per doubling of the mesh).\n\n";
  md += why_targets_missed(rows, drills, max_level, accuracy.baseline);
  md += "### Issue 17 per level\n\n";
  md += level_tables_md(rows, drills, max_level);
  const LevelChartFiles level_charts = draw_level_charts(rows, dir, max_level);
  for (const std::string& file : {level_charts.cg, level_charts.refresh, level_charts.speedup})
    if (!file.empty()) md += "![" + file + "](results/" + file + ")\n";
  md +=
      "\nCG iterations: physics.capsule's cg_iterations_per_step_mean where the run reports it, "
      "else cg_iterations_total over frames_stepped. The refresh chart's slopes are fitted "
      "against the drill's own elements over the levels run; the speed-up is the 1-thread "
      "frame mean over the 2-thread one with the haptic thread beside both.\n\n";

  // Points.
  md += "### Every point\n\n";
  md +=
      "| drill | level | elements | threads | frame p50 / p99 / max (ms) | costliest system p50 / "
      "max (ms) | haptic period p50 / p99 / max (us), overruns | memory before / scene / peak "
      "(MiB), B per element | error % | state hash "
      "|\n|---|---:|---:|---:|---|---|---|---|---:|---|\n";
  for (const auto& row : rows) {
    const auto& r = row.r;
    if (r.config.variant != "default") continue;
    if (!r.ok) {
      md += "| " + r.config.drill + " | " + std::to_string(r.config.level) + " | - | " +
            std::to_string(r.config.threads) + " | failed: " + r.error + " | | | | | |\n";
      continue;
    }
    const CostSummary* top = nullptr;
    for (const auto& s : r.systems)
      if (!top || s.mean_ms > top->mean_ms) top = &s;
    md += "| " + r.config.drill + " | " + std::to_string(r.config.level) + " | " +
          fmt("%.0f", row.elements) + " | " + std::to_string(r.config.threads) + " | " +
          f("%.3f", r.frame.p50_ms) + " / " + f("%.2f", r.frame.p99_ms) + " / " +
          f("%.1f", r.frame.max_ms) + " | " +
          (top ? top->name + " " + f("%.3f", top->p50_ms) + " / " + f("%.1f", top->max_ms) : "-") +
          " | " + f("%.0f", r.period_p50_us) + " / " + f("%.0f", r.period_p99_us) + " / " +
          f("%.0f", r.period_max_us) + ", " + fmt("%.0f", r.haptic_overruns) + " | " +
          f("%.0f", r.rss_before_mb) + " / " + f("%.0f", r.rss_scene_mb) + " / " +
          f("%.0f", r.rss_peak_mb) + ", " + f("%.0f", r.bytes_per_element) + " | " +
          f("%.2f", row.error_pct) + " | `" + r.state_hash + "` |\n";
  }
  md += "\n";

  // Charts with their readings.
  md += "### Frame cost against mesh size\n\n";
  for (const std::string& drill : drills) {
    if (!charts.frame_cost.count(drill)) continue;
    std::vector<double> x, y;
    for (int l = 0; l <= max_level; ++l)
      if (const SweepRow* p = find(drill, l, 1))
        x.push_back(p->elements), y.push_back(p->r.frame.p50_ms);
    const PowerFit fit = fit_power_law(x, y);
    std::vector<double> y99;
    for (int l = 0; l <= max_level; ++l)
      if (const SweepRow* p = find(drill, l, 1)) y99.push_back(p->r.frame.p99_ms);
    const PowerFit fit99 = fit_power_law(x, y99);
    md += "![" + drill + "](results/" + charts.frame_cost.at(drill) + ")\n\n";
    md += "**" + drill + "**: frame p50 grows as elements^" +
          (fit.ok ? fmt("%.2f", fit.slope) : std::string("?")) + ", p99 as elements^" +
          (fit99.ok ? fmt("%.2f", fit99.slope) : std::string("?")) + " (1 thread, levels 0.." +
          std::to_string(max_level) + ").";
    if (drill == "capsulorhexis") {
      // Figures, not causes: the active set's size and the slowest system at both ends.
      const SweepRow* lo = nullptr;
      const SweepRow* hi = nullptr;
      for (int l = 0; l <= max_level; ++l)
        if (const SweepRow* p = find(drill, l, 1)) {
          if (!lo) lo = p;
          hi = p;
        }
      for (const SweepRow* p : {lo, hi == lo ? nullptr : hi}) {
        if (!p) continue;
        const auto& r = p->r;
        std::string slowest;
        double worst = -1;
        for (const auto& sys : r.systems)
          if (sys.max_ms > worst) worst = sys.max_ms, slowest = sys.name;
        md += " Level " + std::to_string(r.config.level) + ": active set " +
              f("%.0f", physics_number(r, "capsule", "active_particles_mean")) +
              " nodes on average of " + fmt("%.0f", p->elements) +
              "; the slowest single frame of "
              "a system is " +
              slowest + "'s (" + f("%.1f", worst) + " ms of the frame's max " +
              f("%.1f", r.frame.max_ms) + " ms).";
      }
    } else if (drill == "phaco_sculpting")
      md +=
          " The lens is static tets; a frame is the probe's broadphase query and the removal of "
          "the tets it sweeps (seed 000 §5.3). The lens's volume is fixed, so the tets a tip of "
          "fixed size sweeps grow in proportion to the tet count; the time per removed tet is "
          "flat (targets table).";
    else
      md +=
          " The cornea is cut only while the keratome moves through it; the other frames cost "
          "microseconds. One frame per drill grows with the cornea (the worst cornea_cut frame, "
          "targets table) while the p99 stays flat; it is not analysed further here.";
    md +=
        " The seeds' figures (diamonds) are whole-trainer rates with rendering on 2006–2008 "
        "machines; ours here is the simulation alone, the trainer's rendered rate is in the "
        "trainer section.\n\n";
  }
  md += "### Per-system cost, stacked\n\n";
  for (const std::string& drill : drills)
    if (charts.systems.count(drill))
      md += "![" + drill + " systems](results/" + charts.systems.at(drill) + ")\n";
  md +=
      "\nEach line adds one system's mean cost per frame on top of those below it, so the gaps are "
      "the systems' shares; the dashed line is the measured whole frame (the difference is the "
      "scheduler's own work).\n\n";

  md += "### Speed against accuracy: the method alternatives in the scene\n\n";
  md += "Each alternative runs the same expert at levels ";
  for (size_t i = 0; i < variant_levels.size(); ++i)
    md += (i ? ", " : "") + std::to_string(variant_levels[i]);
  md +=
      " on 1 thread; error against each drill's reference (listed at the top of the "
      "section).\n\n";
  md +=
      "| drill | variant | level | frame mean / p99 (ms) | error % | score | capsule divergences / "
      "fallbacks | note |\n|---|---|---:|---|---:|---:|---|---|\n";
  for (const auto& row : rows) {
    const auto& r = row.r;
    if (r.config.threads != 1 || is_scaling_variant(r.config.variant)) continue;
    const bool is_variant_level = std::find(variant_levels.begin(), variant_levels.end(),
                                            r.config.level) != variant_levels.end();
    if (r.config.variant == "default" &&
        !(is_variant_level && !variants_of(r.config.drill).empty()))
      continue;
    const double score = r.metrics.contains("score") && r.metrics["score"].is_number()
                             ? r.metrics["score"].get<double>()
                             : std::nan("");
    md += "| " + r.config.drill + " | " + r.config.variant + " | " +
          std::to_string(r.config.level) + " | " +
          (r.ok ? f("%.3f", r.frame.mean_ms) + " / " + f("%.2f", r.frame.p99_ms) : "failed") +
          " | " + f("%.2f", row.error_pct) + " | " + f("%.1f", score) + " | " +
          f("%.0f", physics_number(r, "capsule", "divergences")) + " / " +
          f("%.0f", physics_number(r, "capsule", "fallbacks")) + " | " +
          (r.ok ? row.error_detail : r.error) + " |\n";
  }
  md +=
      "\nThe note names the metric furthest from the reference (run vs reference); an error \"-\" "
      "means "
      "the run lacks a scored outcome, e.g. a rhexis that did not close or a lens model without "
      "trenches. Two caveats. The sculpting reference is the default narrowphase's at the finest "
      "level, so an alternative that converges to a different answer shows a large error here "
      "even where it is closer to the truth: the exact narrowphases remove every tet the tip "
      "touches, not only those whose centre it covers, and the lens section compares both with "
      "the exact swept volume. The "
      "fragmenting lens is the divide-and-conquer model; the trench drill does not score it. "
      "Without "
      "the active set, the whole capsule's implicit step runs every frame: it is measured up to "
      "level 3 "
      "only, and not in --quick.\n\n";
  for (const std::string& drill : drills)
    if (charts.pareto.count(drill))
      md += "![" + drill + " speed against accuracy](results/" + charts.pareto.at(drill) + ")\n";
  md += "\n";
  for (const std::string& drill : drills) md += pareto_md(rows, drill, kNoHaptics);
  md +=
      "How converged each reference is, and how far the capsulorhexis's level-3 outcome moves "
      "with the time step alone, is in docs/perf_sweep.md (\"The converged reference\"): read a "
      "front at level 3 with that spread in mind.\n\n";
  md +=
      "The stability maps (time step against stiffness per integrator) and OpenPhaco's membrane "
      "against Bullet's btSoftBody are in the membrane section; force propagation against "
      "dynamics, Horn against polar decomposition and the SPH search's cell order are measured on "
      "their own systems in the membrane and lens sections, where they are not a choice of the "
      "scene.\n\n";

  md += "### Thread scaling\n\n![threads](results/" + charts.threads + ")\n\n";
  md +=
      "Dots: the same speed-up without the haptic thread beside the frames, and with the "
      "executor's flow graph every frame instead of its Auto dispatch. The same figures "
      "against the level are in the issue-17 per-level charts above; what the figures show where "
      "a target is missed is in the targets' reading.\n\n";
  md += frame_dispatch_md(rows, drills);
  md += "### Haptic period under load\n\n![haptic period](results/" + charts.haptics + ")\n\n";
  md += "### Memory per element\n\n![memory](results/" + charts.memory + ")\n\n";
  for (const std::string& drill : drills) {
    const SweepRow* lo = find(drill, 3, 1);
    const SweepRow* hi = find(drill, max_level, 1);
    if (lo && hi && hi != lo)
      md += "- " + drill + ": " + fmt("%.0f", lo->r.bytes_per_element) +
            " bytes per element at level 3 (peak " + fmt("%.0f", lo->r.rss_peak_mb) + " MiB), " +
            fmt("%.0f", hi->r.bytes_per_element) + " at level " + std::to_string(max_level) +
            " (peak " + fmt("%.0f", hi->r.rss_peak_mb) + " MiB, " +
            fmt("%.0f", double(hi->r.total_elements)) + " elements).\n";
  }
  md +=
      "\nBytes per element: the point process's peak resident set while stepping, less its "
      "resident "
      "set before the scene was built, over every body's particles, triangles and tets. Part of it "
      "does not grow with the mesh, so the small levels show more bytes per element.\n\n";
  write_section(dir, "sweep", md);
  progress.finish();

  if (!failures.empty()) {
    std::string all_failures;
    for (const auto& e : failures) all_failures += "\n  " + e;
    throw CheckFailed("sweep: " + std::to_string(failures.size()) + " check(s) failed (also in " +
                      (dir / "sweep.md").string() + "):" + all_failures);
  }
}

}  // namespace phaco::perf
