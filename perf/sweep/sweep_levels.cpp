#include "perf/sweep/sweep_levels.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <tuple>

#include "engine/core/error.hpp"
#include "perf/report.hpp"

namespace phaco::perf {

namespace fs = std::filesystem;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string f(const char* format, double v) {
  return std::isfinite(v) ? fmt(format, v) : std::string("-");
}

std::string met(bool ok) {
  return ok ? "**met**" : "**missed**";
}

bool has(const std::vector<std::string>& drills, const char* d) {
  return std::find(drills.begin(), drills.end(), d) != drills.end();
}

const LevelFigures* at_level(const std::vector<LevelFigures>& figs, int level) {
  for (const auto& g : figs)
    if (g.level == level) return &g;
  return nullptr;
}

// The system with the largest worst frame of a point, and that worst frame.
std::pair<std::string, double> costliest_worst_frame(const SweepPointResult& r) {
  std::pair<std::string, double> best{"", kNaN};
  for (const auto& s : r.systems)
    if (!(s.max_ms <= best.second)) best = {s.name, s.max_ms};
  return best;
}

}  // namespace

std::string speedup_text(const LevelFigures& g) {
  if (!std::isfinite(g.speedup)) return "-";
  std::string t = fmt("%.2f", g.speedup) + "×";
  if (g.speedup_pairs > 1)
    t += " [" + fmt("%.2f", g.speedup_lo) + "–" + fmt("%.2f", g.speedup_hi) + "], " +
         std::to_string(g.speedup_pairs);
  return t;
}

double cg_iterations_per_step(const SweepPointResult& r) {
  const double mean = physics_number(r, "capsule", "cg_iterations_per_step_mean");
  if (std::isfinite(mean)) return mean;
  const double total = physics_number(r, "capsule", "cg_iterations_total");
  const double stepped = physics_number(r, "capsule", "frames_stepped");
  return std::isfinite(total) && stepped > 0 ? total / stepped : kNaN;
}

double speedup(const SweepRow* one, const SweepRow* two) {
  if (!one || !two || !(one->r.frame.mean_ms > 0) || !(two->r.frame.mean_ms > 0)) return kNaN;
  return one->r.frame.mean_ms / two->r.frame.mean_ms;
}

std::vector<LevelFigures> level_figures(const std::vector<SweepRow>& rows, const std::string& drill,
                                        int max_level) {
  std::vector<LevelFigures> out;
  for (int l = 0; l <= max_level; ++l) {
    const SweepRow* a = find_row(rows, drill, l, 1);
    const SweepRow* b = find_row(rows, drill, l, 2);
    if (!a && !b) continue;
    LevelFigures g;
    g.level = l;
    g.elements = a ? a->elements : b->elements;
    const SweepPointResult& r = a ? a->r : b->r;
    g.cg_per_step = cg_iterations_per_step(r);
    g.refresh_ms_mean = physics_number(r, "capsule_cutting", "physics_refresh_ms_mean");
    g.refresh_ms_max = physics_number(r, "capsule_cutting", "physics_refresh_ms_max");
    g.refresh_springs = physics_number(r, "capsule_cutting", "physics_refresh_springs_mean");
    g.refresh_ms_per_spring = refresh_ms_per_patched_spring(r);
    g.cut_edit_ms_max = physics_number(r, "capsule_cutting", "edit_ms_max");
    g.cornea_cut_max_ms = system_cost(r, "cornea_cut", &CostSummary::max_ms);
    g.p50_1 = a ? a->r.frame.p50_ms : kNaN, g.p99_1 = a ? a->r.frame.p99_ms : kNaN;
    g.max_1 = a ? a->r.frame.max_ms : kNaN, g.mean_1 = a ? a->r.frame.mean_ms : kNaN;
    g.p50_2 = b ? b->r.frame.p50_ms : kNaN, g.p99_2 = b ? b->r.frame.p99_ms : kNaN;
    g.max_2 = b ? b->r.frame.max_ms : kNaN, g.mean_2 = b ? b->r.frame.mean_ms : kNaN;
    // Paired repetitions: the level's own pair, then each "repeat k" pair that ran whole.
    std::vector<double> ratios;
    if (const double s = speedup(a, b); std::isfinite(s)) ratios.push_back(s);
    for (int rep = 2;; ++rep) {
      const std::string v = repeat_variant(rep);
      const SweepRow *ra = find_row(rows, drill, l, 1, v), *rb = find_row(rows, drill, l, 2, v);
      if (!ra && !rb) break;
      if (const double s = speedup(ra, rb); std::isfinite(s)) ratios.push_back(s);
    }
    const MeanInterval mi = mean_interval95(ratios);
    g.speedup = mi.mean, g.speedup_lo = mi.lo, g.speedup_hi = mi.hi;
    g.speedup_pairs = int(ratios.size());
    g.error_pct = a ? a->error_pct : kNaN;
    out.push_back(g);
  }
  return out;
}

