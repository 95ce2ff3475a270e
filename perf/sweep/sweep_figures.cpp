// The sweep's raw figures; see sweep_figures.hpp.
#include "perf/sweep/sweep_figures.hpp"

#include <cmath>
#include <fstream>

#include "engine/core/error.hpp"
#include "perf/report.hpp"

namespace phaco::perf {

namespace fs = std::filesystem;

void write_sweep_figures(const std::vector<SweepRow>& rows, const SweepRun& run,
                         const fs::path& dir) {
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
  if (!run.replot) {
    const nlohmann::json saved = {{"command", run.command},
                                  {"load", run.load},
                                  {"max_level", run.max_level},
                                  {"drills", run.drills},
                                  {"variant_levels", run.variant_levels},
                                  {"threads", run.threads},
                                  {"speedup_reps", run.speedup_reps},
                                  {"run_failures", run.run_failures},
                                  {"points", all}};
    std::ofstream(dir / "sweep_points.json") << saved.dump() << '\n';  // compact: ~1 MB indented
  }
}

SweepRun read_saved_sweep(const fs::path& dir, std::vector<SweepRow>& rows) {
  std::ifstream in(dir / "sweep_points.json");
  if (!in)
    throw InputError("sweep --replot: no " + (dir / "sweep_points.json").string() +
                     " to redraw from");
  SweepRun run;
  run.replot = true;
  try {
    const nlohmann::json saved = nlohmann::json::parse(in);
    run.command = saved.at("command").get<std::string>();
    run.load = saved.at("load").get<std::string>();
    run.max_level = saved.at("max_level");
    run.drills = saved.at("drills").get<std::vector<std::string>>();
    run.variant_levels = saved.at("variant_levels").get<std::vector<int>>();
    run.threads = saved.at("threads").get<std::vector<int>>();
    run.speedup_reps = saved.value("speedup_reps", 1);  // sweeps saved before the repeats: one
    run.run_failures = saved.at("run_failures").get<std::vector<std::string>>();
    for (const auto& j : saved.at("points")) {
      SweepRow row;
      row.r = result_from_json(j);
      row.elements = drill_elements(row.r);
      rows.push_back(std::move(row));
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError("sweep --replot: " + (dir / "sweep_points.json").string() + ": " + e.what());
  }
  return run;
}

}  // namespace phaco::perf
