// phaco-perf membrane (issue 3): the membrane step's cost per level × threads × method with the
// fitted slope, thread scaling, the spring pass against this machine's memory bandwidth, a grasp
// with the active node set, Bullet btSoftBody on the same mesh, speed against accuracy at the real
// capsule material, and the stability map. Measurements live in membrane_methods.cpp; this file
// sweeps, tabulates, charts and writes the section.
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/membrane_fixture.hpp"
#include "perf/membrane_methods.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco::perf {

namespace {

namespace fs = std::filesystem;

struct CostRow {
  std::string method;
  int level = 0, threads = 1;
  uint32_t vertices = 0, springs = 0;
  double s_per_step = 0, dt = 0;
  std::string note;
  double ns_per_vertex() const { return 1e9 * s_per_step / vertices; }
};

// Triad GB/s from results/bandwidth.csv: where ("memory"/"cache") × threads; empty if absent.
std::map<std::pair<std::string, int>, double> read_triad(const fs::path& csv) {
  std::map<std::pair<std::string, int>, double> out;
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::vector<std::string> cells;
    std::stringstream ss(line);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (cells.size() == 5 && cells[1] == "triad")
      out[{cells[0], std::stoi(cells[2])}] = std::stod(cells[4]);
  }
  return out;
}

const CostRow* find(const std::vector<CostRow>& rows, const std::string& method, int level,
                    int threads) {
  for (const auto& r : rows) {
    if (r.method == method && r.level == level && r.threads == threads) return &r;
  }
  return nullptr;
}

std::string met_bold(bool ok) {
  return ok ? "**met**" : "**missed**";
}

}  // namespace