PowerFit slope_over_levels(const std::vector<LevelFigures>& figures, double LevelFigures::*value,
                           int lo, int hi) {
  std::vector<double> x, y;
  for (const auto& g : figures)
    if (g.level >= lo && g.level <= hi) x.push_back(g.elements), y.push_back(g.*value);
  return fit_power_law(x, y);
}

std::string level_tables_md(const std::vector<SweepRow>& rows,
                            const std::vector<std::string>& drills, int max_level) {
  std::string md;
  for (const std::string& drill : drills) {
    const auto figs = level_figures(rows, drill, max_level);
    if (figs.empty()) continue;
    const bool rhexis = drill == "capsulorhexis", incision = drill == "corneal_incision";
    md += "**" + drill + "**, default methods (error: 1 thread, against the reference):\n\n";
    md += "| level | " + std::string(drill_elements_name(drill)) + " |" +
          (rhexis ? " CG iterations per stepped frame | physics refresh per cut, mean / max (µs) | "
                    "springs it patched, mean |"
                  : "") +
          (incision ? " cornea_cut worst frame (ms) |" : "") +
          " frame p50 / p99 / max, 1 thread (ms) | frame p50 / p99 / max, 2 threads (ms) | "
          "speed-up of the mean [95 %], pairs | error % |\n|---:|---:|" +
          (rhexis ? "---:|---|---:|" : "") + (incision ? "---:|" : "") + "---|---|---:|---:|\n";
    for (const auto& g : figs) {
      md += "| " + std::to_string(g.level) + " | " + fmt("%.0f", g.elements) + " | ";
      if (rhexis)
        md += f("%.1f", g.cg_per_step) + " | " + f("%.1f", 1e3 * g.refresh_ms_mean) + " / " +
              f("%.0f", 1e3 * g.refresh_ms_max) + " | " + f("%.1f", g.refresh_springs) + " | ";
      if (incision) md += f("%.2f", g.cornea_cut_max_ms) + " | ";
      md += f("%.3f", g.p50_1) + " / " + f("%.2f", g.p99_1) + " / " + f("%.1f", g.max_1) + " | " +
            f("%.3f", g.p50_2) + " / " + f("%.2f", g.p99_2) + " / " + f("%.1f", g.max_2) + " | " +
            speedup_text(g) + " | " + f("%.2f", g.error_pct) + " |\n";
    }
    md += "\n";
  }
  return md;
}

