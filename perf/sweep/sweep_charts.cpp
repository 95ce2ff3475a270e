// The sweep's charts (issue 9 item 3), drawn with engine/plot/chart.hpp on OpenCV.
#include <algorithm>
#include <cmath>
#include <set>

#include "perf/plot.hpp"
#include "perf/sweep/sweep_data.hpp"

namespace phaco::perf {

namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kDrills = {"capsulorhexis", "phaco_sculpting", "corneal_incision"};

std::vector<const SweepRow*> select(const std::vector<SweepRow>& rows, const std::string& drill,
                                    int threads, const std::string& variant = "default") {
  std::vector<const SweepRow*> out;
  for (const auto& row : rows) {
    if (row.r.ok && row.r.config.drill == drill && row.r.config.threads == threads &&
        row.r.config.variant == variant)
      out.push_back(&row);
  }
  std::sort(out.begin(), out.end(), [](const SweepRow* a, const SweepRow* b) {
    return a->r.config.level < b->r.config.level;
  });
  return out;
}

Series line(const std::string& name, const std::vector<const SweepRow*>& pts,
            double (*y)(const SweepRow&), bool fit, bool dashed = false) {
  Series s{.name = name, .fit_power_law = fit, .dashed = dashed};
  for (const SweepRow* p : pts) {
    s.x.push_back(p->elements);
    s.y.push_back(y(*p));
  }
  return s;
}

// A horizontal reference line across the elements' range.
Series level_line(const std::string& name, double y, double x0, double x1) {
  return Series{.name = name, .x = {x0, x1}, .y = {y, y}, .style = Style::Line, .dashed = true};
}

// The seeds' published figures as points on the frame-cost axes (simulation and rendering on
// 2006–2008 hardware; ours is the simulation alone).
std::vector<Marker> seed_markers(const std::string& drill) {
  if (drill == "phaco_sculpting")
    return {{"seed 000: 10 fps, 14,300 tets", 14300, 100.0},
            {"seed 002: 25 fps, 2,100 tets", 2100, 40.0}};
  if (drill == "capsulorhexis")
    return {{"seed 003: 60 fps, 2,005 vertices", 2005, 1000.0 / 60},
            {"seed 003: 50 fps tearing", 2005, 20.0}};
  return {};
}

}  // namespace

