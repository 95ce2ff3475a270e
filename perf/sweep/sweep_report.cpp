// The sweep's report; see sweep_report.hpp.
#include "perf/sweep/sweep_report.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

#include "engine/core/error.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/sweep/sweep_levels.hpp"
#include "perf/sweep/sweep_mechanics.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

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

// What every part of the section reads.
struct Section {
  const std::vector<SweepRow>& rows;
  const SweepRun& run;
  const SweepAccuracy& accuracy;
  const std::vector<std::string>& failures;
  const SweepChartFiles& charts;
  const fs::path& dir;
  const SweepRow* find(const std::string& drill, int level, int threads,
                       const std::string& variant = "default") const {
    return find_row(rows, drill, level, threads, variant);
  }
  // Power-law fit of a figure of the default methods' 1-thread points against the drill's
  // elements, over the levels run.
  template <class Value>
  PowerFit fit(const std::string& drill, Value value) const {
    std::vector<double> x, y;
    for (int l = 0; l <= run.max_level; ++l)
      if (const SweepRow* p = find(drill, l, 1)) {
        x.push_back(p->elements);
        y.push_back(value(p->r));
      }
    return fit_power_law(x, y);
  }
};

// The sculpt's lens_sculpt time per removed tet: the drill's total over the tets it removed.
double ms_per_removed_tet(const SweepPointResult& r) {
  const double removed =
      r.metrics.contains("tets_removed") ? r.metrics["tets_removed"].get<double>() : 0.0;
  return removed > 0
             ? system_cost(r, "lens_sculpt", &CostSummary::mean_ms) * double(r.frames) / removed
             : std::nan("");
}

// " as elements^1.23" from a fit, or nothing when the fit failed: a reading is printed only where
// the figures give it.
std::string growth(const PowerFit& fit) {
  return fit.ok ? " as elements^" + fmt("%.2f", fit.slope) : std::string();
}

// The section's head: how it was measured, the references, the checks.
std::string intro_md(const Section& s) {
  const std::vector<std::string>& drills = s.run.drills;
  const int max_level = s.run.max_level;
  const SweepAccuracy& accuracy = s.accuracy;
  std::string md = "## The whole trainer under load: the sweep (issues 9 and 17)\n\n";
  md += "Measured by `" + s.run.command + "`, " + s.run.load +
        (s.run.replot ? " (report redrawn by `phaco-perf sweep --replot`)" : "") +
        ". Each drill's scripted expert (`data/scenarios/<drill>_expert.json`) runs to its end at "
        "every resolution level 0.." +
        std::to_string(max_level) + " on " + std::to_string(s.run.threads.size()) +
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
      std::to_string(max_level) +
      "): they check convergence, and --quick "
      "stops at level 3.\n\n";

  if (!s.failures.empty()) {
    md += "**Checks failed:**\n\n";
    for (const auto& e : s.failures) md += "- " + e + "\n";
    md += "\n";
  } else {
    md +=
        "Checks passed: every point ran to its end; 1 and 2 threads gave the same state hash at "
        "every level and variant; the default methods never diverged and stayed within their "
        "accuracy bounds against level " +
        std::to_string(max_level) + " (";
    for (const std::string& drill : drills) {
      const Bound b = bound_of(drill);
      md += (drill == drills.front() ? "" : ", ") + drill + " ≤ " + fmt("%.0f", b.max_error_pct) +
            " % from level " + std::to_string(b.from_level);
    }
    md += ").\n\n";
  }
  return md;
}

