// phaco-perf soak (issue 18 item 7): phaco-trainer left running drill after drill under Xvfb, as
// a training station runs all day: the three drills in turn, both hands scripted, each drill cut
// to a few simulated seconds so that every drill comes round many times. After each drill the
// trainer samples its resident memory, the GL objects alive in its context and the haptic
// period over that drill (apps/trainer/trainer_soak.hpp). Checked here:
//   - memory: no drill's resident set, after the first round of the three, exceeds by more than
//     5 % the largest of that first round (what a station reaches once every drill has run);
//   - GL objects: from the second round on, each drill leaves as many objects alive every time it
//     runs as it did in the second round (a leak of one buffer per drill shows at once). Not the
//     first round: the renderer keeps the slots of the largest scene it has drawn for reuse, so a
//     drill that first ran before a larger one finds a few more objects alive afterwards, once;
//   - at least three whole rounds ran, so both checks had something to compare.
// A failed check writes the figures and exits 1. CI runs `--quick` (90 s); the 30-minute figure
// in perf/RESULTS.md is the default run.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
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
constexpr double kDrillSeconds = 6;  // simulated seconds per drill
constexpr double kGrowthLimit = 0.05;
constexpr int kDrillsPerRound = 3;

fs::path trainer_exe() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  const fs::path bin = self.parent_path().parent_path() / "apps" / "phaco-trainer";
  if (ec || !fs::exists(bin))
    throw InputError("soak: phaco-trainer not found at " + bin.string() +
                     " (build the target phaco-trainer)");
  return bin;
}

int gl_total(const nlohmann::json& s) {
  int n = 0;
  for (const char* k :
       {"gl_buffers", "gl_vertex_arrays", "gl_textures", "gl_programs", "gl_framebuffers"})
    n += s.value(k, 0);
  return n;
}

}  // namespace

