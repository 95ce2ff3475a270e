// phaco-perf cohorts (issue 20 item 4): do the scores separate skill, as simulator validation
// studies show (Privett 2010, Thomsen 2015)? Per drill, a cohort of N scripted experts and one of
// N scripted novices (perf/cohorts: the drill's expert or a novice script each, with measured
// human tremor, timing and small technique variations), every member run to its end; the score
// distributions, their separation (ROC AUC) and the contrasting-groups pass/fail cut-off with the
// share of each cohort that passes.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/cohorts/cohort.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/scene/run.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kDrills = {"corneal_incision", "capsulorhexis", "phaco_sculpting",
                                          "nucleus_removal"};

struct DrillCohorts {
  std::string drill, run;  // run: which `phaco-perf cohorts` run the rows come from
  std::vector<double> experts, novices;
  int experts_failed = 0, novices_failed = 0;
  double auc = 0, cutoff = 0, experts_pass = 0, novices_pass = 0;
};

double share_at_or_above(const std::vector<double>& v, double cut) {
  if (v.empty()) return std::nan("");
  return static_cast<double>(
             std::count_if(v.begin(), v.end(), [&](double x) { return x >= cut; })) /
         static_cast<double>(v.size());
}

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? std::nan("") : s / static_cast<double>(v.size());
}

void summarise(DrillCohorts& c) {
  c.auc = roc_auc(c.experts, c.novices);
  c.cutoff = contrasting_groups_cutoff(c.experts, c.novices);
  c.experts_pass = share_at_or_above(c.experts, c.cutoff);
  c.novices_pass = share_at_or_above(c.novices, c.cutoff);
}

// Where a member's score went: each term that lost points, as "metric -points", most first.
std::string lost_points(const nlohmann::json& terms) {
  std::vector<std::pair<double, std::string>> lost;
  for (const auto& term : terms) {
    const double gone = term.value("weight", 0.0) - term.value("points", 0.0);
    if (gone > 0.05) lost.emplace_back(gone, term.value("metric", std::string("?")));
  }
  std::sort(lost.begin(), lost.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string out;
  char buf[32];
  for (const auto& [gone, metric] : lost) {
    std::snprintf(buf, sizeof buf, " -%.1f", gone);
    out += (out.empty() ? "" : "; ") + metric + buf;
  }
  return out;
}

// The rows of the drills not run this time, from the results of an earlier run (cohorts.json),
// so that `--drill X` adds X's rows without dropping the others'. Rows written before the run
// column existed say so.
std::vector<DrillCohorts> kept_rows(const fs::path& json, const std::vector<std::string>& run,
                                    Table& t) {
  std::vector<DrillCohorts> kept;
  std::ifstream in(json);
  if (!in) return kept;
  nlohmann::json rows;
  try {
    rows = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError("cohorts: cannot read the earlier results " + json.string() + ": " + e.what());
  }
  for (const std::string& drill : kDrills) {
    if (std::find(run.begin(), run.end(), drill) != run.end()) continue;
    DrillCohorts c;
    c.drill = drill;
    for (const auto& r : rows) {
      if (r.value("drill", "") != drill) continue;
      const bool expert = r.value("group", "") == "expert";
      const double score = r.value("score", 0.0);
      const bool failed = r.value("failed", 0.0) != 0.0;
      c.run = r.value("run", std::string("an earlier run (before runs were recorded)"));
      (expert ? c.experts : c.novices).push_back(score);
      (expert ? c.experts_failed : c.novices_failed) += failed;
      t.add({drill, r.value("group", ""), r.value("member", 0.0), r.value("script", ""),
             r.value("seed", 0.0), score, failed ? 1.0 : 0.0, r.value("lost", std::string()),
             c.run});
    }
    if (c.experts.empty() || c.novices.empty()) continue;
    summarise(c);
    kept.push_back(std::move(c));
  }
  return kept;
}

}  // namespace

