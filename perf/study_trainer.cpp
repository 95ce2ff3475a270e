// phaco-perf trainer (issue 8): phaco-trainer on Mesa's software renderer (llvmpipe) under Xvfb at
// 1280×720, every drill at the default eye with both hands on scripted devices through the 1 kHz
// loop: the render frame rate and frame times, and beside them the simulation rate and the haptic
// period — once rendering, once with the same loop drawing nothing (--no-render), to show that
// rendering does not slow the simulation or the haptic thread (DESIGN.md §5). The trainer runs as
// its own process, exactly as a trainee starts it; it writes its figures with --stats. Then the
// scripted expert's whole procedure (issue 20, phaco-trainer --procedure), render on and off.

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"
#include "perf/trainer_run.hpp"
#include "procedures/eye/eye_params.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

constexpr double kTargetFps = 30.0;

std::string trainer_met(bool ok) {
  return ok ? "met" : "**missed**";
}

// "name on/off before → after, ..." for the runs.
std::string loads(const std::vector<const TrainerRun*>& runs) {
  std::string out;
  for (const TrainerRun* r : runs) {
    out += (out.empty() ? "" : ", ") + r->drill + (r->render ? "" : " (render off)") + " " +
           fmt("%.1f", r->load_before) + " → " + fmt("%.1f", r->load_after);
  }
  return out;
}

// The scripted expert's procedure (issue 20): every step, each on the eye the steps before it
// left; the trainer writes its figures when the procedure closes (--quick: after `quick_s`).
TrainerRun run_procedure(const fs::path& bin, const fs::path& dir, const fs::path& file,
                         bool render, std::optional<double> quick_s) {
  const std::string after = quick_s ? std::to_string(*quick_s) : std::string("3600");
  return run_trainer(bin, dir, "procedure", "--procedure " + file.string(),
                     "--stats-after " + after + " --timeout 3600", render);
}

// Why a haptic period ran long (the trainer's --stats `haptic_loop`): the wake-up's lateness and
// the tick's own compute at p99, and the deadlines skipped.
std::string loop_why(const nlohmann::json& stats) {
  const nlohmann::json loop = stats.value("haptic_loop", nlohmann::json::object());
  if (loop.empty()) return "—";
  const auto p99 = [&](const char* part) {
    return loop.value(part, nlohmann::json::object()).value("p99_us", 0.0);
  };
  return fmt("%.0f", p99("lateness")) + " / " + fmt("%.0f", p99("compute")) + ", " +
         fmt("%.0f", loop.value("overruns", 0.0));
}