LevelChartFiles draw_level_charts(const std::vector<SweepRow>& rows, const fs::path& dir,
                                  int max_level) {
  LevelChartFiles files;
  const auto rhexis = level_figures(rows, "capsulorhexis", max_level);
  const auto incision = level_figures(rows, "corneal_incision", max_level);

  Series cg{.name = "capsulorhexis, default methods"};
  for (const auto& g : rhexis) cg.x.push_back(g.level), cg.y.push_back(g.cg_per_step);
  if (!rhexis.empty()) {
    Chart c{.title = "CG iterations per stepped frame (capsule implicit step)",
            .x = {.label = "resolution level", .min = 0.0, .max = double(max_level)},
            .y = {.label = "CG iterations per stepped frame", .min = 0.0}};
    c.series.push_back(cg);
    c.series.push_back(Series{.name = "target 40 at level 3",
                              .x = {0.0, double(max_level)},
                              .y = {40.0, 40.0},
                              .style = Style::Line,
                              .dashed = true});
    files.cg = "sweep_cg_iterations.png";
    save_chart(c, dir / files.cg);
  }

  Chart rf{.title = "Topology change cost against mesh size (1 thread)",
           .x = {.label = "elements of the drill's body", .scale = Scale::Log10},
           .y = {.label = "ms", .scale = Scale::Log10}};
  Series mean{.name = "capsule refresh, mean", .fit_power_law = true};
  Series worst{.name = "capsule refresh, max", .fit_power_law = true, .dashed = true};
  for (const auto& g : rhexis) {
    mean.x.push_back(g.elements), mean.y.push_back(g.refresh_ms_mean);
    worst.x.push_back(g.elements), worst.y.push_back(g.refresh_ms_max);
  }
  Series cornea{.name = "cornea cut, worst", .fit_power_law = true};
  for (const auto& g : incision)
    cornea.x.push_back(g.elements), cornea.y.push_back(g.cornea_cut_max_ms);
  if (!rhexis.empty() || !incision.empty()) {
    rf.series = {mean, worst, cornea};
    files.refresh = "sweep_refresh.png";
    save_chart(rf, dir / files.refresh);
  }

  Chart sp{.title = "Speed-up of the mean frame, 2 threads over 1",
           .x = {.label = "resolution level", .min = 0.0, .max = double(max_level)},
           .y = {.label = "speed-up (1-thread mean / 2-thread mean)", .min = 0.0, .max = 2.2}};
  for (const char* drill : {"capsulorhexis", "phaco_sculpting", "corneal_incision"}) {
    Series s{.name = drill};
    Series lo{.name = std::string(drill) + ", 95 % low", .style = Style::Line, .dashed = true};
    Series hi{.name = std::string(drill) + ", 95 % high", .style = Style::Line, .dashed = true};
    for (const auto& g : level_figures(rows, drill, max_level)) {
      s.x.push_back(g.level), s.y.push_back(g.speedup);
      if (g.speedup_pairs > 1 && std::isfinite(g.speedup_lo) && std::isfinite(g.speedup_hi))
        lo.x.push_back(g.level), lo.y.push_back(g.speedup_lo), hi.x.push_back(g.level),
            hi.y.push_back(g.speedup_hi);
    }
    if (!s.x.empty()) sp.series.push_back(s);
    if (!lo.x.empty()) sp.series.push_back(lo), sp.series.push_back(hi);
  }
  if (!sp.series.empty()) {
    sp.series.push_back(Series{.name = "target 1.5 at levels 6-8",
                               .x = {6.0, 8.0},
                               .y = {1.5, 1.5},
                               .style = Style::Line,
                               .dashed = true});
    sp.series.push_back(Series{.name = "floor 0.95",
                               .x = {0.0, double(max_level)},
                               .y = {0.95, 0.95},
                               .style = Style::Line,
                               .dashed = true});
    files.speedup = "sweep_speedup.png";
    save_chart(sp, dir / files.speedup);
  }
  return files;
}

DrillFront drill_front(const std::vector<SweepRow>& rows, const std::string& drill,
                       const std::string& skip_variant) {
  DrillFront front;
  std::vector<double> x, y;
  for (const auto& row : rows)
    if (row.r.ok && row.r.config.drill == drill && row.r.config.threads == 1 &&
        row.r.config.variant != skip_variant && !is_scaling_variant(row.r.config.variant) &&
        std::isfinite(row.error_pct) && row.error_pct > 0 && row.r.frame.mean_ms > 0) {
      front.points.push_back(&row);
      x.push_back(row.r.frame.mean_ms);
      y.push_back(row.error_pct);
    }
  if (front.points.size() >= 2)
    for (size_t i : pareto_indices(x, y)) front.front.push_back(front.points[i]);
  return front;
}

