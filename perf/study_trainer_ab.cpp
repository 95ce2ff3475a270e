// phaco-perf trainer-ab (issue 24's "no lower than today's"): this build's phaco-trainer against
// an earlier build, drill by drill, in interleaved runs. One run of `phaco-perf trainer` moves by
// up to a quarter from run to run on a shared machine, so a before/after comparison of two such
// studies cannot tell a few percent apart. Here the builds alternate run by run (ABBA: the first
// build of a repetition is the last of the next), so a slow drift of the machine falls on both,
// and each repetition gives paired ratios (frame rate, and the drawing's CPU per frame, which a
// shared machine moves far less); the verdict is the paired ratios' 95 % interval (Student's t). A
// variant is this build reading another data folder (e.g. a drill file with a body taken out), to
// tell what a scene's content costs from what the code costs.
#include <algorithm>
#include <cmath>
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

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

struct Build {
  std::string name;
  fs::path bin;
  std::optional<fs::path> data;
  std::string only_drill;  // a variant run in this drill only (empty: every drill)
};

struct AbOptions {
  std::vector<Build> builds;  // [0] the earlier build, [1] this one, then this one's variants
  std::vector<std::string> drills;
  int reps = 4;
  double seconds = 20;
};

AbOptions parse(const StudyOptions& options) {
  AbOptions o;
  Build earlier{.name = "earlier build"};
  std::vector<Build> variants;
  const fs::path self = trainer_binary();
  for (size_t i = 0; i < options.extra.size(); ++i) {
    const std::string& e = options.extra[i];
    if (i + 1 >= options.extra.size())
      throw InputError("trainer-ab: " + e + " needs a value (try --help)");
    const std::string v = options.extra[++i];
    if (e == "--against") {
      earlier.bin = v;
      if (!fs::is_regular_file(earlier.bin))
        throw InputError("trainer-ab: --against: no phaco-trainer at '" + v + "'");
    } else if (e == "--against-data") {
      earlier.data = v;
      if (!fs::is_directory(v))
        throw InputError("trainer-ab: --against-data: no folder '" + v + "'");
    } else if (e == "--label") {
      earlier.name = v;
    } else if (e == "--variant") {
      const size_t eq = v.find('=');
      if (eq == std::string::npos || eq == 0 || !fs::is_directory(v.substr(eq + 1)))
        throw InputError(
            "trainer-ab: --variant expects NAME[@DRILL]=DATA_DIR (an existing "
            "folder), got '" +
            v + "'");
      const std::string head = v.substr(0, eq);
      const size_t at = head.find('@');
      variants.push_back({"this build, " + head.substr(0, at), self, fs::path(v.substr(eq + 1)),
                          at == std::string::npos ? std::string() : head.substr(at + 1)});
    } else if (e == "--reps") {
      o.reps = std::atoi(v.c_str());
      if (o.reps < 2 || o.reps > 50)
        throw InputError("trainer-ab: --reps expects 2..50, got '" + v + "'");
    } else if (e == "--seconds") {
      o.seconds = std::atof(v.c_str());
      if (!(o.seconds >= 2 && o.seconds <= 600))
        throw InputError("trainer-ab: --seconds expects 2..600, got '" + v + "'");
    } else if (e == "--drill") {
      if (v != "capsulorhexis" && v != "phaco_sculpting" && v != "corneal_incision" &&
          v != "nucleus_removal")
        throw InputError("trainer-ab: unknown drill '" + v + "'");
      o.drills.push_back(v);
    } else {
      throw InputError("trainer-ab: unknown option '" + e + "'");
    }
  }
  if (earlier.bin.empty())
    throw InputError("trainer-ab: --against OLD_PHACO_TRAINER is required (try --help)");
  if (o.drills.empty()) o.drills = {"capsulorhexis", "phaco_sculpting", "corneal_incision"};
  o.builds = {earlier, Build{"this build", self, std::nullopt}};
  o.builds.insert(o.builds.end(), variants.begin(), variants.end());
  return o;
}

}  // namespace