// The procedure's section: the whole run's figures, then each step's (render on).
std::string procedure_section(const TrainerRun& on, const TrainerRun& off, const fs::path& file,
                              bool quick) {
  const auto& a = on.stats;
  const auto& b = off.stats;
  std::string md =
      "### The whole procedure (issue 20)\n\n`phaco-trainer --procedure " +
      file.filename().string() +
      "` (the scripted expert's four steps in one eye, at the procedure file's eye "
      "level; both hands on scripted devices) under the same Xvfb, " +
      (quick ? std::string("the first ") + fmt("%.0f", a.value("wall_s", 0.0)) + " s (--quick)"
             : std::string("from its start to its end")) +
      "; the haptic loop and the frame count restart with each step (the next step's loop "
      "starting from the spin margin the last one learned). The procedure's haptic period "
      "p50 / p99 is pooled over every tick of every step (the steps' histograms merged: the "
      "target's \"p99 over the procedure\"); the worst step's own p99 is beside it. The "
      "simulation rate is the steps' frames over the whole wall time (step changes included). "
      "Targets: 30 fps, haptic period p99 ≤ 1020 us.\n\n";
  md +=
      "| run | fps | frame p50 / p99 ms | target 30 fps | simulation Hz | haptic period p50 / "
      "p99 us, pooled | target p99 ≤ 1020 us | worst step's p99 us | wall s |\n"
      "|---|---|---|---|---|---|---|---|---|\n";
  for (const TrainerRun* r : {&on, &off}) {
    const auto& s = r->stats;
    const double f = s.value("fps", 0.0);
    const double p99 = s.value("haptic_period_p99_us", 0.0);
    md += std::string("| ") + (r->render ? "render on" : "render off") + " | " +
          (r->render ? fmt("%.1f", f) : std::string("—")) + " | " +
          (r->render ? fmt("%.1f", s.value("frame_p50_ms", 0.0)) + " / " +
                           fmt("%.1f", s.value("frame_p99_ms", 0.0))
                     : std::string("—")) +
          " | " + (r->render ? trainer_met(f >= kTargetFps) : std::string("—")) + " | " +
          fmt("%.1f", s.value("sim_rate_hz", 0.0)) + " | " +
          fmt("%.0f", s.value("haptic_period_p50_us", 0.0)) + " / " + fmt("%.0f", p99) + " | " +
          trainer_met(p99 <= 1020.0) + " | " +
          fmt("%.1f", s.value("haptic_period_worst_step_p99_us", 0.0)) + " | " +
          fmt("%.0f", s.value("wall_s", 0.0)) + " |\n";
  }
  md +=
      "\n| step | fps (render on) | wall s | simulated s | simulation Hz | haptic period p50 / "
      "p99 us, render on (off) | lateness / compute p99 us, overruns |\n"
      "|---|---|---|---|---|---|---|\n";
  const auto steps_a = a.value("steps", nlohmann::json::array());
  const auto steps_b = b.value("steps", nlohmann::json::array());
  for (size_t i = 0; i < steps_a.size(); ++i) {
    const auto& s = steps_a[i];
    const double wall = s.value("wall_s", 0.0);
    md += "| " + s.value("drill", std::string("?")) + " | " + fmt("%.1f", s.value("fps", 0.0)) +
          " | " + fmt("%.0f", wall) + " | " + fmt("%.1f", s.value("sim_time_s", 0.0)) + " | " +
          fmt("%.1f", wall > 0 ? s.value("sim_frames", 0.0) / wall : 0.0) + " | " +
          fmt("%.0f", s.value("haptic_period_p50_us", 0.0)) + " / " +
          fmt("%.0f", s.value("haptic_period_p99_us", 0.0));
    if (i < steps_b.size())
      md += " (" + fmt("%.0f", steps_b[i].value("haptic_period_p50_us", 0.0)) + " / " +
            fmt("%.0f", steps_b[i].value("haptic_period_p99_us", 0.0)) + ")";
    md += " | " + loop_why(s) + " |\n";
  }
  return md + "\n";
}

void add_row(Table& t, const TrainerRun& r) {
  const auto& s = r.stats;
  t.add(
      {r.drill, r.render ? "on" : "off", s.value("renderer", std::string("?")), s.value("fps", 0.0),
       s.value("frame_p50_ms", 0.0), s.value("frame_p99_ms", 0.0), s.value("sim_rate_hz", 0.0),
       s.value("haptic_period_p50_us", 0.0), s.value("haptic_period_p99_us", 0.0),
       // A drill is its own only step.
       s.value("haptic_period_worst_step_p99_us", s.value("haptic_period_p99_us", 0.0)),
       s.value("haptic_ticks", 0.0), s.value("snapshots_published", 0.0), s.value("wall_s", 0.0)});
}

}  // namespace

