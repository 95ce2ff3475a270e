// phaco-perf trainer (issue 8): phaco-trainer on Mesa's software renderer (llvmpipe) under Xvfb at
// 1280×720, every drill at the default eye with both hands on scripted devices through the 1 kHz
// loop: the render frame rate and frame times, and beside them the simulation rate and the haptic
// period — once rendering, once with the same loop drawing nothing (--no-render), to show that
// rendering does not slow the simulation or the haptic thread (DESIGN.md §5). The trainer runs as
// its own process, exactly as a trainee starts it; it writes its figures with --stats.
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/plot.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

constexpr int kWidth = 1280, kHeight = 720;
constexpr double kTargetFps = 30.0;

// phaco-trainer beside this executable's build: <build>/perf/phaco-perf → <build>/apps/.
fs::path trainer_binary() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const fs::path bin = self.parent_path().parent_path() / "apps" / "phaco-trainer";
  if (ec || !fs::exists(bin)) {
    throw InputError("trainer: phaco-trainer not found at " + bin.string() +
                     " (build the target phaco-trainer)");
  }
  return bin;
}

struct TrainerRun {
  std::string drill;
  bool render = true;
  nlohmann::json stats;
};

TrainerRun run_trainer(const fs::path& bin, const fs::path& dir, const std::string& drill,
                       bool render, double seconds) {
  const fs::path out = dir / ("trainer_" + drill + (render ? "" : "_norender") + ".stats.json");
  fs::remove(out);
  // The drill runs longer than the measurement: the scripted hands hold their last pose.
  const std::string cmd = "xvfb-run -a -s '-screen 0 " + std::to_string(kWidth) + "x" +
                          std::to_string(kHeight) + "x24' " + bin.string() + " --drill " + drill +
                          " --left scripted --right scripted --duration " +
                          std::to_string(seconds + 30) + " --size " + std::to_string(kWidth) + "x" +
                          std::to_string(kHeight) + " --stats " + out.string() + " --stats-after " +
                          std::to_string(seconds) + (render ? "" : " --no-render") +
                          " > /dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  if (rc != 0 || !fs::exists(out)) {
    throw InputError("trainer: `" + cmd + "` failed (exit " + std::to_string(rc) +
                     "); is xvfb-run installed (scripts/install-deps.sh)?");
  }
  std::ifstream in(out);
  return {drill, render, nlohmann::json::parse(in)};
}

std::string met(bool ok) {
  return ok ? "met" : "**missed**";
}

}  // namespace

void run_trainer_study(const StudyOptions& options) {
  for (const auto& e : options.extra) throw InputError("trainer: unknown option '" + e + "'");
  const std::string load = load_note();
  const fs::path dir = options.out_dir / "results";
  const fs::path bin = trainer_binary();
  const double seconds = options.quick ? 5 : 20;
  const std::array<std::string, 3> drills = {"capsulorhexis", "phaco_sculpting",
                                             "corneal_incision"};
  Progress progress(static_cast<int>(drills.size()) * 2 + 1);
  std::vector<TrainerRun> runs;
  for (const auto& d : drills) {
    for (bool render : {true, false}) {
      progress.step("trainer: " + d + (render ? "" : " (no render)"));
      runs.push_back(run_trainer(bin, dir, d, render, seconds));
    }
  }
  progress.step("trainer: writing");

  Table t;
  t.columns = {"drill",
               "render",
               "renderer",
               "fps",
               "frame_p50_ms",
               "frame_p99_ms",
               "sim_rate_hz",
               "haptic_p50_us",
               "haptic_p99_us",
               "haptic_ticks",
               "snapshots_published",
               "wall_s"};
  std::string md = "## The trainer: frame rate on the software renderer (issue 8)\n\n";
  md += std::string("Measured by `phaco-perf trainer") + (options.quick ? " --quick" : "") + "`, " +
        load + ". `phaco-trainer` under Xvfb at " + std::to_string(kWidth) + "×" +
        std::to_string(kHeight) + ", the default eye (level 3), both hands on scripted devices " +
        "through the 1 kHz loop, " + fmt("%.0f", seconds) +
        " s per run; *render off* is the same process and loop drawing nothing. The simulation's "
        "target rate is 1/dt = 120 Hz, the haptic period 1000 us; the render target is 30 fps.\n\n";
  md +=
      "| drill | renderer | fps | frame p50 / p99 ms | target 30 fps | simulation Hz (render off) "
      "| "
      "haptic period p50 / p99 us (render off) |\n|---|---|---|---|---|---|---|\n";
  Chart chart{.title = "phaco-trainer on llvmpipe at 1280x720",
              .x = {.label = "drill (1 rhexis, 2 sculpting, 3 incision)"},
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
          fmt("%.1f", on.value("frame_p99_ms", 0.0)) + " | " + met(f >= kTargetFps) + " | " +
          fmt("%.1f", on.value("sim_rate_hz", 0.0)) + " (" +
          fmt("%.1f", off.value("sim_rate_hz", 0.0)) + ") | " +
          fmt("%.0f", on.value("haptic_period_p50_us", 0.0)) + " / " +
          fmt("%.0f", on.value("haptic_period_p99_us", 0.0)) + " (" +
          fmt("%.0f", off.value("haptic_period_p50_us", 0.0)) + " / " +
          fmt("%.0f", off.value("haptic_period_p99_us", 0.0)) + ") |\n";
    const double x = static_cast<double>(i / 2 + 1);
    fps.x.push_back(x), fps.y.push_back(f);
    sim.x.push_back(x), sim.y.push_back(on.value("sim_rate_hz", 0.0));
    sim_off.x.push_back(x), sim_off.y.push_back(off.value("sim_rate_hz", 0.0));
    for (const TrainerRun* r : {&runs[i], &runs[i + 1]}) {
      const auto& s = r->stats;
      t.add({r->drill, r->render ? "on" : "off", s.value("renderer", std::string("?")),
             s.value("fps", 0.0), s.value("frame_p50_ms", 0.0), s.value("frame_p99_ms", 0.0),
             s.value("sim_rate_hz", 0.0), s.value("haptic_period_p50_us", 0.0),
             s.value("haptic_period_p99_us", 0.0), s.value("haptic_ticks", 0.0),
             s.value("snapshots_published", 0.0), s.value("wall_s", 0.0)});
    }
  }
  chart.series = {fps, sim, sim_off};
  save_chart(chart, dir / "trainer_rates.png");
  write_csv(t, dir / "trainer.csv");
  write_json(t, dir / "trainer.json");
  md += "\n![trainer rates](results/trainer_rates.png)\n\n";
  write_section(dir, "trainer", md);
  progress.finish();
}

}  // namespace phaco::perf