std::string pareto_md(const std::vector<SweepRow>& rows, const std::string& drill,
                      const std::string& skip_variant) {
  const DrillFront front = drill_front(rows, drill, skip_variant);
  const std::vector<const SweepRow*>& pts = front.points;
  if (pts.size() < 2) return "";
  std::string md =
      "**" + drill + ", the front** (cheapest first; a point with error 0 is left out):";
  bool default_on = false;
  std::string integrators;
  for (const SweepRow* p : front.front) {
    const auto& c = p->r.config;
    md += " " + c.variant + " at level " + std::to_string(c.level) + " (" +
          fmt("%.3f", p->r.frame.mean_ms) + " ms, " + fmt("%.2f", p->error_pct) + " %);";
    if (c.variant == "default" && c.level == 3) default_on = true;
    if (c.variant.rfind("capsule.integrator=", 0) == 0)
      integrators += (integrators.empty() ? "" : ", ") + c.variant.substr(19) + " at level " +
                     std::to_string(c.level);
  }
  md.back() = '.';
  const SweepRow* d = find_row(rows, drill, 3, 1);
  if (!d) return md + " The default methods did not run at level 3.\n\n";
  md += std::string(" **The default methods at level 3 (") + fmt("%.3f", d->r.frame.mean_ms) +
        " ms, " + f("%.2f", d->error_pct) + " %) " +
        (default_on ? "lie on the front.**" : "do not lie on the front.**");
  std::string better;
  for (const SweepRow* p : pts)
    if (p->r.config.level == 3 && p->r.config.variant != "default" &&
        p->r.frame.mean_ms < d->r.frame.mean_ms && p->error_pct < d->error_pct)
      better += (better.empty() ? "" : "; ") + p->r.config.variant + " (" +
                fmt("%.3f", p->r.frame.mean_ms) + " ms, " + fmt("%.2f", p->error_pct) + " %)";
  if (!better.empty()) md += " Both faster and closer at level 3: " + better + ".";
  if (!default_on && !integrators.empty())
    md += " On the front where the default at level 3 is not: " + integrators + ".";
  return md + "\n\n";
}

Baseline load_baseline(const fs::path& path) {
  Baseline b;
  std::ifstream in(path);
  if (!in) return b;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    b.source = j.value("source", "");
    for (const auto& p : j.at("points")) {
      SweepPointResult r;
      r.config.drill = p.at("drill");
      r.config.level = p.at("level");
      r.metrics = p.at("metrics");
      r.ok = true;
      b.points.push_back(std::move(r));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError("sweep: the baseline " + path.string() + " is unreadable: " + e.what());
  }
  return b;
}

namespace {

// The worst error margin of the default against the baseline over the levels both have:
// (level, default error − baseline error); level −1 when none compares.
std::pair<int, double> worst_accuracy_margin(const std::vector<SweepRow>& rows,
                                             const std::vector<SweepRow>& baseline,
                                             const std::string& drill, int max_level) {
  std::pair<int, double> worst{-1, -1e300};
  for (int l = 0; l <= max_level; ++l) {
    const SweepRow* now = find_row(rows, drill, l, 1);
    const SweepRow* then = nullptr;
    for (const auto& b : baseline)
      if (b.r.config.drill == drill && b.r.config.level == l) then = &b;
    if (!now || !then || !std::isfinite(then->error_pct)) continue;
    const double margin = std::isfinite(now->error_pct) ? now->error_pct - then->error_pct : 1e300;
    if (margin > worst.second) worst = {l, margin};
  }
  return worst;
}

}  // namespace