void run_trainer_study(const StudyOptions& options) {
  for (const auto& e : options.extra) throw InputError("trainer: unknown option '" + e + "'");
  const std::string load = load_note();
  const fs::path dir = options.out_dir / "results";
  const fs::path bin = trainer_binary();
  const double seconds = options.quick ? 5 : 20;
  const std::array<std::string, 4> drills = {"capsulorhexis", "phaco_sculpting", "corneal_incision",
                                             "nucleus_removal"};
  Progress progress(static_cast<int>(drills.size()) * 2 + 3);
  std::vector<TrainerRun> runs;
  for (const auto& d : drills) {
    for (bool render : {true, false}) {
      progress.step("trainer: " + d + (render ? "" : " (no render)"));
      runs.push_back(run_trainer_drill(bin, dir, d, render, seconds));
    }
  }
  const fs::path procedure = eye::data_dir() / "procedures" / "cataract_expert.json";
  std::array<TrainerRun, 2> procedure_runs;
  for (bool render : {true, false}) {
    progress.step(std::string("trainer: the expert procedure") + (render ? "" : " (no render)"));
    procedure_runs[render ? 0 : 1] = run_procedure(
        bin, dir, procedure, render, options.quick ? std::optional<double>(30) : std::nullopt);
  }
  progress.step("trainer: writing");

  Table t;
  t.columns = {"drill",         "render",
               "renderer",      "fps",
               "frame_p50_ms",  "frame_p99_ms",
               "sim_rate_hz",   "haptic_p50_us",
               "haptic_p99_us", "haptic_worst_step_p99_us",
               "haptic_ticks",  "snapshots_published",
               "wall_s"};
  std::string md = "## The trainer: frame rate on the software renderer (issue 8)\n\n";
  md +=
      std::string("Measured by `phaco-perf trainer") + (options.quick ? " --quick" : "") + "`, " +
      load + ". `phaco-trainer` under Xvfb at " + std::to_string(kTrainerWidth) + "×" +
      std::to_string(kTrainerHeight) +
      ", the default eye (level 3), both hands on scripted devices " + "through the 1 kHz loop, " +
      fmt("%.0f", seconds) +
      " s per run; *render off* is the same process and loop drawing nothing. The simulation's "
      "target rate is 1/dt = 120 Hz, the haptic period 1000 us; the render target is 30 fps. "
      "A haptic period runs long when the thread wakes late (lateness: wake-up after the deadline) "
      "or a tick's own work (compute: the device, the local haptic model, the force) outlasts "
      "the period (overruns: deadlines skipped).\n\n";
  md +=
      "| drill | renderer | fps | frame p50 / p99 ms | target 30 fps | simulation Hz (render off) "
      "| "
      "haptic period p50 / p99 us (render off) | lateness / compute p99 us, overruns |\n"
      "|---|---|---|---|---|---|---|---|\n";
  Chart chart{.title = "phaco-trainer on llvmpipe at 1280x720",
              .x = {.label = "drill (1 rhexis, 2 sculpting, 3 incision, 4 nucleus)"},
              .y = {.label = "rate (Hz)", .scale = Scale::Log10}};
  Series fps{.name = "render fps", .style = Style::LineAndMarkers},
      sim{.name = "simulation Hz, rendering", .style = Style::LineAndMarkers},
      sim_off{.name = "simulation Hz, render off", .style = Style::LineAndMarkers, .dashed = true};
  for (size_t i = 0; i + 1 < runs.size(); i += 2) {
    const auto& on = runs[i].stats;
    const auto& off = runs[i + 1].stats;
    const double f = on.value("fps", 0.0);
    md += "| " + runs[i].drill + " | " + on.value("renderer", std::string("?")) + " | " +
          fmt("%.1f", f) + " | " + fmt("%.1f", on.value("frame_p50_ms", 0.0)) + " / " +
          fmt("%.1f", on.value("frame_p99_ms", 0.0)) + " | " + trainer_met(f >= kTargetFps) +
          " | " + fmt("%.1f", on.value("sim_rate_hz", 0.0)) + " (" +
          fmt("%.1f", off.value("sim_rate_hz", 0.0)) + ") | " +
          fmt("%.0f", on.value("haptic_period_p50_us", 0.0)) + " / " +
          fmt("%.0f", on.value("haptic_period_p99_us", 0.0)) + " (" +
          fmt("%.0f", off.value("haptic_period_p50_us", 0.0)) + " / " +
          fmt("%.0f", off.value("haptic_period_p99_us", 0.0)) + ") | " + loop_why(on) + " |\n";
    const double x = static_cast<double>(i / 2 + 1);
    fps.x.push_back(x), fps.y.push_back(f);
    sim.x.push_back(x), sim.y.push_back(on.value("sim_rate_hz", 0.0));
    sim_off.x.push_back(x), sim_off.y.push_back(off.value("sim_rate_hz", 0.0));
    for (const TrainerRun* r : {&runs[i], &runs[i + 1]}) {
      add_row(t, *r);
    }
  }
  for (const TrainerRun& r : procedure_runs) add_row(t, r);
  chart.series = {fps, sim, sim_off};
  save_chart(chart, dir / "trainer_rates.png");
  write_csv(t, dir / "trainer.csv");
  write_json(t, dir / "trainer.json");
  md += "\n![trainer rates](results/trainer_rates.png)\n\n";
  md += procedure_section(procedure_runs[0], procedure_runs[1], procedure, options.quick);
  std::vector<const TrainerRun*> all;
  for (const TrainerRun& r : runs) all.push_back(&r);
  for (const TrainerRun& r : procedure_runs) all.push_back(&r);
  md +=
      "1-min load average before → after each run (above 2, other processes shared the 2 cores "
      "with the trainer): " +
      loads(all) + ".\n\n";
  write_section(dir, "trainer", md);
  progress.finish();
}

}  // namespace phaco::perf