void run_membrane(const StudyOptions& options) {
  int max_level = options.quick ? 3 : 7;  // level 8 on request (--max-level 8)
  for (size_t i = 0; i < options.extra.size(); ++i) {
    if (options.extra[i] == "--max-level" && i + 1 < options.extra.size()) {
      max_level = option_int("membrane", "--max-level", options.extra[++i]);
      if (max_level < eye::kMinLevel || max_level > eye::kMaxLevel)
        throw InputError("membrane: --max-level out of 0.." + std::to_string(eye::kMaxLevel));
    } else {
      throw InputError("membrane: unknown option '" + options.extra[i] + "'");
    }
  }
  const fs::path dir = options.out_dir / "results";
  const std::string load = load_note();
  const double min_seconds = options.quick ? 0.02 : 0.15;
  const int accuracy_level = options.quick ? 1 : 3;
  const int active_small = options.quick ? 1 : 3, active_large = max_level;
  Progress progress((max_level + 1) * 2 + 2 + 2 + 1);

  // 1. Cost per level × threads × method.
  std::vector<CostRow> costs;
  std::map<int, std::pair<uint32_t, uint32_t>> sizes;
  std::vector<std::pair<int, ActiveSample>> active;
  for (int level = 0; level <= max_level; ++level) {
    FixtureOptions fo;
    fo.level = level;
    MembraneFixture f = make_membrane_fixture(fo);
    sizes[level] = {f.vertex_count(), f.spring_count()};
    for (int threads : {1, 2}) {
      progress.step("membrane: level " + std::to_string(level) + ", " + std::to_string(threads) +
                    " thread(s)");
      for (const CostSample& s : measure_costs(f, threads, min_seconds, true)) {
        costs.push_back({s.method, level, threads, f.vertex_count(), f.spring_count(),
                         s.seconds_per_step, s.dt_s, s.note});
      }
    }
    if (level == active_small || level == active_large) {
      progress.step("membrane: grasp with active set, level " + std::to_string(level));
      active.push_back({level, measure_active_grasp(f, 1, min_seconds)});
    }
  }
  progress.step("membrane: speed vs accuracy, level " + std::to_string(accuracy_level));
  LoadCase load_case;
  const std::vector<AccuracySample> accuracy =
      measure_accuracy(accuracy_level, options.quick, &load_case);
  progress.step("membrane: stability map");
  const std::vector<StabilitySample> stability = measure_stability(options.quick);
  progress.step("membrane: bandwidth, charts");
  const auto triad = read_triad(dir / "bandwidth.csv");
  progress.finish();

  // Table: every figure, one row each.
  Table t;
  t.columns = {"part",           "method",  "level",    "vertices",    "springs",
               "threads",        "setting", "dt_s",     "us_per_step", "ns_per_vertex_step",
               "cost_per_sim_s", "error",   "gb_per_s", "note"};
  for (const CostRow& r : costs) {
    double bytes = 0;
    if (r.method == "spring pass") bytes = spring_pass_bytes(r.vertices, r.springs);
    if (r.method == "plain step") bytes = plain_step_bytes(r.vertices, r.springs);
    t.add({std::string("cost"), r.method, double(r.level), double(r.vertices), double(r.springs),
           double(r.threads), std::string(""), r.dt, 1e6 * r.s_per_step, r.ns_per_vertex(),
           r.s_per_step / r.dt, NAN, bytes > 0 ? bytes / r.s_per_step * 1e-9 : NAN, r.note});
  }
  for (const auto& [level, a] : active) {
    t.add({std::string("active"), std::string("plain step, 5-hop active set"), double(level),
           double(sizes[level].first), double(sizes[level].second), 1.0,
           std::to_string(a.active_particles) + " active particles", NAN, 1e6 * a.seconds_per_step,
           NAN, NAN, NAN, NAN, std::to_string(a.active_springs) + " active springs"});
  }
  for (const AccuracySample& a : accuracy) {
    t.add({std::string("accuracy"), a.method, double(accuracy_level),
           double(sizes.count(accuracy_level) ? sizes[accuracy_level].first : 0), NAN, 1.0,
           a.setting, NAN, 1e6 * a.wall_s_per_frame, NAN, a.cost_per_sim_s, a.error, NAN,
           a.stable ? std::string("") : std::string("diverged")});
  }
  for (const StabilitySample& s : stability) {
    t.add({std::string("stability"), s.method, 0.0, NAN, NAN, 1.0, "k/m " + fmt("%.3g", s.k_over_m),
           s.dt_max_s, NAN, NAN, NAN, NAN, NAN,
           s.dt_theory_s > 0 ? "theory " + fmt("%.3g", s.dt_theory_s) + " s" : std::string("")});
  }
  write_csv(t, dir / "membrane.csv");
  write_json(t, dir / "membrane.json");

  // Charts.
  std::vector<std::string> methods;
  for (const CostRow& r : costs) {
    if (std::find(methods.begin(), methods.end(), r.method) == methods.end())
      methods.push_back(r.method);
  }
  Chart cost{"Membrane step cost vs size (capsule, 1 thread; dashed: 2 threads)",
             {"vertices", Scale::Log10},
             {"time per step (us)", Scale::Log10}};
  Chart per_vertex{"Cost per vertex per step (1 thread)",
                   {"vertices", Scale::Log10},
                   {"ns per vertex per step", Scale::Log10}};
  Chart scaling{"Thread scaling: time(1 thread) / time(2 threads)",
                {"vertices", Scale::Log10},
                {"speed-up on 2 threads", Scale::Linear, 0.0, 2.5}};
  for (const std::string& m : methods) {
    Series s1{m}, s2{m + " (2 threads)"}, pv{m}, sc{m};
    s1.fit_power_law = true;
    s2.dashed = true;
    s2.style = Style::Line;
    for (const CostRow& r : costs) {
      if (r.method != m) continue;
      (r.threads == 1 ? s1 : s2).x.push_back(r.vertices);
      (r.threads == 1 ? s1 : s2).y.push_back(1e6 * r.s_per_step);
      if (r.threads == 1) {
        pv.x.push_back(r.vertices), pv.y.push_back(r.ns_per_vertex());
        if (const CostRow* two = find(costs, m, r.level, 2))
          sc.x.push_back(r.vertices), sc.y.push_back(r.s_per_step / two->s_per_step);
      }
    }
    cost.series.push_back(s1);
    if (m == "plain step" || m == "implicit_euler") cost.series.push_back(s2);
    per_vertex.series.push_back(pv);
    if (!sc.x.empty()) scaling.series.push_back(sc);
  }
  for (const auto& [level, a] : active) {
    if (cost.series.empty() || level != active_large) continue;
    Series s{"grasp, 5-hop active set"};
    for (const auto& [l2, a2] : active)
      s.x.push_back(sizes[l2].first), s.y.push_back(1e6 * a2.seconds_per_step);
    cost.series.push_back(s);
  }
  per_vertex.markers = {{"target 8 ns", 8000, 8}, {"target 8 ns", 128000, 8}};
  scaling.markers = {{"target 1.8x", 128000, 1.8}};
  save_chart(cost, dir / "membrane_cost.png");
  save_chart(per_vertex, dir / "membrane_ns_per_vertex.png");
  save_chart(scaling, dir / "membrane_threads.png");

  Chart bw{"Achieved bandwidth vs this machine's triad",
           {"vertices", Scale::Log10},
           {"GB/s", Scale::Log10}};
  for (const char* m : {"spring pass", "plain step"}) {
    for (int threads : {1, 2}) {
      Series s{std::string(m) + ", " + std::to_string(threads) + " thread(s)"};
      s.dashed = threads == 2;
      for (const CostRow& r : costs) {
        if (r.method == m && r.threads == threads) {
          const double bytes = r.method == "spring pass" ? spring_pass_bytes(r.vertices, r.springs)
                                                         : plain_step_bytes(r.vertices, r.springs);
          s.x.push_back(r.vertices), s.y.push_back(bytes / r.s_per_step * 1e-9);
        }
      }
      bw.series.push_back(s);
    }
  }
  if (!sizes.empty()) {
    const double x0 = sizes.begin()->second.first, x1 = sizes.rbegin()->second.first;
    for (const auto& [key, gbs] : triad) {
      Series s{"triad, " + key.first + ", " + std::to_string(key.second) + "T"};
      s.style = Style::Line;
      s.dashed = true;
      s.x = {x0, x1}, s.y = {gbs, gbs};
      bw.series.push_back(s);
    }
  }
  save_chart(bw, dir / "membrane_bandwidth.png");

  Chart acc{"Speed vs accuracy: one frame after a point load (level " +
                std::to_string(accuracy_level) + ", E = 2 MPa)",
            {"wall seconds per simulated second (1 thread)", Scale::Log10},
            {"relative error vs static equilibrium", Scale::Log10, {}, {}}};
  acc.pareto_front = true;
  {
    std::vector<std::string> names;
    for (const auto& a : accuracy) {
      if (std::find(names.begin(), names.end(), a.method) == names.end()) names.push_back(a.method);
    }
    for (const auto& n : names) {
      Series s{n};
      for (const auto& a : accuracy) {
        if (a.method == n) s.x.push_back(a.cost_per_sim_s), s.y.push_back(a.error);
      }
      acc.series.push_back(s);
    }
    acc.markers = {{"real time", 1.0, 1e-3}};
  }
  save_chart(acc, dir / "membrane_accuracy.png");

  Chart stab{"Stability map: largest stable dt (deform::stability_map, patch, 200 steps)",
             {"max k/m (1/s^2)", Scale::Log10},
             {"largest stable dt (s)", Scale::Log10}};
  {
    std::vector<std::string> names;
    for (const auto& s : stability) {
      if (std::find(names.begin(), names.end(), s.method) == names.end()) names.push_back(s.method);
    }
    Series theory{"2/sqrt(8 k/m) (symplectic bound)"};
    theory.style = Style::Line;
    theory.dashed = true;
    for (const auto& n : names) {
      Series s{n};
      for (const auto& st : stability) {
        if (st.method != n) continue;
        s.x.push_back(st.k_over_m), s.y.push_back(st.dt_max_s);
        if (n == "symplectic_euler")
          theory.x.push_back(st.k_over_m), theory.y.push_back(st.dt_theory_s);
      }
      stab.series.push_back(s);
    }
    stab.series.push_back(theory);
  }
  save_chart(stab, dir / "membrane_stability.png");

  // Section.
  const std::string cmd =
      std::string("phaco-perf membrane") + (options.quick ? " --quick" : "") +
      (max_level != (options.quick ? 3 : 7) ? " --max-level " + std::to_string(max_level) : "");
  std::string md = "## Membrane (issue 3)\n\n";
  md += "Measured by `" + cmd + "`, " + load +
        " (on 2 cores, a load above 1 slows every figure and flattens thread "
        "scaling). The anterior capsule of the standard eye per level (curvilinear layout), rim "
        "anchored, E = 2000 kPa, h = 0.013 mm, rho = 1000 kg/m^3, pre-stretch 2 %, linear springs, "
        "area-weighted. "
        "Every method is timed under a 50 Hz, 0.01 mN point load at the centre, best of 3 runs. "
        "Explicit steps "
        "run at 0.9 x their stable step (Gershgorin bound 2/sqrt(max sum k/m)), implicit ones and "
        "XPBD at 1/120 s. "
        "Bullet btSoftBody: same vertices, springs, triangles, masses and rest lengths "
        "(perf/peers/bullet_membrane.hpp "
        "documents the stiffness mapping), 1 position iteration, dt = 1/120 s.\n\n";
  md +=
      "![cost](results/membrane_cost.png)\n\n![ns per "
      "vertex](results/membrane_ns_per_vertex.png)\n\n";
  md += "### Cost per vertex per step (ns), 1 and 2 threads\n\n| method |";
  std::string sep = "|---|";
  for (const auto& [level, sz] : sizes)
    md += " L" + std::to_string(level) + " (" + std::to_string(sz.first) + ") |", sep += "---:|";
  md += "\n" + sep + "\n";
  for (const std::string& m : methods) {
    for (int threads : {1, 2}) {
      if (!find(costs, m, 0, threads) && !find(costs, m, max_level, threads)) continue;
      md += "| " + m + " (" + std::to_string(threads) + "T) |";
      for (const auto& [level, sz] : sizes) {
        const CostRow* r = find(costs, m, level, threads);
        md += r ? " " + fmt("%.1f", r->ns_per_vertex()) + " |" : " |";
      }
      md += "\n";
    }
  }
  md += "\nFitted slope of time per step against vertices (1 thread, levels 0.." +
        std::to_string(max_level) + "): ";
  for (const std::string& m : methods) {
    std::vector<double> x, y;
    for (const CostRow& r : costs) {
      if (r.method == m && r.threads == 1) x.push_back(r.vertices), y.push_back(r.s_per_step);
    }
    const PowerFit fit = fit_power_law(x, y);
    if (fit.ok) md += m + " " + fmt("%.2f", fit.slope) + "; ";
  }
  md += "\n\n![threads](results/membrane_threads.png)\n\n";

  // Targets.
  md += "### Targets\n\n| target | measured | verdict |\n|---|---|---|\n";
  auto level_near = [&](uint32_t v) {
    int best = -1;
    for (const auto& [level, sz] : sizes) {
      if (best < 0 || std::fabs(std::log(double(sz.first) / v)) <
                          std::fabs(std::log(double(sizes[best].first) / v)))
        best = level;
    }
    return best;
  };
  const int l8k = level_near(8000), l128k = level_near(128000);
  for (int level : {l8k, l128k}) {
    if (const CostRow* r = find(costs, "plain step", level, 1)) {
      md += "| membrane step <= 8 ns/vertex/step, 1 core, " + std::to_string(r->vertices) +
            " vertices | " + fmt("%.2f", r->ns_per_vertex()) + " ns | " +
            met_bold(r->ns_per_vertex() <= 8) + " |\n";
    }
  }
  if (const CostRow* a = find(costs, "plain step", l128k, 1); a) {
    if (const CostRow* b = find(costs, "plain step", l128k, 2)) {
      const double s = a->s_per_step / b->s_per_step;
      md += "| >= 1.8x on 2 threads at " + std::to_string(a->vertices) + " vertices | " +
            fmt("%.2f", s) + "x | " + met_bold(s >= 1.8) + " |\n";
    }
  }
  for (int level : {l8k, l128k}) {
    const CostRow* ours = find(costs, "plain step", level, 1);
    const CostRow* bt = find(costs, "btSoftBody", level, 1);
    if (ours && bt) {
      const double ratio = bt->s_per_step / ours->s_per_step;
      md += "| >= 15x faster per step than btSoftBody, " + std::to_string(ours->vertices) +
            " vertices | " + fmt("%.1f", ratio) + "x (btSoftBody " +
            fmt("%.0f", bt->ns_per_vertex()) + " ns/node) | " + met_bold(ratio >= 15) + " |\n";
    }
  }
  if (active.size() >= 2) {
    const double ratio =
        active.back().second.seconds_per_step / active.front().second.seconds_per_step;
    md += "| grasp-active step at " + std::to_string(sizes[active.back().first].first) +
          " vertices within 2x of " + std::to_string(sizes[active.front().first].first) + " | " +
          fmt("%.2f", ratio) + "x (" + fmt("%.1f", 1e6 * active.back().second.seconds_per_step) +
          " vs " + fmt("%.1f", 1e6 * active.front().second.seconds_per_step) + " us, " +
          std::to_string(active.back().second.active_particles) + " active particles) | " +
          met_bold(ratio <= 2) + " |\n";
  }
  md += "| hot tables <= 64 B/vertex | " + fmt("%.0f", hot_bytes_per_vertex()) +
        " B (particles x, y, z, vx, vy, vz, inv_mass: 7 floats + kind 1 B; forces 3 floats) | " +
        met_bold(hot_bytes_per_vertex() <= 64) + " |\n";
  md += "| hot tables <= 16 B/spring | " + fmt("%.0f", hot_bytes_per_spring()) +
        " B (i, j, rest_length, stiffness) | " + met_bold(hot_bytes_per_spring() <= 16) + " |\n\n";

  // Bandwidth.
  md += "### The spring pass against the memory bandwidth\n\n";
  md +=
      "Bytes a pass must move at least once: the spring pass reads 16 B per spring and, per "
      "vertex, positions "
      "(12 B) and forces (12 B read + 12 B written); the plain step adds the node pass (x, v, "
      "inv_mass, f read; x, "
      "v, f written). Triad figures from the bandwidth section (`phaco-perf bandwidth`)";
  md += triad.empty() ? " — not measured yet, run `phaco-perf bandwidth`.\n\n" : ".\n\n";
  md +=
      "| level | vertices | spring pass 1T (GB/s) | spring pass 2T (GB/s) | plain step 1T (GB/s) | "
      "plain step 2T (GB/s) |\n"
      "|---:|---:|---:|---:|---:|---:|\n";
  for (const auto& [level, sz] : sizes) {
    md += "| " + std::to_string(level) + " | " + std::to_string(sz.first) + " |";
    for (const char* m : {"spring pass", "plain step"}) {
      for (int threads : {1, 2}) {
        const CostRow* r = find(costs, m, level, threads);
        const double bytes = std::string(m) == "spring pass"
                                 ? spring_pass_bytes(sz.first, sz.second)
                                 : plain_step_bytes(sz.first, sz.second);
        md += r ? " " + fmt("%.1f", bytes / r->s_per_step * 1e-9) + " |" : " |";
      }
    }
    md += "\n";
  }
  for (const auto& [key, gbs] : triad)
    md += "\nTriad, " + key.first + ", " + std::to_string(key.second) +
          " thread(s): " + fmt("%.1f", gbs) + " GB/s.";
  md += "\n\n![bandwidth](results/membrane_bandwidth.png)\n\n";

  // Accuracy.
  md += "### Speed against accuracy at the real capsule material\n\n";
  md += "The load case: the level-" + std::to_string(accuracy_level) +
        " capsule laid flat (z = 0), relaxed to its "
        "pre-stretched equilibrium, then a " +
        fmt("%.3g", load_case.load_mn) +
        " mN point load at the centre for one "
        "frame (1/120 s), viscosity " +
        fmt("%.0f", load_case.viscosity_per_s) +
        " /s (critical for the fundamental "
        "mode with the tension estimate T = " +
        fmt("%.3g", load_case.tension_mn_mm) +
        " mN/mm, so the real membrane "
        "settles within the frame to 1e-9). Reference: the static equilibrium under the load "
        "(procedures/reference, "
        "Newton in double precision), centre deflection " +
        fmt("%.4g", 1e3 * load_case.reference_centre_deflection_mm) +
        " um. Error: ||u - u_ref|| / ||u_ref|| over the free particles after the frame; cost: wall "
        "time of the frame "
        "× 120 (wall seconds per simulated second, 1 thread). Mass scaling (plain step, mass xN) "
        "lengthens the stable "
        "step by sqrt(N) and slows the settling by N: its error is the price.\n\n";
  md += "![accuracy](results/membrane_accuracy.png)\n\n";
  md +=
      "| method | setting | wall per frame (us) | s per simulated s | error "
      "|\n|---|---|---:|---:|---:|\n";
  for (const auto& a : accuracy) {
    md += "| " + a.method + " | " + a.setting + " | " + fmt("%.1f", 1e6 * a.wall_s_per_frame) +
          " | " + fmt("%.3g", a.cost_per_sim_s) + " | " +
          (a.stable ? fmt("%.3g", a.error) : std::string("diverged")) + " |\n";
  }
  // Cheapest method reaching 1 % and 10 %.
  for (double tol : {0.1, 0.01}) {
    const AccuracySample* best = nullptr;
    for (const auto& a : accuracy) {
      if (a.stable && a.error <= tol && (!best || a.cost_per_sim_s < best->cost_per_sim_s))
        best = &a;
    }
    md += "\nCheapest within " + fmt("%.0f", 100 * tol) + " %: " +
          (best ? best->method + " (" + best->setting + "), " + fmt("%.3g", best->cost_per_sim_s) +
                      " s per simulated s."
                : std::string("none."));
  }
  md += "\n\n### Stability map\n\n";
  md +=
      "deform::stability_map (systems/deform/stability.hpp): the largest step at which each "
      "integrator keeps a "
      "rim-anchored 6 x 6 patch, displaced and released undamped, finite and within 10 x its "
      "initial energy for 200 "
      "steps, by bisection in omega·dt between 1e-3 and 1e3; spring k over decades at node masses "
      "1e-10 kg (the "
      "capsule's at level 3) and 1e-8 kg, plotted against k/m. A method stable over the whole "
      "range is drawn at "
      "its upper bound, 1e3/omega. Explicit Euler undamped is unstable at every step; over 200 "
      "steps it passes only "
      "while (1 + omega²dt²)^200 <= 10.\n\n![stability](results/membrane_stability.png)\n\n";
  md +=
      "| method | largest stable sqrt(k/m)·dt over the map (min .. max) | cells stable over the "
      "whole range |\n"
      "|---|---|---:|\n";
  {
    std::map<std::string, std::vector<const StabilitySample*>> by_method;
    for (const auto& s : stability) by_method[s.method].push_back(&s);
    for (const auto& [name, cells] : by_method) {
      double lo = INFINITY, hi = 0;
      int everywhere = 0;
      for (const StabilitySample* c : cells) {
        const double w = c->dt_max_s * std::sqrt(c->k_over_m);
        lo = std::min(lo, w), hi = std::max(hi, w);
        everywhere += c->stable_everywhere;
      }
      md += "| " + name + " | " + fmt("%.3g", lo) + " .. " + fmt("%.3g", hi) + " | " +
            std::to_string(everywhere) + " of " + std::to_string(cells.size()) + " |\n";
    }
  }
  write_section(dir, "membrane", md);
}

}  // namespace phaco::perf