void run_trainer_ab(const StudyOptions& options) {
  const AbOptions o = parse(options);
  const std::string load = load_note();
  const fs::path dir = options.out_dir / "results";
  const size_t nb = o.builds.size();
  size_t runs_per_rep = 0;
  for (const std::string& d : o.drills)
    for (const Build& b : o.builds) runs_per_rep += b.only_drill.empty() || b.only_drill == d;
  Progress progress(static_cast<int>(runs_per_rep) * o.reps + 1);
  // fps[drill][build][rep], and the drawing's CPU per frame (ms) alike
  using PerBuild = std::vector<std::vector<std::vector<double>>>;
  PerBuild fps(o.drills.size(), std::vector<std::vector<double>>(nb));
  PerBuild cpu_ms = fps;
  Table t;
  t.columns = {"drill",
               "build",
               "rep",
               "fps",
               "frame_p50_ms",
               "frame_p99_ms",
               "render_main_ms",
               "render_llvmpipe_ms",
               "other_threads_ms",
               "load_before"};
  for (int rep = 0; rep < o.reps; ++rep) {
    for (size_t d = 0; d < o.drills.size(); ++d) {
      for (size_t k = 0; k < nb; ++k) {
        const size_t b = rep % 2 == 0 ? k : nb - 1 - k;  // ABBA
        const Build& build = o.builds[b];
        if (!build.only_drill.empty() && build.only_drill != o.drills[d]) continue;
        progress.step("trainer-ab: " + o.drills[d] + ", " + build.name);
        RenderCpu cpu;
        const TrainerRun r = run_trainer_drill(build.bin, dir, o.drills[d], true, o.seconds,
                                               build.data, "ab_" + std::to_string(b), &cpu);
        if (!cpu.measured)
          throw InputError("trainer-ab: could not read the CPU time of " + build.bin.string() +
                           " from /proc while it ran");
        const double f = r.stats.value("fps", 0.0);
        fps[d][b].push_back(f);
        cpu_ms[d][b].push_back(cpu.main_ms + cpu.llvmpipe_ms);
        t.add({o.drills[d], build.name, static_cast<double>(rep + 1), f,
               r.stats.value("frame_p50_ms", 0.0), r.stats.value("frame_p99_ms", 0.0), cpu.main_ms,
               cpu.llvmpipe_ms, cpu.other_ms, r.load_before});
      }
    }
  }
  progress.step("trainer-ab: writing");

  std::string md = "## The trainer against an earlier build (issue 24)\n\n";
  md += "Measured by `phaco-perf trainer-ab`, " + load + ". `phaco-trainer` as `phaco-perf " +
        "trainer` runs it (Xvfb, 1280×720, scripted hands, llvmpipe; each build draws what it " +
        "draws then: this one its tip-height labels and panels, the controls overlay being off " +
        "in unattended runs), " + fmt("%.0f", o.seconds) + " s measured per run, " +
        std::to_string(o.reps) +
        " repetitions, the builds alternating run by run (ABBA). The earlier build: " +
        o.builds[0].name + " (`" + o.builds[0].bin.filename().string() + "`" +
        (o.builds[0].data ? ", its own data folder" : std::string()) + ")." +
        (nb > 2 ? " A variant is this build reading another data folder." : "") +
        " Two figures per run: the frame rate, and the drawing's CPU per frame (the trainer's "
        "main thread and Mesa's llvmpipe threads, read from /proc over the measured window, "
        "its first 3 s skipped). When other processes share the cores the frame rate falls with "
        "them, while the CPU a frame costs moves much less. Ratio: each repetition's figure over "
        "the earlier build's in the same repetition; its mean and 95 % interval (Student's t). "
        "*Lower* fps or *more* CPU: the whole interval on the wrong side of 1.\n\n";
  md +=
      "| drill | build | fps mean [min – max] | fps ratio, mean [95 %] | CPU per frame, ms, mean "
      "[min – max] | CPU ratio, mean [95 %] | verdict |\n|---|---|---|---|---|---|---|\n";
  Chart chart{.title = "phaco-trainer, CPU per drawn frame, each run (llvmpipe, 1280x720)",
              .x = {.label = "drill (1 rhexis, 2 sculpting, 3 incision, 4 nucleus) + build offset"},
              .y = {.label = "main + llvmpipe CPU per frame (ms)"}};
  for (size_t b = 0; b < nb; ++b)
    chart.series.push_back({.name = o.builds[b].name, .style = Style::Scatter});
  auto range = [](const std::vector<double>& v, const char* f) {
    return fmt(f, mean_interval95(v).mean) + " [" + fmt(f, *std::min_element(v.begin(), v.end())) +
           " – " + fmt(f, *std::max_element(v.begin(), v.end())) + "]";
  };
  auto paired = [](const std::vector<double>& v, const std::vector<double>& base) {
    std::vector<double> r;
    for (size_t i = 0; i < v.size(); ++i) r.push_back(v[i] / base[i]);
    return mean_interval95(r);
  };
  auto text = [](const MeanInterval& i) {
    return fmt("%.3f", i.mean) + " [" + fmt("%.3f", i.lo) + " – " + fmt("%.3f", i.hi) + "]";
  };
  for (size_t d = 0; d < o.drills.size(); ++d) {
    const double x0 = o.drills[d] == "capsulorhexis"      ? 1
                      : o.drills[d] == "phaco_sculpting"  ? 2
                      : o.drills[d] == "corneal_incision" ? 3
                                                          : 4;
    for (size_t b = 0; b < nb; ++b) {
      const auto& f = fps[d][b];
      const auto& c = cpu_ms[d][b];
      if (f.empty()) continue;
      std::string fps_ratio = "—", cpu_ratio = "—", verdict_text = "—";
      if (b > 0) {
        const MeanInterval fr = paired(f, fps[d][0]), cr = paired(c, cpu_ms[d][0]);
        fps_ratio = text(fr), cpu_ratio = text(cr);
        if (fr.hi < 1.0) {
          verdict_text = "**fps lower**";
        } else {
          verdict_text = fr.lo > 1.0 ? "fps higher" : "fps: no difference resolved";
        }
        verdict_text += cr.lo > 1.0   ? "; **CPU per frame higher**"
                        : cr.hi < 1.0 ? "; CPU per frame lower"
                                      : "; CPU per frame: no difference resolved";
      }
      md += "| " + o.drills[d] + " | " + o.builds[b].name + " | " + range(f, "%.1f") + " | " +
            fps_ratio + " | " + range(c, "%.2f") + " | " + cpu_ratio + " | " + verdict_text +
            " |\n";
      for (double v : c) {
        chart.series[b].x.push_back(x0 + 0.15 * static_cast<double>(b));
        chart.series[b].y.push_back(v);
      }
    }
  }
  save_chart(chart, dir / "trainer_ab.png");
  write_csv(t, dir / "trainer_ab.csv");
  write_json(t, dir / "trainer_ab.json");
  md += "\n![trainer against an earlier build](results/trainer_ab.png)\n\n";
  write_section(dir, "trainer_ab", md);
  progress.finish();
}

}  // namespace phaco::perf