SweepChartFiles draw_sweep_charts(const std::vector<SweepRow>& rows, const fs::path& dir) {
  SweepChartFiles files;
  auto p50 = [](const SweepRow& r) { return r.r.frame.p50_ms; };
  auto p99 = [](const SweepRow& r) { return r.r.frame.p99_ms; };
  auto mx = [](const SweepRow& r) { return r.r.frame.max_ms; };

  for (const std::string& drill : kDrills) {
    const auto one = select(rows, drill, 1), two = select(rows, drill, 2);
    if (one.empty() && two.empty()) continue;
    double x0 = 1e300, x1 = 0;
    for (const auto* p : one) x0 = std::min(x0, p->elements), x1 = std::max(x1, p->elements);
    for (const auto* p : two) x0 = std::min(x0, p->elements), x1 = std::max(x1, p->elements);
    x0 = std::min(x0, 2000.0);
    Chart c{.title = drill + ": frame time against mesh size",
            .x = {.label = drill_elements_name(drill), .scale = Scale::Log10},
            .y = {.label = "frame time (ms)", .scale = Scale::Log10}};
    c.series.push_back(line("p50, 1 thread", one, +p50, true));
    c.series.push_back(line("p50, 2 threads", two, +p50, true, true));
    c.series.push_back(line("p99, 2 threads", two, +p99, false));
    c.series.push_back(line("max, 2 threads", two, +mx, false, true));
    c.series.push_back(level_line("60 Hz (16.7 ms)", 1000.0 / 60, x0, x1));
    c.series.push_back(level_line("240 Hz (4 ms)", 4.0, x0, x1));
    c.markers = seed_markers(drill);
    const std::string name = "sweep_frame_" + drill + ".png";
    save_chart(c, dir / name);
    files.frame_cost[drill] = name;

    // Per-system cost stacked: each line is the sum of the systems below it (means add up,
    // percentiles do not), 1 thread, against the level.
    if (!one.empty()) {
      const SweepRow& top = *one.back();
      std::vector<std::pair<double, std::string>> order;
      for (const auto& s : top.r.systems) order.push_back({s.mean_ms, s.name});
      std::sort(order.rbegin(), order.rend());
      Chart st{.title = drill + ": mean cost by system, stacked (1 thread)",
               .x = {.label = "resolution level"},
               .y = {.label = "mean time per frame (ms), cumulative"}};
      std::vector<double> below(one.size(), 0.0);
      for (const auto& [cost, sys] : order) {
        Series s{.name = "+ " + sys};
        for (size_t i = 0; i < one.size(); ++i) {
          for (const auto& c2 : one[i]->r.systems)
            if (c2.name == sys) below[i] += c2.mean_ms;
          s.x.push_back(one[i]->r.config.level);
          s.y.push_back(below[i]);
        }
        st.series.push_back(s);
      }
      Series frame{.name = "whole frame", .dashed = true};
      for (const auto* p : one) {
        frame.x.push_back(p->r.config.level);
        frame.y.push_back(p->r.frame.mean_ms);
      }
      st.series.push_back(frame);
      const std::string sname = "sweep_systems_" + drill + ".png";
      save_chart(st, dir / sname);
      files.systems[drill] = sname;
    }

    // Speed against accuracy: every variant's points over the levels it ran at.
    std::set<std::string> variants;
    for (const auto& row : rows)
      if (row.r.ok && row.r.config.drill == drill && row.r.config.threads == 1)
        if (!is_scaling_variant(row.r.config.variant)) variants.insert(row.r.config.variant);
    if (variants.size() > 1) {
      Chart pa{.title = drill + ": speed against accuracy (1 thread)",
               .x = {.label = "mean frame time (ms)", .scale = Scale::Log10},
               .y = {.label = "error against the reference (%)", .scale = Scale::Log10},
               .pareto_front = true};
      for (const std::string& v : variants) {
        Series s{.name = v == "default" ? "default methods, levels" : v,
                 .style = Style::LineAndMarkers};
        for (const SweepRow* p : select(rows, drill, 1, v)) {
          s.x.push_back(p->r.frame.mean_ms);
          s.y.push_back(p->error_pct);
        }
        pa.series.push_back(s);
      }
      const std::string pname = "sweep_pareto_" + drill + ".png";
      save_chart(pa, dir / pname);
      files.pareto[drill] = pname;
    }
  }

  // Thread scaling: mean frame time on 1 thread over that on 2.
  Chart th{.title = "Speed-up of the mean frame, 2 threads over 1",
           .x = {.label = "elements of the drill's body", .scale = Scale::Log10},
           .y = {.label = "speed-up (1-thread mean / 2-thread mean)", .min = 0.0, .max = 2.2}};
  double tx0 = 1e300, tx1 = 0;
  for (const std::string& drill : kDrills) {
    // 1-thread frame mean over the 2-thread one, per level both ran, for one variant.
    auto speedups = [&](const std::string& variant, Series s) {
      for (const auto* a : select(rows, drill, 1, variant))
        for (const auto* b : select(rows, drill, 2, variant))
          if (a->r.config.level == b->r.config.level && b->r.frame.mean_ms > 0) {
            s.x.push_back(a->elements);
            s.y.push_back(a->r.frame.mean_ms / b->r.frame.mean_ms);
          }
      return s;
    };
    const Series s = speedups("default", {.name = drill});
    for (double x : s.x) tx0 = std::min(tx0, x), tx1 = std::max(tx1, x);
    th.series.push_back(s);
    // The same without the haptic thread beside the frames (default level and the largest), and
    // with the flow graph every frame (the executor before its Auto dispatch).
    th.series.push_back(speedups(kNoHapticsVariant,
                                 {.name = drill + ", no haptic thread", .style = Style::Scatter}));
    const Series graph =
        speedups(kGraphEveryFrameVariant,
                 {.name = drill + ", flow graph every frame", .style = Style::Scatter});
    if (!graph.x.empty()) th.series.push_back(graph);
  }
  if (tx1 > 0) {
    th.series.push_back(level_line("target 1.5 (levels 6-8)", 1.5, tx0, tx1));
    th.series.push_back(level_line("floor 0.95", 0.95, tx0, tx1));
  }
  files.threads = "sweep_threads.png";
  save_chart(th, dir / files.threads);

  // Haptic period under load: ticks per µs of period (bins widen beyond 2 ms), per drill at the
  // default level and the largest, 2 simulation threads.
  Chart hp{.title = "Haptic period under load (2 simulation threads)",
           .x = {.label = "period (us)", .scale = Scale::Log10, .min = 500.0},
           .y = {.label = "ticks per us of period", .scale = Scale::Log10}};
  for (const std::string& drill : kDrills) {
    const auto two = select(rows, drill, 2);
    if (two.empty()) continue;
    std::vector<const SweepRow*> pick;
    for (const auto* p : two)
      if (p->r.config.level == 3) pick.push_back(p);
    if (two.back()->r.config.level != 3) pick.push_back(two.back());
    for (const auto* p : pick) {
      if (p->r.haptic_ticks < 1000) continue;  // too short a run to say anything
      Series s{.name = drill + " level " + std::to_string(p->r.config.level),
               .style = Style::Scatter};
      for (const auto& b : p->r.period_bins) {
        s.x.push_back(b[0] + 0.5 * b[1]);
        s.y.push_back(b[2] / b[1]);
      }
      hp.series.push_back(s);
    }
  }
  files.haptics = "sweep_haptics.png";
  save_chart(hp, dir / files.haptics);

  // Resident memory per element.
  Chart me{.title = "Peak resident memory per element (1 thread)",
           .x = {.label = "elements of every body (particles + triangles + tets)",
                 .scale = Scale::Log10},
           .y = {.label = "bytes per element", .scale = Scale::Log10}};
  for (const std::string& drill : kDrills) {
    Series s{.name = drill};
    for (const auto* p : select(rows, drill, 1)) {
      s.x.push_back(double(p->r.total_elements));
      s.y.push_back(p->r.bytes_per_element);
    }
    me.series.push_back(s);
  }
  files.memory = "sweep_memory.png";
  save_chart(me, dir / files.memory);
  return files;
}

}  // namespace phaco::perf