// The frame-time targets: the default scene at level 3, the large meshes at 60 Hz.
std::string scene_targets_md(const Section& s) {
  const std::vector<std::string>& drills = s.run.drills;
  const int max_level = s.run.max_level;
  std::string md;
  // Targets.
  md += "### Targets\n\n| target | figure | verdict |\n|---|---|---|\n";
  for (const std::string& drill : drills) {
    const SweepRow* d1 = s.find(drill, 3, 1);
    const SweepRow* d2 = s.find(drill, 3, 2);
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
    for (int l = max_level; l >= 0 && !big; --l) big = s.find(drill, l, 2);
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
  return md;
}

// The haptic targets, with issue 17's before them (the 2-thread speed-up's replaces issue 9's
// 1.7× at level 3).
std::string haptic_targets_md(const Section& s) {
  const std::vector<SweepRow>& rows = s.rows;
  const std::vector<std::string>& drills = s.run.drills;
  const int max_level = s.run.max_level;
  const SweepAccuracy& accuracy = s.accuracy;
  std::string md;
  md += issue17_targets_md(rows, drills, max_level, accuracy.baseline);
  // The haptic targets, judged where the frames ran long enough for the thread to tick a second
  // or more after its warm-up: the default level and the largest, 2 simulation threads.
  for (const std::string& drill : drills) {
    std::vector<const SweepRow*> pts;
    if (const SweepRow* p = s.find(drill, 3, 2)) pts.push_back(p);
    for (int l = max_level; l > 3; --l)
      if (const SweepRow* p = s.find(drill, l, 2)) {
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
  return md;
}

// Topology changes against mesh size, and how a target is judged.
std::string topology_targets_md(const Section& s) {
  const int max_level = s.run.max_level;
  std::string md;
  // Topology changes against mesh size: the capsulorhexis's cut edit and physics refresh, the
  // sculpt's tet removal, the incision's cornea cut; slopes of the worst frame against elements.
  std::vector<std::pair<std::string, PowerFit>> topo;
  {
    auto fit_of = [&s](const std::string& drill, auto value) { return s.fit(drill, value); };
    if (s.find("capsulorhexis", 0, 1)) {
      topo.push_back({"capsulorhexis: cut edit, worst frame",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return physics_number(r, "capsule_cutting", "edit_ms_max");
                      })});
      topo.push_back({"capsulorhexis: physics refresh after a cut, mean",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return physics_number(r, "capsule_cutting", "physics_refresh_ms_mean");
                      })});
      topo.push_back(
          {"capsulorhexis: physics refresh per patched spring (the refresh's mean over the springs "
           "it added and removed)",
           fit_of("capsulorhexis", refresh_ms_per_patched_spring)});
      topo.push_back({"capsulorhexis: capsule_cut system, worst frame",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return system_cost(r, "capsule_cut", &CostSummary::max_ms);
                      })});
    }
    if (s.find("phaco_sculpting", 0, 1))
      topo.push_back(
          {"sculpting: lens_sculpt time per removed tet (the drill's total over the tets removed)",
           fit_of("phaco_sculpting", ms_per_removed_tet)});
    if (s.find("phaco_sculpting", 0, 1))
      topo.push_back({"sculpting: lens_sculpt system (tet removal), p99",
                      fit_of("phaco_sculpting", [](const SweepPointResult& r) {
                        return system_cost(r, "lens_sculpt", &CostSummary::p99_ms);
                      })});
    if (s.find("corneal_incision", 0, 1))
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
  return md;
}

// What the figures show where a target is missed, and issue 17's per-level tables and charts.
std::string levels_md(const Section& s) {
  const std::vector<SweepRow>& rows = s.rows;
  const std::vector<std::string>& drills = s.run.drills;
  const int max_level = s.run.max_level;
  const SweepAccuracy& accuracy = s.accuracy;
  std::string md;
  md += why_targets_missed(rows, drills, max_level, accuracy.baseline);
  md += "### Issue 17 per level\n\n";
  md += level_tables_md(rows, drills, max_level);
  const LevelChartFiles level_charts = draw_level_charts(rows, s.dir, max_level);
  for (const std::string& file : {level_charts.cg, level_charts.refresh, level_charts.speedup})
    if (!file.empty()) md += "![" + file + "](results/" + file + ")\n";
  md +=
      "\nCG iterations: physics.capsule's cg_iterations_per_step_mean where the run reports it, "
      "else cg_iterations_total over frames_stepped. The refresh chart's slopes are fitted "
      "against the drill's own elements over the levels run; the speed-up is the 1-thread "
      "frame mean over the 2-thread one with the haptic thread beside both. Single runs of one "
      "point differ by up to 40 % on this machine, so where the capsulorhexis points were "
      "repeated (" +
      std::to_string(s.run.speedup_reps) +
      " runs of each, the repeats after every other point, thread order alternating) its "
      "speed-up is the mean of the paired ratios with its 95 % interval (Student's t), and the "
      "targets are judged on that mean; the frame columns are the first pair's.\n\n";
  md += speedup_pairs_md(rows, max_level);
  return md;
}