std::string issue17_targets_md(const std::vector<SweepRow>& rows,
                               const std::vector<std::string>& drills, int max_level,
                               const std::vector<SweepRow>& baseline) {
  std::string md;
  const bool rhexis = has(drills, "capsulorhexis");
  const auto figs =
      rhexis ? level_figures(rows, "capsulorhexis", max_level) : std::vector<LevelFigures>{};
  for (const auto& [level, p99, mx] : {std::tuple{3, 4.0, 8.0}, std::tuple{8, 16.7, 33.0}}) {
    const LevelFigures* g = at_level(figs, level);
    if (!g || !std::isfinite(g->p99_2)) continue;
    md += "| issue 17: capsulorhexis expert, level " + std::to_string(level) +
          ", 2 threads: frame p99 ≤ " + fmt("%.1f", p99) + " ms, max ≤ " + fmt("%.0f", mx) +
          " ms | p99 " + f("%.2f", g->p99_2) + " ms, max " + f("%.1f", g->max_2) + " ms | p99 " +
          met(g->p99_2 <= p99) + ", max " + met(g->max_2 <= mx) + " |\n";
  }
  if (rhexis) {
    const PowerFit fit = slope_over_levels(figs, &LevelFigures::refresh_ms_mean, 0, 8);
    md +=
        "| issue 17: capsule physics refresh after a cut, slope ≤ 0.25 against elements (levels "
        "0.." +
        std::to_string(std::min(8, max_level)) + ") | mean per cut: slope " +
        (fit.ok ? fmt("%.2f", fit.slope) + " (r² " + fmt("%.2f", fit.r2) + ")" : "-") + " | " +
        (fit.ok ? met(fit.slope <= 0.25) : "no data") + " |\n";
  }
  if (has(drills, "corneal_incision")) {
    const PowerFit fit = slope_over_levels(level_figures(rows, "corneal_incision", max_level),
                                           &LevelFigures::cornea_cut_max_ms, 0, 8);
    md += "| issue 17: the cornea's worst cut frame, slope ≤ 0.25 against elements (levels 0.." +
          std::to_string(std::min(8, max_level)) + ") | slope " +
          (fit.ok ? fmt("%.2f", fit.slope) + " (r² " + fmt("%.2f", fit.r2) + ")" : "-") + " | " +
          (fit.ok ? met(fit.slope <= 0.25) : "no data") + " |\n";
  }
  if (rhexis && !figs.empty()) {
    std::string big, low;
    bool big_ok = true, low_ok = true, any_big = false;
    for (const auto& g : figs) {
      if (!std::isfinite(g.speedup)) continue;
      if (g.level >= 6) {
        any_big = true;
        big += (big.empty() ? "" : ", ") + std::to_string(g.level) + ": " + speedup_text(g);
        big_ok = big_ok && g.speedup >= 1.5;
      }
      if (g.speedup < 0.95) {
        low += (low.empty() ? "" : ", ") + std::to_string(g.level) + ": " + speedup_text(g);
        low_ok = false;
      }
    }
    md +=
        "| issue 17: 2-thread speed-up of the capsulorhexis frame mean ≥ 1.5× at levels 6–8, "
        "never below 0.95× | " +
        (any_big ? "levels " + big : std::string("levels 6–8 not run")) + "; below 0.95× at " +
        (low.empty() ? std::string("no level") : "levels " + low) + " | ≥ 1.5× " +
        (any_big ? met(big_ok) : std::string("not judged")) + ", ≥ 0.95× " + met(low_ok) + " |\n";
    if (const LevelFigures* g = at_level(figs, 3))
      md += "| issue 17: CG iterations at level 3 ≤ 40 per stepped frame | " +
            f("%.1f", g->cg_per_step) + " | " +
            (std::isfinite(g->cg_per_step) ? met(g->cg_per_step <= 40) : "no data") + " |\n";
  }
  for (const std::string& drill : drills) {
    if (baseline.empty()) {
      md += "| issue 17: accuracy against the reference no worse than today's default, " + drill +
            " | no baseline (perf/results/sweep_baseline.json) | not judged |\n";
      continue;
    }
    const auto [level, margin] = worst_accuracy_margin(rows, baseline, drill, max_level);
    if (level < 0) {
      md += "| issue 17: accuracy against the reference no worse than today's default, " + drill +
            " | no level with both errors | not judged |\n";
      continue;
    }
    const SweepRow* now = find_row(rows, drill, level, 1);
    double then_err = kNaN;
    for (const auto& b : baseline)
      if (b.r.config.drill == drill && b.r.config.level == level) then_err = b.error_pct;
    md += "| issue 17: accuracy against the reference no worse than today's default, " + drill +
          " (every level) | worst level " + std::to_string(level) + ": " +
          f("%.2f", now ? now->error_pct : kNaN) + " % against " + f("%.2f", then_err) +
          " % before | " + met(margin <= 1e-9) + " |\n";
  }
  return md;
}