void run_cohorts(const StudyOptions& options) {
  int n = options.quick ? 4 : 30;
  std::vector<std::string> drills;
  for (size_t i = 0; i < options.extra.size(); ++i) {
    const std::string& e = options.extra[i];
    if ((e == "--n" || e == "--drill") && i + 1 >= options.extra.size())
      throw InputError("cohorts: " + e + " needs a value");
    if (e == "--n") {
      const std::string v = options.extra[++i];
      n = std::atoi(v.c_str());
      if (n < 2 || n > 1000) throw InputError("cohorts: --n expects 2..1000, got '" + v + "'");
    } else if (e == "--drill") {
      const std::string d = options.extra[++i];
      if (std::find(kDrills.begin(), kDrills.end(), d) == kDrills.end())
        throw InputError("cohorts: unknown drill '" + d +
                         "'; expected corneal_incision, capsulorhexis, phaco_sculpting or "
                         "nucleus_removal");
      drills.push_back(d);
    } else {
      throw InputError("cohorts: unknown option '" + e + "'");
    }
  }
  if (drills.empty()) drills = kDrills;
  const std::string load = load_note();
  const fs::path dir = options.out_dir / "results";
  const fs::path scenarios = eye::data_dir() / "scenarios";
  SceneOptions scene;
  scene.cache_dir = dir / ".mesh-cache";

  Progress progress(static_cast<int>(drills.size()) * 2 * n + 1);
  Table t;
  t.columns = {"drill", "group", "member", "script", "seed", "score", "failed", "lost", "run"};
  // This run, as its section names it beside each drill's rows.
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  const std::string this_run = std::string(stamp) + ", --n " + std::to_string(n);
  std::vector<DrillCohorts> out;
  for (const std::string& drill : drills) {
    std::vector<fs::path> novices;
    for (const auto& e : fs::directory_iterator(scenarios))
      if (e.path().filename().string().rfind(drill + "_novice_", 0) == 0)
        novices.push_back(e.path());
    std::sort(novices.begin(), novices.end());
    if (novices.empty()) throw InputError("cohorts: no novice script for " + drill);
    const Scenario expert = load_scenario(scenarios / (drill + "_expert.json"));
    DrillCohorts c;
    c.drill = drill;
    c.run = this_run;
    // Every member, experts then novices; run two at a time (each scene on one thread), the
    // first alone so the meshes are cached before two scenes read them.
    struct Member {
      int group = 0, m = 0;
      fs::path script;
      uint64_t seed = 0;
      double score = 0;
      bool failed = false;
      std::string lost;  // the score terms that lost points, "metric -points; ..."
    };
    std::vector<Member> members;
    for (int group = 0; group < 2; ++group)
      for (int m = 0; m < n; ++m)
        members.push_back({group, m,
                           group == 0 ? scenarios / (drill + "_expert.json")
                                      : novices[size_t(m) % novices.size()],
                           1000003ull * uint64_t(group + 1) + uint64_t(m)});
    std::mutex lock;
    std::atomic<size_t> next{1};
    const auto run_member = [&](Member& mb) {
      {
        const std::lock_guard<std::mutex> g(lock);
        progress.step("cohorts: " + drill + (mb.group == 0 ? " expert " : " novice ") +
                      std::to_string(mb.m + 1));
      }
      const Scenario base = mb.group == 0 ? expert : load_scenario(mb.script);
      const RunReport r = run_scenario(
          cohort_member(base, mb.group == 0 ? expert_spec() : novice_spec(), mb.seed), scene);
      mb.score = r.metrics.value("score", 0.0);
      mb.failed = !r.complications.empty();
      mb.lost = lost_points(r.score_terms);
    };
    run_member(members.front());
    std::vector<std::thread> workers;
    std::exception_ptr error;
    for (int w = 0; w < 2; ++w)
      workers.emplace_back([&] {
        try {
          for (size_t i = next++; i < members.size(); i = next++) run_member(members[i]);
        } catch (...) {
          const std::lock_guard<std::mutex> g(lock);
          error = std::current_exception();
          next = members.size();
        }
      });
    for (auto& w : workers) w.join();
    if (error) std::rethrow_exception(error);
    for (const Member& mb : members) {
      (mb.group == 0 ? c.experts : c.novices).push_back(mb.score);
      (mb.group == 0 ? c.experts_failed : c.novices_failed) += mb.failed;
      t.add({drill, std::string(mb.group == 0 ? "expert" : "novice"), double(mb.m),
             mb.script.filename().string(), double(mb.seed), mb.score, mb.failed ? 1.0 : 0.0,
             mb.lost, this_run});
    }
    summarise(c);
    out.push_back(std::move(c));
  }
  progress.step("cohorts: writing");
  // The other drills' rows stay as an earlier run left them; every drill in kDrills order.
  for (DrillCohorts& c : kept_rows(dir / "cohorts.json", drills, t)) out.push_back(std::move(c));
  std::sort(out.begin(), out.end(), [](const DrillCohorts& a, const DrillCohorts& b) {
    return std::find(kDrills.begin(), kDrills.end(), a.drill) <
           std::find(kDrills.begin(), kDrills.end(), b.drill);
  });
  write_csv(t, dir / "cohorts.csv");
  write_json(t, dir / "cohorts.json");

  // A strip chart: each drill's experts and novices side by side, the cut-off across them.
  Chart chart{.title = "Scores of scripted expert and novice cohorts, per drill",
              .x = {.label = "drill: 1 incision, 2 capsulorhexis, 3 sculpting, 4 nucleus removal "
                             "(left experts, right novices)",
                    .min = 0.5,
                    .max = 4.5},
              .y = {.label = "score", .min = 0.0, .max = 105.0}};
  Series ex{.name = "experts", .style = Style::Scatter},
      nov{.name = "novices", .style = Style::Scatter};
  for (const DrillCohorts& c : out) {
    const double x =
        1.0 + double(std::find(kDrills.begin(), kDrills.end(), c.drill) - kDrills.begin());
    for (size_t i = 0; i < c.experts.size(); ++i)
      ex.x.push_back(x - 0.2 + 0.1 * double(i) / double(c.experts.size())),
          ex.y.push_back(c.experts[i]);
    for (size_t i = 0; i < c.novices.size(); ++i)
      nov.x.push_back(x + 0.1 + 0.1 * double(i) / double(c.novices.size())),
          nov.y.push_back(c.novices[i]);
    chart.series.push_back({.name = c.drill + " cut-off " + fmt("%.1f", c.cutoff),
                            .x = {x - 0.35, x + 0.35},
                            .y = {c.cutoff, c.cutoff},
                            .style = Style::Line,
                            .dashed = true});
  }
  chart.series.push_back(ex);
  chart.series.push_back(nov);
  save_chart(chart, dir / "cohorts.png");

  std::string md = "## Cohorts: do the scores separate skill? (issue 20 item 4)\n\n";
  std::string command = "phaco-perf cohorts --n " + std::to_string(n);
  if (drills.size() < kDrills.size())
    for (const std::string& d : drills) command += " --drill " + d;
  md += "Measured by `" + command + "` (" + this_run + "), " + load +
        ". Per drill, N scripted experts (the drill's expert script) and N scripted novices (its "
        "novice scripts in turn), each replayed with hand tremor (per axis "
        "a sinusoid at 8–12 Hz; RMS transverse 35 µm for experts and 59 µm for novices, axial 13 "
        "and 21 µm: FBG-forceps measurements on porcine eyes), a tempo factor (±5 % experts, ±15 "
        "% novices) and a constant offset of the hands (σ 0.05 mm and 0.15 mm per axis) "
        "(perf/cohorts). AUC: the probability that an expert outscores a novice (Mann–Whitney). "
        "Cut-off: the contrasting-groups method (Thomsen 2015), where normal densities fitted to "
        "the two groups cross (σ floored at 1 point); pass = score ≥ cut-off. The novices are "
        "scripted defects (docs/scoring.md), not a sample of real trainees: the figures show the "
        "scores respond to those defects under human-like noise, not how real novices score.\n\n";
  md +=
      "| drill | N per group | experts mean (min–max) | novices mean (min–max) | failed "
      "(complication) E / N | ROC AUC | cut-off | experts passing | novices passing | run |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const DrillCohorts& c : out) {
    const auto [emin, emax] = std::minmax_element(c.experts.begin(), c.experts.end());
    const auto [nmin, nmax] = std::minmax_element(c.novices.begin(), c.novices.end());
    md += "| " + c.drill + " | " + std::to_string(c.experts.size()) + " | " +
          fmt("%.1f", mean(c.experts)) + " (" + fmt("%.1f", *emin) + "–" + fmt("%.1f", *emax) +
          ") | " + fmt("%.1f", mean(c.novices)) + " (" + fmt("%.1f", *nmin) + "–" +
          fmt("%.1f", *nmax) + ") | " + std::to_string(c.experts_failed) + " / " +
          std::to_string(c.novices_failed) + " | " + fmt("%.3f", c.auc) + " | " +
          fmt("%.1f", c.cutoff) + " | " + fmt("%.0f %%", 100 * c.experts_pass) + " | " +
          fmt("%.0f %%", 100 * c.novices_pass) + " | " + c.run + " |\n";
  }
  std::string kept, missing;
  for (const std::string& d : kDrills) {
    if (std::find(drills.begin(), drills.end(), d) != drills.end()) continue;
    const bool has =
        std::any_of(out.begin(), out.end(), [&](const DrillCohorts& c) { return c.drill == d; });
    (has ? kept : missing) += ((has ? kept : missing).empty() ? "" : ", ") + d;
  }
  if (!kept.empty())
    md +=
        "\nNot run this time (`--drill` chose the others), their rows kept from the earlier run "
        "named in the run column: " +
        kept + ".\n";
  if (!missing.empty()) md += "\nNot run, and no earlier rows: " + missing + ".\n";
  md += "\n![cohort scores](results/cohorts.png)\n\n";
  write_section(dir, "cohorts", md);
  progress.finish();
}

}  // namespace phaco::perf