// Every point of the default methods.
std::string points_md(const Section& s) {
  const std::vector<SweepRow>& rows = s.rows;
  std::string md;
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
  return md;
}

// Frame cost against mesh size, per drill, with what the figures show.
std::string frame_cost_md(const Section& s) {
  const std::vector<std::string>& drills = s.run.drills;
  const int max_level = s.run.max_level;
  const SweepChartFiles& charts = s.charts;
  std::string md;
  // Charts with their readings.
  md += "### Frame cost against mesh size\n\n";
  for (const std::string& drill : drills) {
    if (!charts.frame_cost.count(drill)) continue;
    const PowerFit fit = s.fit(drill, [](const SweepPointResult& r) { return r.frame.p50_ms; });
    const PowerFit fit99 = s.fit(drill, [](const SweepPointResult& r) { return r.frame.p99_ms; });
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
        if (const SweepRow* p = s.find(drill, l, 1)) {
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
    } else if (drill == "phaco_sculpting") {
      // The tets a tip of fixed size sweeps grow with the tet count (the lens's volume is fixed):
      // what is read here is the time per removed tet, and the system's slow frames.
      md +=
          " The lens is static tets; a frame is the probe's broadphase query and the removal of "
          "the tets it sweeps (seed 000 §5.3).";
      const std::string per_tet = growth(s.fit(drill, ms_per_removed_tet));
      const std::string sculpt_p99 = growth(s.fit(drill, [](const SweepPointResult& r) {
        return system_cost(r, "lens_sculpt", &CostSummary::p99_ms);
      }));
      if (!per_tet.empty()) md += " The lens_sculpt time per removed tet grows" + per_tet + ".";
      if (!sculpt_p99.empty()) md += " The lens_sculpt p99 grows" + sculpt_p99 + ".";
    } else {
      md += " The cornea is cut only while the keratome moves through it.";
      const std::string cut_max = growth(s.fit(drill, [](const SweepPointResult& r) {
        return system_cost(r, "cornea_cut", &CostSummary::max_ms);
      }));
      if (!cut_max.empty()) md += " The worst cornea_cut frame grows" + cut_max + ".";
    }
    md +=
        " The seeds' figures (diamonds) are whole-trainer rates with rendering on 2006–2008 "
        "machines; ours here is the simulation alone, the trainer's rendered rate is in the "
        "trainer section.\n\n";
  }
  return md;
}

// The per-system stack and the method alternatives against accuracy.
std::string methods_md(const Section& s) {
  const std::vector<SweepRow>& rows = s.rows;
  const std::vector<std::string>& drills = s.run.drills;
  const SweepChartFiles& charts = s.charts;
  const std::vector<int>& variant_levels = s.run.variant_levels;
  std::string md;
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
  for (const std::string& drill : drills) md += pareto_md(rows, drill, kNoHapticsVariant);
  if (std::find(drills.begin(), drills.end(), "capsulorhexis") != drills.end())
    md += integrator_mechanics_md(rows, results_file(s.dir, "membrane.json"), kNoHapticsVariant);
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
  return md;
}

// Thread scaling, the haptic period and memory.
std::string scaling_md(const Section& s) {
  const std::vector<SweepRow>& rows = s.rows;
  const std::vector<std::string>& drills = s.run.drills;
  const int max_level = s.run.max_level;
  const SweepChartFiles& charts = s.charts;
  std::string md;
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
    const SweepRow* lo = s.find(drill, 3, 1);
    const SweepRow* hi = s.find(drill, max_level, 1);
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
  return md;
}

}  // namespace

std::string sweep_section_md(const std::vector<SweepRow>& rows, const SweepRun& run,
                             const SweepAccuracy& accuracy,
                             const std::vector<std::string>& failures, const fs::path& dir) {
  const SweepChartFiles charts = draw_sweep_charts(rows, dir);
  const Section s{rows, run, accuracy, failures, charts, dir};
  return intro_md(s) + scene_targets_md(s) + haptic_targets_md(s) + topology_targets_md(s) +
         levels_md(s) + points_md(s) + frame_cost_md(s) + methods_md(s) + scaling_md(s);
}

}  // namespace phaco::perf