std::string why_missed_md(const std::vector<SweepRow>& rows, const std::vector<std::string>& drills,
                          int max_level, const std::vector<SweepRow>& baseline) {
  std::string md;
  if (has(drills, "capsulorhexis")) {
    const auto figs = level_figures(rows, "capsulorhexis", max_level);
    for (const auto& [level, p99, mx] : {std::tuple{3, 4.0, 8.0}, std::tuple{8, 16.7, 33.0}}) {
      const SweepRow* r2 = find_row(rows, "capsulorhexis", level, 2);
      if (!r2 || (r2->r.frame.p99_ms <= p99 && r2->r.frame.max_ms <= mx)) continue;
      const auto& r = r2->r;
      const auto [name, worst] = costliest_worst_frame(r);
      const double refresh_max = physics_number(r, "capsule_cutting", "physics_refresh_ms_max");
      const double edit_max = physics_number(r, "capsule_cutting", "edit_ms_max");
      md += "- **Capsulorhexis, level " + std::to_string(level) + ", 2 threads** (p99 " +
            f("%.2f", r.frame.p99_ms) + " ms, max " + f("%.1f", r.frame.max_ms) +
            " ms). The system with the slowest single frame is " + name + " (" + f("%.1f", worst) +
            " ms, " + f("%.0f", 100 * worst / r.frame.max_ms) +
            " % of the worst frame); its p99 is " +
            f("%.2f", system_cost(r, name, &CostSummary::p99_ms)) + " ms. capsule_dynamics: p99 " +
            f("%.2f", system_cost(r, "capsule_dynamics", &CostSummary::p99_ms)) + " ms, max " +
            f("%.1f", system_cost(r, "capsule_dynamics", &CostSummary::max_ms)) + " ms, " +
            f("%.0f", cg_iterations_per_step(r)) +
            " CG iterations per stepped frame. The physics refresh after a cut: up to " +
            f("%.1f", refresh_max) + " ms (" + f("%.0f", 100 * refresh_max / r.frame.max_ms) +
            " % of the worst frame), the cut's edit up to " + f("%.2f", edit_max) + " ms, " +
            f("%.0f", physics_number(r, "capsule_cutting", "topology_changes")) +
            " topology changes in the drill.\n";
    }
    const PowerFit rf = slope_over_levels(figs, &LevelFigures::refresh_ms_mean, 0, 8);
    if (rf.ok && rf.slope > 0.25) {
      const LevelFigures& hi = figs.back();
      md += "- **Physics refresh per cut** grows as elements^" + fmt("%.2f", rf.slope) + ": mean " +
            f("%.1f", 1e3 * hi.refresh_ms_mean) + " µs, max " + f("%.0f", 1e3 * hi.refresh_ms_max) +
            " µs at level " + std::to_string(hi.level) + " (" + fmt("%.0f", hi.elements) +
            " capsule vertices), against a worst cut edit of " + f("%.2f", hi.cut_edit_ms_max) +
            " ms there.";
      // What the refresh touches: a finer mesh's tear crosses more springs per frame, and the
      // refresh patches each (docs/cutting_and_tearing.md).
      const PowerFit springs = slope_over_levels(figs, &LevelFigures::refresh_springs, 0, 8);
      const PowerFit per_spring =
          slope_over_levels(figs, &LevelFigures::refresh_ms_per_spring, 0, 8);
      if (springs.ok && per_spring.ok)
        md += " The springs a refresh patches grow as elements^" + fmt("%.2f", springs.slope) +
              " (" + f("%.1f", figs.front().refresh_springs) + " at level " +
              std::to_string(figs.front().level) + ", " + f("%.1f", hi.refresh_springs) +
              " at level " + std::to_string(hi.level) +
              "), its cost per patched spring as elements^" + fmt("%.2f", per_spring.slope) + ".";
      md += "\n";
    }
    std::string low;
    for (const auto& g : figs)
      if (std::isfinite(g.speedup) && (g.speedup < 0.95 || (g.level >= 6 && g.speedup < 1.5)))
        low += (low.empty() ? "" : ", ") + std::to_string(g.level) + " (" + fmt("%.3f", g.mean_1) +
               " → " + fmt("%.3f", g.mean_2) + " ms in the first pair; " + speedup_text(g) + ")";
    if (!low.empty()) {
      md += "- **2-thread speed-up short** at levels " + low + ".";
      for (int level : {3, max_level}) {
        const double alone = speedup(find_row(rows, "capsulorhexis", level, 1, kNoHapticsVariant),
                                     find_row(rows, "capsulorhexis", level, 2, kNoHapticsVariant));
        if (std::isfinite(alone))
          md += " Without the haptic thread at level " + std::to_string(level) + ": " +
                fmt("%.2f", alone) + "×.";
        const double graph =
            speedup(find_row(rows, "capsulorhexis", level, 1, kGraphEveryFrameVariant),
                    find_row(rows, "capsulorhexis", level, 2, kGraphEveryFrameVariant));
        if (std::isfinite(graph))
          md += " With the flow graph every frame at level " + std::to_string(level) + ": " +
                fmt("%.2f", graph) + "×.";
        if (level == max_level) break;
      }
      md += "\n";
    }
    if (const LevelFigures* g = at_level(figs, 3); g && g->cg_per_step > 40) {
      const SweepRow* r = find_row(rows, "capsulorhexis", 3, 1);
      std::string pre;
      if (r && r->r.physics.contains("capsule") &&
          r->r.physics["capsule"].contains("preconditioner"))
        if (const auto& v = r->r.physics["capsule"]["preconditioner"]; v.is_string())
          pre = " with the " + v.get<std::string>() + " preconditioner";
      md += "- **CG iterations at level 3**: " + f("%.1f", g->cg_per_step) + " per stepped frame" +
            pre + ", over an active set of " +
            f("%.0f", r ? physics_number(r->r, "capsule", "active_particles_mean") : kNaN) +
            " nodes on average (max " +
            f("%.0f", r ? physics_number(r->r, "capsule", "active_particles_max") : kNaN) + ").\n";
    }
  }
  if (has(drills, "corneal_incision")) {
    const auto figs = level_figures(rows, "corneal_incision", max_level);
    const PowerFit fit = slope_over_levels(figs, &LevelFigures::cornea_cut_max_ms, 0, 8);
    if (fit.ok && fit.slope > 0.25 && !figs.empty())
      md += "- **The cornea's worst cut frame** grows as elements^" + fmt("%.2f", fit.slope) +
            " (r² " + fmt("%.2f", fit.r2) + "): " + f("%.2f", figs.front().cornea_cut_max_ms) +
            " ms at level " + std::to_string(figs.front().level) + ", " +
            f("%.2f", figs.back().cornea_cut_max_ms) + " ms at level " +
            std::to_string(figs.back().level) + ".\n";
  }
  for (const std::string& drill : drills) {
    if (baseline.empty()) break;
    const auto [level, margin] = worst_accuracy_margin(rows, baseline, drill, max_level);
    if (level < 0 || margin <= 1e-9) continue;
    const SweepRow* now = find_row(rows, drill, level, 1);
    md += "- **" + drill + " accuracy** at level " + std::to_string(level) + " is " +
          (margin > 1e299 ? std::string("unknown (a metric is missing)")
                          : fmt("%.2f", margin) + " points worse than before issue 17") +
          (now && !now->error_detail.empty() ? "; furthest off: " + now->error_detail : "") + ".\n";
  }
  return md.empty() ? "- Every issue-17 target that could be judged is met.\n" : md;
}