void run_soak(const StudyOptions& options) {
  double seconds = options.quick ? 90 : 1800;
  for (size_t i = 0; i < options.extra.size(); ++i) {
    if (options.extra[i] == "--seconds" && i + 1 < options.extra.size()) {
      seconds = std::atof(options.extra[++i].c_str());
      if (!(seconds >= 30 && seconds <= 86400))
        throw InputError("soak: --seconds expects 30..86400, got '" + options.extra[i] + "'");
    } else {
      throw InputError("soak: unknown option '" + options.extra[i] + "'");
    }
  }
  const std::string load = load_note();
  const fs::path dir = options.out_dir / "results";
  fs::create_directories(dir);
  const fs::path out = dir / "soak.json";
  const fs::path log = dir / "soak.log";
  fs::remove(out);
  Progress progress(2);
  progress.step("soak: phaco-trainer drill after drill for " + fmt("%.0f", seconds) + " s");
  const std::string cmd = "xvfb-run -a -s '-screen 0 " + std::to_string(kWidth) + "x" +
                          std::to_string(kHeight) + "x24' " + trainer_exe().string() + " --soak " +
                          out.string() + " --soak-for " + fmt("%.0f", seconds) + " --duration " +
                          fmt("%.0f", kDrillSeconds) + " --size " + std::to_string(kWidth) + "x" +
                          std::to_string(kHeight) + " > " + log.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  if (rc != 0 || !fs::exists(out))
    throw CheckFailed("soak: `" + cmd + "` failed (exit " + std::to_string(rc) + "); see " +
                      log.string());
  progress.step("soak: checks and charts");
  nlohmann::json soak;
  std::ifstream(out) >> soak;
  const nlohmann::json& samples = soak.at("samples");

  // The first round sets the memory a station reaches; the second each drill's GL count.
  std::map<std::string, int> first_gl;
  double first_round_mb = 0;
  for (size_t i = 0; i < samples.size() && i < kDrillsPerRound; ++i)
    first_round_mb = std::max(first_round_mb, samples[i].value("rss_mb", 0.0));
  for (size_t i = kDrillsPerRound; i < samples.size() && i < 2 * kDrillsPerRound; ++i)
    first_gl[samples[i]["drill"]] = gl_total(samples[i]);
  double worst_growth = 0;
  std::string worst_at, gl_leaks;
  for (size_t i = kDrillsPerRound; i < samples.size(); ++i) {
    const auto& s = samples[i];
    const double growth = s.value("rss_mb", 0.0) / first_round_mb - 1.0;
    if (growth > worst_growth)
      worst_growth = growth, worst_at = "drill " + std::to_string(i) + " (" +
                                        s["drill"].get<std::string>() + ", " +
                                        fmt("%.0f", s.value("wall_s", 0.0)) + " s)";
    if (const int gl = gl_total(s); i >= 2 * kDrillsPerRound && gl != first_gl[s["drill"]])
      gl_leaks += (gl_leaks.empty() ? "" : ", ") + std::string("drill ") + std::to_string(i) +
                  " (" + s["drill"].get<std::string>() + "): " + std::to_string(gl) + " vs " +
                  std::to_string(first_gl[s["drill"]]);
  }
  const bool enough = samples.size() >= 3 * kDrillsPerRound;
  const bool memory_ok = worst_growth <= kGrowthLimit;
  const bool gl_ok = gl_leaks.empty();

  Table t;
  t.columns = {"drill_index",   "drill",         "wall_s",        "rss_mb", "gl_objects",
               "haptic_p99_us", "haptic_max_us", "render_p99_ms", "score"};
  Chart mem{.title = "Soak: resident memory after each drill",
            .x = {.label = "wall time (s)"},
            .y = {.label = "resident memory (MiB)", .min = 0.0}};
  Chart hap{.title = "Soak: haptic period over each drill",
            .x = {.label = "wall time (s)"},
            .y = {.label = "period (us)", .scale = Scale::Log10}};
  Chart gl{.title = "Soak: GL objects alive after each drill",
           .x = {.label = "wall time (s)"},
           .y = {.label = "objects", .min = 0.0}};
  std::map<std::string, Series> mem_by, gl_by;
  Series p99{.name = "p99"}, pmax{.name = "max", .style = Style::Scatter};
  for (const auto& s : samples) {
    const std::string d = s["drill"];
    const double w = s.value("wall_s", 0.0);
    t.add({s.value("drill_index", 0.0), d, w, s.value("rss_mb", 0.0), double(gl_total(s)),
           s.value("haptic_period_p99_us", 0.0), s.value("haptic_period_max_us", 0.0),
           s.value("render_frame_p99_ms", 0.0), s.value("score", 0.0)});
    mem_by[d].name = d, mem_by[d].style = Style::LineAndMarkers;
    mem_by[d].x.push_back(w), mem_by[d].y.push_back(s.value("rss_mb", 0.0));
    gl_by[d].name = d, gl_by[d].style = Style::LineAndMarkers;
    gl_by[d].x.push_back(w), gl_by[d].y.push_back(gl_total(s));
    p99.x.push_back(w), p99.y.push_back(s.value("haptic_period_p99_us", 0.0));
    pmax.x.push_back(w), pmax.y.push_back(s.value("haptic_period_max_us", 0.0));
  }
  for (auto& [d, s] : mem_by) mem.series.push_back(s);
  for (auto& [d, s] : gl_by) gl.series.push_back(s);
  hap.series = {p99, pmax};
  save_chart(mem, dir / "soak_memory.png");
  save_chart(hap, dir / "soak_haptics.png");
  save_chart(gl, dir / "soak_gl.png");
  write_csv(t, dir / "soak.csv");

  double hp99 = 0, hmax = 0;
  int fifo = 0, over = 0;  // drills with SCHED_FIFO; drills whose period max exceeds 1.5 ms
  for (const auto& s : samples) {
    hp99 = std::max(hp99, s.value("haptic_period_p99_us", 0.0));
    hmax = std::max(hmax, s.value("haptic_period_max_us", 0.0));
    fifo += s.value("haptic_fifo", false) ? 1 : 0;
    over += s.value("haptic_period_max_us", 0.0) > 1500 ? 1 : 0;
  }
  const double last_mb = samples.empty() ? 0 : samples.back().value("rss_mb", 0.0);
  std::string md = "## Soak: the trainer drill after drill (issue 18)\n\n";
  md += "Measured by `phaco-perf soak" + std::string(options.quick ? " --quick" : "") + "`, " +
        load + ". `phaco-trainer --soak` under Xvfb at 1280×720 on the software renderer, the " +
        "three drills in turn (capsulorhexis, phaco sculpting, corneal incision), both hands " +
        "scripted, " + fmt("%.0f", kDrillSeconds) + " simulated s each, for " +
        fmt("%.0f", seconds) + " s of wall time; after each drill the trainer samples its " +
        "resident memory, the GL objects alive in its context (every name probed with glIs*) " +
        "and the haptic period over the drill.\n\n";
  md += "| what | figure | verdict |\n|---|---|---|\n";
  md += "| drills run | " + std::to_string(samples.size()) + " in " +
        fmt("%.0f", samples.empty() ? 0.0 : samples.back().value("wall_s", 0.0)) + " s | " +
        (enough ? "met (≥ 3 rounds)" : "**missed**: fewer than 3 rounds") + " |\n";
  md += "| memory growth after the first round ≤ 5 % | first round's largest " +
        fmt("%.1f", first_round_mb) + " MiB; last " + fmt("%.1f", last_mb) + " MiB; worst " +
        fmt("%+.1f", 100 * worst_growth) + " %" + (worst_at.empty() ? "" : " at " + worst_at) +
        " | " + (memory_ok ? "met" : "**missed**") + " |\n";
  md += "| GL objects alive, each drill against its run in the second round | " +
        (gl_ok ? std::string("equal every time") : gl_leaks) + " | " +
        (gl_ok ? "met" : "**missed**") + " |\n";
  md += "| haptic period over the drills | worst p99 " + fmt("%.0f", hp99) + " us; max " +
        fmt("%.0f", hmax) + " us; max above 1.5 ms in " + std::to_string(over) + " of " +
        std::to_string(samples.size()) + " drills; SCHED_FIFO granted in " + std::to_string(fifo) +
        " | reported |\n\n";
  md +=
      "![soak memory](results/soak_memory.png)\n\n![soak GL](results/soak_gl.png)\n\n"
      "![soak haptics](results/soak_haptics.png)\n\n";
  write_section(dir, "soak", md);
  progress.finish();
  if (!enough || !memory_ok || !gl_ok)
    throw CheckFailed(
        "soak: " + std::string(!enough ? "fewer than three rounds of drills; " : "") +
        (!memory_ok ? "memory grew " + fmt("%.1f", 100 * worst_growth) + " % at " + worst_at + "; "
                    : "") +
        (!gl_ok ? "GL objects leaked: " + gl_leaks : ""));
}

}  // namespace phaco::perf