Placement placement_of(const SweepPointResult& r) {
  const double a = r.round_trip_before_ns, b = r.round_trip_after_ns;
  if (!std::isfinite(a) || !std::isfinite(b)) return Placement::Moved;
  if (a < kNearRoundTripNs && b < kNearRoundTripNs) return Placement::Near;
  if (a > kApartRoundTripNs && b > kApartRoundTripNs) return Placement::Apart;
  return Placement::Moved;
}

std::string speedup_pairs_md(const std::vector<SweepRow>& rows, int max_level) {
  static constexpr const char* kName[] = {"near", "apart", "moved"};
  std::string table;
  std::vector<double> by_placement[3];
  for (int level = 0; level <= max_level; ++level) {
    std::string cells;
    for (int rep = 1;; ++rep) {
      const std::string v = rep == 1 ? std::string("default") : repeat_variant(rep);
      const SweepRow* one = find_row(rows, "capsulorhexis", level, 1, v);
      const SweepRow* two = find_row(rows, "capsulorhexis", level, 2, v);
      if (!one && !two) break;
      const double s = speedup(one, two);
      if (!std::isfinite(s)) continue;
      const Placement p = placement_of(two->r);
      by_placement[int(p)].push_back(s);
      cells += (cells.empty() ? "" : ", ") + fmt("%.2f", s) + "× (" + kName[int(p)] + " " +
               f("%.0f", two->r.round_trip_before_ns) + "/" +
               f("%.0f", two->r.round_trip_after_ns) + " ns, " +
               f("%.0f", physics_number(two->r, "capsule", "team_steps")) + " team)";
    }
    if (!cells.empty()) table += "| " + std::to_string(level) + " | " + cells + " |\n";
  }
  if (table.empty()) return "";
  std::string summary;
  for (int p = 0; p < 3; ++p) {
    std::vector<double>& v = by_placement[p];
    if (v.empty()) continue;
    std::sort(v.begin(), v.end());
    const double median =
        v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
    summary += (summary.empty() ? "" : "; ") + std::string(kName[p]) + ": " +
               std::to_string(v.size()) + " pairs, median " + fmt("%.2f", median) + "× (" +
               fmt("%.2f", v.front()) + "–" + fmt("%.2f", v.back()) + "×)";
  }
  return "**The speed-up pair by pair** (capsulorhexis expert, default methods): each pair's "
         "1-thread mean over its 2-thread mean, with a cache line's round trip between the two "
         "CPUs just before and just after the 2-thread point's frames (perf/cores.hpp; near: both "
         "under " +
         fmt("%.0f", kNearRoundTripNs) + " ns, apart: both over " + fmt("%.0f", kApartRoundTripNs) +
         " ns, moved: in between, changed, or not measured) and the steps that point took on its "
         "team of two "
         "(systems/deform/team_choice.hpp). The host moves the two vCPUs within minutes, and a "
         "team pays only where they are near (docs/implicit_and_active.md).\n\n"
         "| level | pairs: speed-up (placement, round trip before/after, steps on the team) |\n"
         "|---:|---|\n" +
         table + "\nBy placement: " + summary + ".\n\n";
}

std::string frame_dispatch_md(const std::vector<SweepRow>& rows,
                              const std::vector<std::string>& drills) {
  std::string md;
  for (const std::string& drill : drills) {
    for (int level = 0; level <= 8; ++level) {
      const SweepRow* g1 = find_row(rows, drill, level, 1, kGraphEveryFrameVariant);
      const SweepRow* g2 = find_row(rows, drill, level, 2, kGraphEveryFrameVariant);
      if (!g1 || !g2) continue;
      const SweepRow* a1 = find_row(rows, drill, level, 1);
      const SweepRow* a2 = find_row(rows, drill, level, 2);
      const double serial = a2 && a2->r.frames > 0
                                ? 100.0 * double(a2->r.serial_frames) /
                                      double(a2->r.serial_frames + a2->r.graph_frames)
                                : kNaN;
      md += "| " + drill + " | " + std::to_string(level) + " | " + f("%.3f", g1->r.frame.mean_ms) +
            " → " + f("%.3f", g2->r.frame.mean_ms) + " ms, " + f("%.2f", speedup(g1, g2)) + "× | " +
            (a1 && a2 ? f("%.3f", a1->r.frame.mean_ms) + " → " + f("%.3f", a2->r.frame.mean_ms) +
                            " ms, " + f("%.2f", speedup(a1, a2)) + "×"
                      : std::string("–")) +
            " | " + f("%.0f", serial) + " % | " +
            f("%.2f", speedup(find_row(rows, drill, level, 1, kNoHapticsVariant),
                              find_row(rows, drill, level, 2, kNoHapticsVariant))) +
            "× |\n";
    }
  }
  if (md.empty()) return "";
  return "**Frame dispatch** (engine/schedule/executor.hpp): the 2-thread speed-up of the frame "
         "mean, 1 → 2 threads, with the flow graph every frame (the executor before Auto) and "
         "with Auto, which runs a frame's systems serially on the calling thread unless the work "
         "off the graph's critical path (from each system's moving-average cost) exceeds 0.05 ms; "
         "parallel loops inside a system use both threads either way.\n\n"
         "| drill | level | flow graph every frame | Auto (default) | 2-thread frames Auto ran "
         "serially | Auto, no haptic thread |\n|---|---:|---|---|---:|---:|\n" +
         md + "\n";
}

}  // namespace phaco::perf
