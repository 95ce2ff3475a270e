// phaco-perf sweep (issue 9): the whole trainer under the harness. Each drill's scripted expert is
// run to its end at every resolution level (0..8: up to 256k capsule vertices and 1.6M lens
// tets), on 1 and 2 simulation threads, with the 1 kHz haptic thread ticking beside the frames;
// and again at a few levels with each method alternative the scene can choose (integrators,
// spring stiffness, capsule layout, active set, spring law; broadphase, narrowphase and lens
// model). Each point runs in its own process (perf/sweep/sweep_point.hpp). Accuracy is the
// drill's scored outcome against the finest level's (the converged reference, DESIGN.md §8).
//
// The targets are judged here from the points, and the checks a CI run relies on are
// enforced: every point runs to its end, 1 and 2 threads give the same state hash, the default
// methods stay within their accuracy bounds and never diverge.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/error.hpp"
#include "perf/chart.hpp"
#include "perf/report.hpp"
#include "perf/studies.hpp"
#include "perf/sweep/sweep_data.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco::perf {
namespace {

namespace fs = std::filesystem;

struct Variant {
  std::string label;  // "key=value"
  std::string layout;
  std::map<std::string, std::string> methods;
  int max_level = 99;  // not above this level: the whole capsule's implicit step every frame
                       // (no active set) takes minutes per drill beyond the default level
  bool quick = true;   // also in --quick (CI): not the slow ones (20 s and more at level 1)
};

// The alternatives a drill's scene can choose (docs/ARCHITECTURE.md, `methods`); the others
// (force propagation, Horn vs polar, SPH cell order, Bullet) are measured on their own systems
// in the membrane and lens sections.
std::vector<Variant> variants_of(const std::string& drill) {
  std::vector<Variant> v;
  auto method = [&](const std::string& k, const std::string& value) {
    v.push_back({k + "=" + value, "", {{k, value}}});
  };
  if (drill == "capsulorhexis") {
    for (const char* i :
         {"implicit_predictor", "semi_implicit_001", "symplectic_euler", "explicit_euler", "xpbd"})
      method("capsule.integrator", i);
    method("capsule.stiffness", "uniform");
    method("capsule.spring_law", "quadratic");
    method("capsule.active_set", "off");
    v.back().max_level = 3;
    v.back().quick = false;
    v.push_back({"eye.capsule_layout=isotropic", "isotropic", {}});
  } else if (drill == "phaco_sculpting") {
    method("lens.broadphase", "dbvt");
    method("lens.narrowphase", "exact_gjk");
    method("lens.narrowphase", "exact_mpr");
    method("lens.model", "fragments");
    v.back().quick = false;
  }
  return v;
}

// Accuracy bounds the default methods must keep from level `from` up (checked in CI by --quick):
// the error of the drill's scored outcome against the reference level, percent.
struct Bound {
  int from_level;
  double max_error_pct;
};
Bound bound_of(const std::string& drill) {
  if (drill == "capsulorhexis") return {2, 10.0};
  if (drill == "phaco_sculpting") return {1, 15.0};
  return {1, 10.0};
}

// Points of the default methods without the haptic thread beside them (thread scaling).
constexpr const char* kNoHaptics = "no haptic thread";

std::string key(const SweepPointConfig& c) {
  return c.drill + "/" + std::to_string(c.level) + "/" + c.variant;
}

std::string label(const SweepPointConfig& c) {
  return c.drill + " level " + std::to_string(c.level) + ", " + std::to_string(c.threads) +
         " thread" + (c.threads > 1 ? "s" : "") + (c.variant == "default" ? "" : ", " + c.variant);
}

double physics_number(const SweepPointResult& r, const std::string& body, const std::string& k) {
  if (!r.physics.contains(body) || !r.physics[body].contains(k) || !r.physics[body][k].is_number())
    return std::nan("");
  return r.physics[body][k].get<double>();
}

double system_cost(const SweepPointResult& r, const std::string& name, double CostSummary::*field) {
  for (const auto& s : r.systems)
    if (s.name == name) return s.*field;
  return std::nan("");
}

std::string f(const char* format, double v) {
  return std::isfinite(v) ? fmt(format, v) : std::string("-");
}

std::string met(bool ok) {
  return ok ? "**met**" : "**missed**";
}

const SweepRow* find_row(const std::vector<SweepRow>& rows, const std::string& drill, int level,
                         int threads, const std::string& variant = "default") {
  for (const auto& row : rows)
    if (row.r.ok && row.r.config.drill == drill && row.r.config.level == level &&
        row.r.config.threads == threads && row.r.config.variant == variant)
      return &row;
  return nullptr;
}

// Why a target is missed and what would close it, with the figures that show the cause.
std::string why_targets_missed(const std::vector<SweepRow>& rows,
                               const std::vector<std::string>& drills, int max_level) {
  std::string md = "### Why a target is missed, and what would close it\n\n";
  const bool rhexis = std::find(drills.begin(), drills.end(), "capsulorhexis") != drills.end();
  if (const SweepRow* d = rhexis ? find_row(rows, "capsulorhexis", 3, 1) : nullptr) {
    const auto& r = d->r;
    const double cg = physics_number(r, "capsule", "cg_iterations_total") /
                      std::max(1.0, physics_number(r, "capsule", "frames_stepped"));
    md +=
        "- **The capsulorhexis's slow frames at the default level.** Its mean frame (" +
        f("%.2f", r.frame.mean_ms) + " ms) fits in 4 ms, its p99 (" + f("%.1f", r.frame.p99_ms) +
        " ms) does not. The slow frames are the capsule's implicit step: capsule_dynamics takes " +
        f("%.1f", system_cost(r, "capsule_dynamics", &CostSummary::max_ms)) +
        " ms of the worst frame's " + f("%.1f", r.frame.max_ms) +
        " ms. Jacobi-preconditioned CG needs " + f("%.0f", cg) +
        " iterations per stepped frame on average, over an active set of " +
        f("%.0f", physics_number(r, "capsule", "active_particles_mean")) +
        " nodes on average and up to " +
        f("%.0f", physics_number(r, "capsule", "active_particles_max")) +
        ": the membrane is far stiffer in plane than out of plane, which is hard on a Jacobi "
        "preconditioner (docs/implicit_and_active.md). "
        "What would close it: a stronger preconditioner on the active set (incomplete Cholesky, or "
        "multigrid over the resolution levels), which is where the iterations go.\n";
  }
  const SweepRow* big = nullptr;
  for (int l = max_level; l > 3 && rhexis && !big; --l) big = find_row(rows, "capsulorhexis", l, 1);
  if (big) {
    const auto& r = big->r;
    md += "- **Large capsules and topology changes.** At level " + std::to_string(r.config.level) +
          " (" + fmt("%.0f", big->elements) + " capsule vertices) the typical frame is still " +
          f("%.1f", r.frame.p50_ms) + " ms, but a frame with a cut or tear is " +
          f("%.0f", system_cost(r, "capsule_cut", &CostSummary::max_ms)) +
          " ms: the edit itself is local (at most " +
          f("%.1f", physics_number(r, "capsule_cutting", "edit_ms_max")) +
          " ms), the physics refresh after it is not (mean " +
          f("%.0f", physics_number(r, "capsule_cutting", "physics_refresh_ms_mean")) + " ms, " +
          f("%.0f", physics_number(r, "capsule_cutting", "topology_changes")) +
          " times in the drill). The refresh compacts and re-sorts every spring, re-plans the "
          "parallel spring blocks and rebuilds the spring graph, all linear in the mesh, and the "
          "next implicit step rebuilds its structure. "
          "What would close it: an incremental refresh that appends a cut's new springs to a tail "
          "block, patches the graph rows it touched and compacts rarely, so that a change costs "
          "what it touches.\n";
  }
  std::string alone;
  for (const std::string& drill : drills) {
    const SweepRow* a = find_row(rows, drill, 3, 1, kNoHaptics);
    const SweepRow* b = find_row(rows, drill, 3, 2, kNoHaptics);
    if (a && b && b->r.frame.mean_ms > 0)
      alone += (alone.empty() ? "" : ", ") + drill + " " +
               fmt("%.2f", a->r.frame.mean_ms / b->r.frame.mean_ms) + "×";
  }
  if (!alone.empty()) {
    md +=
        "- **Two threads at the default level.** A drill's frame holds little parallel work. The "
        "capsule's step works on a few hundred active nodes, and each CG iteration over them costs "
        "microseconds, too little to split across threads with profit. The sculpt query touches a "
        "few hundred "
        "tets. The other systems are tiny, and they depend on each other through the frame graph. "
        "Without the haptic thread beside them the speed-ups are " +
        alone +
        ". "
        "The parallel passes do scale where there is work: the membrane section's thread-scaling "
        "chart and targets show the membrane step over a whole large capsule. "
        "What would close it: parallelism across systems rather than inside them, so that "
        "independent work runs side by side (the port solve, the metrics and the haptic "
        "publication beside the capsule step), and a serial cut-off for loops below a grain of "
        "some thousands of nodes. "
        "The trainer already spends the second core elsewhere: rendering runs on the main thread "
        "and the simulation on its own.\n";
  }
  // The worst judged point (the default level or the largest, 2 threads, long enough to judge).
  const SweepRow* worst = nullptr;
  for (const auto& row : rows) {
    const auto& r = row.r;
    if (!r.ok || r.config.variant != "default" || r.config.threads != 2 || r.haptic_ticks < 1000)
      continue;
    if (r.config.level != 3 && r.config.level != max_level) continue;
    if (r.period_max_us > 1500 && (!worst || r.period_max_us > worst->r.period_max_us))
      worst = &row;
  }
  if (worst) {
    const auto& r = worst->r;
    md += "- **The haptic period's maximum** (" + r.config.drill + ", level " +
          std::to_string(r.config.level) + ", 2 threads). The p99 is " +
          f("%.0f", r.period_p99_us) + " us, but single periods reach " +
          f("%.0f", r.period_max_us) + " us" +
          (r.haptic_fifo ? std::string(" even with SCHED_FIFO")
                         : std::string(" (SCHED_FIFO was refused)")) +
          ". The haptic thread never waits for a frame (it computes from the last model it has), "
          "so the stall is outside the loop: the scheduler, the hypervisor (this is a virtual "
          "machine; the haptics section counts the time it steals), or page faults, since the "
          "sweep does not lock memory. "
          "What would close it: locked memory (the haptics section's runs use mlockall), a host "
          "with cores set aside for the haptic thread (isolcpus, nohz_full) or a PREEMPT_RT kernel "
          "on bare metal. Allocations on the haptic thread: " +
          (r.haptic_allocations < 0 ? std::string("not countable in this build")
                                    : fmt("%.0f", r.haptic_allocations)) +
          ".\n";
  }
  if (std::find(drills.begin(), drills.end(), "phaco_sculpting") != drills.end())
    md +=
        "- **Sculpting's cost against the lens's size.** The probe removes the tets its tip "
        "sweeps. At a finer level a tip of the same size sweeps more, smaller tets, so the work "
        "per frame grows with the mesh's density; the cost per removed tet does not. A frame also "
        "never searches the whole lens, thanks to the broadphase.\n";
  return md + "\n";
}

}  // namespace

void run_sweep(const StudyOptions& options) {
  int max_level = options.quick ? 3 : eye::kMaxLevel;
  std::vector<std::string> drills = {"capsulorhexis", "phaco_sculpting", "corneal_incision"};
  bool drills_given = false, replot = false;
  for (size_t i = 0; i < options.extra.size(); ++i) {
    const std::string& a = options.extra[i];
    if (a == "--replot") {
      replot = true;
    } else if (a == "--max-level" && i + 1 < options.extra.size()) {
      max_level = std::stoi(options.extra[++i]);
      if (max_level < 1 || max_level > eye::kMaxLevel)
        throw InputError("sweep: --max-level out of 1.." + std::to_string(eye::kMaxLevel));
    } else if (a == "--drill" && i + 1 < options.extra.size()) {
      const std::string d = options.extra[++i];
      if (d != "capsulorhexis" && d != "phaco_sculpting" && d != "corneal_incision")
        throw InputError(
            "sweep: --drill expects capsulorhexis, phaco_sculpting or corneal_incision, got '" + d +
            "'");
      if (!drills_given) drills.clear(), drills_given = true;
      if (std::find(drills.begin(), drills.end(), d) == drills.end()) drills.push_back(d);
    } else {
      throw InputError("sweep: unknown option '" + a + "'");
    }
  }
  std::string load = load_note();
  const fs::path dir = options.out_dir / "results";
  // The meshes: $PHACO_CACHE_DIR when set (CI shares the tests' cache), else the results' own.
  const char* env_cache = std::getenv("PHACO_CACHE_DIR");
  const fs::path cache = env_cache && *env_cache ? fs::path(env_cache) : dir / ".mesh-cache";
  const fs::path work = dir / ".sweep";
  const fs::path exe = fs::read_symlink("/proc/self/exe");
  const fs::path scenarios = eye::data_dir() / "scenarios";

  std::vector<int> threads = {1, 2};
  if (const int hw = int(std::thread::hardware_concurrency()); hw > 2) threads.push_back(hw);
  std::vector<int> levels;
  for (int l = 0; l <= max_level; ++l) levels.push_back(l);
  std::vector<int> variant_levels = options.quick ? std::vector<int>{1} : std::vector<int>{1, 3, 5};
  std::string cmd = std::string("phaco-perf sweep") + (options.quick ? " --quick" : "") +
                    (max_level != (options.quick ? 3 : eye::kMaxLevel)
                         ? " --max-level " + std::to_string(max_level)
                         : "");
  std::vector<std::string> failures;
  std::vector<SweepRow> rows;
  Progress progress(1);
  if (replot) {
    // The report redrawn from the points a sweep saved (sweep_points.json): new readings and charts
    // without measuring again. The figures stay those of the run that measured them.
    std::ifstream in(dir / "sweep_points.json");
    if (!in)
      throw InputError("sweep --replot: no " + (dir / "sweep_points.json").string() +
                       " to redraw from");
    nlohmann::json saved;
    try {
      saved = nlohmann::json::parse(in);
      cmd = saved.at("command").get<std::string>();
      load = saved.at("load").get<std::string>();
      max_level = saved.at("max_level");
      drills = saved.at("drills").get<std::vector<std::string>>();
      variant_levels = saved.at("variant_levels").get<std::vector<int>>();
      threads = saved.at("threads").get<std::vector<int>>();
      failures = saved.at("run_failures").get<std::vector<std::string>>();
      for (const auto& j : saved.at("points")) {
        SweepRow row;
        row.r = result_from_json(j);
        row.elements = drill_elements(row.r);
        rows.push_back(std::move(row));
      }
    } catch (const nlohmann::json::exception& e) {
      throw InputError("sweep --replot: " + (dir / "sweep_points.json").string() + ": " + e.what());
    }
  }
  const int reference_level = max_level;

  if (!replot) {
    // The plan: a warm-up per (drill, level, layout) builds the meshes into the cache, so that no
    // measured point pays for (or keeps the memory of) mesh generation.
    std::vector<SweepPointConfig> warm, plan;
    for (const std::string& drill : drills) {
      const fs::path scenario = scenarios / (drill + "_expert.json");
      for (int level : levels) {
        SweepPointConfig w{.drill = drill,
                           .scenario = scenario,
                           .level = level,
                           .warm_only = true,
                           .cache_dir = cache};
        warm.push_back(w);
        for (int t : threads) {
          SweepPointConfig c{.drill = drill,
                             .scenario = scenario,
                             .level = level,
                             .threads = t,
                             .cache_dir = cache};
          plan.push_back(c);
        }
      }
      // Thread scaling without the haptic thread, at the default level and the largest: how much
      // of the 2-thread figure the haptic thread takes.
      std::vector<int> scaling_levels = {std::min(3, max_level)};
      if (max_level > 3) scaling_levels.push_back(max_level);
      for (int level : scaling_levels) {
        for (int t : threads) {
          SweepPointConfig c{.drill = drill,
                             .scenario = scenario,
                             .level = level,
                             .threads = t,
                             .variant = kNoHaptics,
                             .haptics = false,
                             .cache_dir = cache};
          plan.push_back(c);
        }
      }
      for (const Variant& v : variants_of(drill)) {
        for (int level : variant_levels) {
          if (level > max_level || level > v.max_level || (options.quick && !v.quick)) continue;
          if (!v.layout.empty()) {
            SweepPointConfig w{.drill = drill,
                               .scenario = scenario,
                               .level = level,
                               .capsule_layout = v.layout,
                               .warm_only = true,
                               .cache_dir = cache};
            warm.push_back(w);
          }
          SweepPointConfig c{.drill = drill,
                             .scenario = scenario,
                             .level = level,
                             .threads = 1,
                             .capsule_layout = v.layout,
                             .methods = v.methods,
                             .variant = v.label,
                             .cache_dir = cache};
          plan.push_back(c);
        }
      }
    }

    progress = Progress(int(warm.size() + plan.size()) + 1);
    for (const auto& w : warm) {
      progress.step("sweep: meshes for " + w.drill + " level " + std::to_string(w.level) +
                    (w.capsule_layout.empty() ? "" : " " + w.capsule_layout));
      const SweepPointResult r = run_sweep_point_isolated(w, exe, work);
      if (!r.ok) failures.push_back("building " + label(w) + ": " + r.error);
    }
    for (const auto& c : plan) {
      progress.step("sweep: " + label(c));
      SweepRow row;
      row.r = run_sweep_point_isolated(c, exe, work);
      if (!row.r.ok) failures.push_back(label(c) + ": " + row.r.error);
      row.elements = drill_elements(row.r);
      rows.push_back(std::move(row));
    }
  }
  progress.step("sweep: accuracy, checks, charts");
  const std::vector<std::string> run_failures = failures;  // saved with the points

  // Accuracy against the reference point of the drill: default methods, 1 thread, finest level.
  std::map<std::string, const SweepRow*> reference;
  for (const auto& row : rows)
    if (row.r.ok && row.r.config.variant == "default" && row.r.config.threads == 1 &&
        row.r.config.level == reference_level)
      reference[row.r.config.drill] = &row;
  for (auto& row : rows) {
    const auto it = reference.find(row.r.config.drill);
    row.error_pct = it != reference.end() && row.r.ok
                        ? accuracy_error_pct(row.r, it->second->r, &row.error_detail)
                        : std::nan("");
  }

  // The checks (a --quick run in CI enforces them; so does every full run).
  std::map<std::string, std::string> hash_of;
  for (const auto& row : rows) {
    if (!row.r.ok) continue;
    const SweepPointConfig& c = row.r.config;
    auto [it, fresh] = hash_of.emplace(key(c), row.r.state_hash);
    if (!fresh && it->second != row.r.state_hash)
      failures.push_back(label(c) + ": state hash " + row.r.state_hash +
                         " differs from the 1-thread run's " + it->second +
                         " (runs must be bit-identical whatever the thread count)");
    if (!row.r.metrics.contains("score") || !row.r.metrics["score"].is_number())
      failures.push_back(label(c) + ": no score in the run's metrics");
    if (c.variant != "default") continue;
    const double divergences = physics_number(row.r, "capsule", "divergences");
    if (std::isfinite(divergences) && divergences > 0)
      failures.push_back(label(c) + ": the capsule diverged " + fmt("%.0f", divergences) +
                         " times");
    const Bound b = bound_of(c.drill);
    if (c.level >= b.from_level && !(row.error_pct <= b.max_error_pct))
      failures.push_back(label(c) + ": accuracy error " + f("%.2f", row.error_pct) +
                         " % against level " + std::to_string(reference_level) +
                         " exceeds its bound " + fmt("%.0f", b.max_error_pct) + " % (" +
                         row.error_detail + ")");
  }
  if (reference.size() < drills.size())
    failures.push_back("a drill has no reference point (level " + std::to_string(reference_level) +
                       ", 1 thread)");

  // Raw figures.
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
  if (!replot) {
    const nlohmann::json saved = {{"command", cmd},
                                  {"load", load},
                                  {"max_level", max_level},
                                  {"drills", drills},
                                  {"variant_levels", variant_levels},
                                  {"threads", threads},
                                  {"run_failures", run_failures},
                                  {"points", all}};
    std::ofstream(dir / "sweep_points.json") << saved.dump() << '\n';  // compact: ~1 MB indented
  }
  const SweepChartFiles charts = draw_sweep_charts(rows, dir);

  auto find = [&](const std::string& drill, int level, int th,
                  const std::string& variant = "default") {
    return find_row(rows, drill, level, th, variant);
  };

  // ---- The section.
  std::string md = "## The whole trainer under load: the sweep (issue 9)\n\n";
  md += "Measured by `" + cmd + "`, " + load +
        (replot ? " (report redrawn by `phaco-perf sweep --replot`)" : "") +
        ". Each drill's scripted expert (`data/scenarios/<drill>_expert.json`) runs to its end at "
        "every resolution level 0.." +
        std::to_string(max_level) + " on " + std::to_string(threads.size()) +
        " thread counts, in a process of its own, while the 1 kHz haptic thread (SCHED_FIFO where "
        "granted, not pinned: it competes with the simulation's threads for the two cores) plays "
        "the expert's tool hand from a scripted device and computes forces from the model each "
        "frame publishes. The scene keeps following its scripted tracks, so a point's state hash "
        "is the same with and without the haptic thread. Frame time is the whole frame graph "
        "(every system of the drill's scene; rendering is measured by `phaco-perf trainer`). "
        "Memory is the point process's resident set: before the scene, after building it from the "
        "mesh cache, and its peak while stepping. Accuracy: the drill's scored outcome (" +
        "capsulorhexis: opening diameter and circularity; sculpting: volume removed, trench width "
        "and depth; incision: width and tunnel length) against the same run at level " +
        std::to_string(reference_level) +
        " (the converged reference), the largest relative difference.\n\n";

  if (!failures.empty()) {
    md += "**Checks failed:**\n\n";
    for (const auto& e : failures) md += "- " + e + "\n";
    md += "\n";
  } else {
    md +=
        "Checks passed: every point ran to its end; 1 and 2 threads gave the same state hash at "
        "every level and variant; the default methods never diverged and stayed within their "
        "accuracy bounds against level " +
        std::to_string(reference_level) + " (";
    for (const std::string& drill : drills) {
      const Bound b = bound_of(drill);
      md += (drill == drills.front() ? "" : ", ") + drill + " ≤ " + fmt("%.0f", b.max_error_pct) +
            " % from level " + std::to_string(b.from_level);
    }
    md += ").\n\n";
  }

  // Targets.
  md += "### Targets\n\n| target | figure | verdict |\n|---|---|---|\n";
  for (const std::string& drill : drills) {
    const SweepRow* d1 = find(drill, 3, 1);
    const SweepRow* d2 = find(drill, 3, 2);
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
    for (int l = max_level; l >= 0 && !big; --l) big = find(drill, l, 2);
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
  for (const std::string& drill : drills) {
    const SweepRow* d1 = find(drill, 3, 1);
    const SweepRow* d2 = find(drill, 3, 2);
    if (!d1 || !d2 || d2->r.frame.mean_ms <= 0) continue;
    const double s = d1->r.frame.mean_ms / d2->r.frame.mean_ms;
    const SweepRow* n1 = find(drill, 3, 1, kNoHaptics);
    const SweepRow* n2 = find(drill, 3, 2, kNoHaptics);
    const std::string alone =
        n1 && n2 && n2->r.frame.mean_ms > 0
            ? "; without the haptic thread " + f("%.3f", n1->r.frame.mean_ms) + " → " +
                  f("%.3f", n2->r.frame.mean_ms) +
                  " ms: " + fmt("%.2f", n1->r.frame.mean_ms / n2->r.frame.mean_ms) + "×"
            : "";
    md += "| 2-thread speed-up ≥ 1.7×, " + drill + " (level 3) | mean " +
          f("%.3f", d1->r.frame.mean_ms) + " → " + f("%.3f", d2->r.frame.mean_ms) +
          " ms: " + fmt("%.2f", s) + "×" + alone + " | " + met(s >= 1.7) +
          (s >= 1.7 ? "" : " by " + fmt("%.2f", 1.7 - s) + "×") + " |\n";
  }
  // The haptic targets, judged where the frames ran long enough for the thread to tick a second
  // or more after its warm-up: the default level and the largest, 2 simulation threads.
  for (const std::string& drill : drills) {
    std::vector<const SweepRow*> pts;
    if (const SweepRow* p = find(drill, 3, 2)) pts.push_back(p);
    for (int l = max_level; l > 3; --l)
      if (const SweepRow* p = find(drill, l, 2)) {
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
  // Topology changes against mesh size: the capsulorhexis's cut edit and physics refresh, the
  // sculpt's tet removal, the incision's cornea cut; slopes of the worst frame against elements.
  std::vector<std::pair<std::string, PowerFit>> topo;
  {
    auto fit_of = [&](const std::string& drill, auto value) {
      std::vector<double> x, y;
      for (int l = 0; l <= max_level; ++l)
        if (const SweepRow* p = find(drill, l, 1)) {
          x.push_back(p->elements);
          y.push_back(value(p->r));
        }
      return fit_power_law(x, y);
    };
    if (find("capsulorhexis", 0, 1)) {
      topo.push_back({"capsulorhexis: cut edit, worst frame",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return physics_number(r, "capsule_cutting", "edit_ms_max");
                      })});
      topo.push_back({"capsulorhexis: physics refresh after a cut, mean",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return physics_number(r, "capsule_cutting", "physics_refresh_ms_mean");
                      })});
      topo.push_back({"capsulorhexis: capsule_cut system, worst frame",
                      fit_of("capsulorhexis", [](const SweepPointResult& r) {
                        return system_cost(r, "capsule_cut", &CostSummary::max_ms);
                      })});
    }
    if (find("phaco_sculpting", 0, 1))
      topo.push_back(
          {"sculpting: lens_sculpt time per removed tet (the drill's total over the tets removed)",
           fit_of("phaco_sculpting", [](const SweepPointResult& r) {
             const double removed =
                 r.metrics.contains("tets_removed") ? r.metrics["tets_removed"].get<double>() : 0.0;
             return removed > 0 ? system_cost(r, "lens_sculpt", &CostSummary::mean_ms) *
                                      double(r.frames) / removed
                                : std::nan("");
           })});
    if (find("phaco_sculpting", 0, 1))
      topo.push_back({"sculpting: lens_sculpt system (tet removal), p99",
                      fit_of("phaco_sculpting", [](const SweepPointResult& r) {
                        return system_cost(r, "lens_sculpt", &CostSummary::p99_ms);
                      })});
    if (find("corneal_incision", 0, 1))
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
  md += why_targets_missed(rows, drills, max_level);

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

  // Charts with their readings.
  md += "### Frame cost against mesh size\n\n";
  for (const std::string& drill : drills) {
    if (!charts.frame_cost.count(drill)) continue;
    std::vector<double> x, y;
    for (int l = 0; l <= max_level; ++l)
      if (const SweepRow* p = find(drill, l, 1))
        x.push_back(p->elements), y.push_back(p->r.frame.p50_ms);
    const PowerFit fit = fit_power_law(x, y);
    std::vector<double> y99;
    for (int l = 0; l <= max_level; ++l)
      if (const SweepRow* p = find(drill, l, 1)) y99.push_back(p->r.frame.p99_ms);
    const PowerFit fit99 = fit_power_law(x, y99);
    md += "![" + drill + "](results/" + charts.frame_cost.at(drill) + ")\n\n";
    md += "**" + drill + "**: frame p50 grows as elements^" +
          (fit.ok ? fmt("%.2f", fit.slope) : std::string("?")) + ", p99 as elements^" +
          (fit99.ok ? fmt("%.2f", fit99.slope) : std::string("?")) + " (1 thread, levels 0.." +
          std::to_string(max_level) + ").";
    if (drill == "capsulorhexis")
      md +=
          " The typical frame grows slowly: the implicit step works on the active nodes around the "
          "tools only (seed 003's active set), whose number depends on the tool's reach more than "
          "on the mesh. The slow frames grow with the mesh: they are the frames where a cut or a "
          "tear changes the topology and the physics is refreshed over the whole capsule (see the "
          "targets' reading).";
    else if (drill == "phaco_sculpting")
      md +=
          " The lens is static tets; a frame is the probe's broadphase query and the removal of "
          "the tets it sweeps (seed 000 §5.3). The lens's volume is fixed, so the tets a tip of "
          "fixed size sweeps grow in proportion to the tet count; the time per removed tet is "
          "flat (targets table).";
    else
      md +=
          " The cornea is cut only while the keratome moves through it; the other frames cost "
          "microseconds. One frame per drill grows with the cornea (the worst cornea_cut frame, "
          "targets table) while the p99 stays flat; it is not analysed further here.";
    md +=
        " The seeds' figures (diamonds) are whole-trainer rates with rendering on 2006–2008 "
        "machines; ours here is the simulation alone, the trainer's rendered rate is in the "
        "trainer section.\n\n";
  }
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
  md += " on 1 thread; error against the default methods at level " +
        std::to_string(reference_level) + ".\n\n";
  md +=
      "| drill | variant | level | frame mean / p99 (ms) | error % | score | capsule divergences / "
      "fallbacks | note |\n|---|---|---:|---|---:|---:|---|---|\n";
  for (const auto& row : rows) {
    const auto& r = row.r;
    if (r.config.threads != 1 || r.config.variant == kNoHaptics) continue;
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
      "trenches. Two caveats. The reference is the default methods' converged answer, so an "
      "alternative that converges to a different answer shows a large error here even where it is "
      "closer to the truth: the exact narrowphases remove every tet the tip touches, not only "
      "those "
      "whose centre it covers, and the lens section compares both with the exact swept volume. The "
      "fragmenting lens is the divide-and-conquer model; the trench drill does not score it. "
      "Without "
      "the active set, the whole capsule's implicit step runs every frame: it is measured up to "
      "level 3 "
      "only, and not in --quick.\n\n";
  for (const std::string& drill : drills)
    if (charts.pareto.count(drill))
      md += "![" + drill + " speed against accuracy](results/" + charts.pareto.at(drill) + ")\n";
  md += "\n";
  // Which choice at which resolution: the Pareto front over every (variant, level) point of a
  // drill on 1 thread, cheapest first: nothing else is both faster and closer to the reference.
  for (const std::string& drill : drills) {
    std::vector<const SweepRow*> pts;
    std::vector<double> x, y;
    for (const auto& row : rows)
      if (row.r.ok && row.r.config.drill == drill && row.r.config.threads == 1 &&
          row.r.config.variant != kNoHaptics && std::isfinite(row.error_pct) && row.error_pct > 0) {
        pts.push_back(&row);
        x.push_back(row.r.frame.mean_ms);
        y.push_back(row.error_pct);
      }
    if (pts.size() < 2) continue;
    md += "**" + drill +
          ", the front** (cheapest first; the reference itself, error 0, is left out):";
    for (size_t i : pareto_indices(x, y))
      md += " " + pts[i]->r.config.variant + " at level " + std::to_string(pts[i]->r.config.level) +
            " (" + fmt("%.3f", x[i]) + " ms, " + fmt("%.2f", y[i]) + " %);";
    md.back() = '.';
    // What beats the default methods at the default level on both counts.
    if (const SweepRow* d = find(drill, 3, 1)) {
      std::string better;
      for (const auto& row : rows)
        if (row.r.ok && row.r.config.drill == drill && row.r.config.level == 3 &&
            row.r.config.threads == 1 && row.r.config.variant != "default" &&
            row.r.config.variant != kNoHaptics && row.r.frame.mean_ms < d->r.frame.mean_ms &&
            row.error_pct < d->error_pct)
          better += (better.empty() ? "" : "; ") + row.r.config.variant + " (" +
                    fmt("%.3f", row.r.frame.mean_ms) + " ms, " + fmt("%.2f", row.error_pct) + " %)";
      md += " At level 3, against the default methods (" + fmt("%.3f", d->r.frame.mean_ms) +
            " ms, " + f("%.2f", d->error_pct) + " %), " +
            (better.empty() ? std::string("no alternative is both faster and closer.")
                            : "both faster and closer: " + better + ".");
    }
    md += "\n\n";
  }
  md +=
      "The stability maps (time step against stiffness per integrator) and OpenPhaco's membrane "
      "against Bullet's btSoftBody are in the membrane section; force propagation against "
      "dynamics, Horn against polar decomposition and the SPH search's cell order are measured on "
      "their own systems in the membrane and lens sections, where they are not a choice of the "
      "scene.\n\n";

  md += "### Thread scaling\n\n![threads](results/" + charts.threads + ")\n\n";
  md +=
      "Dots: the same speed-up without the haptic thread beside the frames. Why the drills do not "
      "reach the target is in the targets' reading above.\n\n";
  md += "### Haptic period under load\n\n![haptic period](results/" + charts.haptics + ")\n\n";
  md += "### Memory per element\n\n![memory](results/" + charts.memory + ")\n\n";
  for (const std::string& drill : drills) {
    const SweepRow* lo = find(drill, 3, 1);
    const SweepRow* hi = find(drill, max_level, 1);
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
  write_section(dir, "sweep", md);
  progress.finish();

  if (!failures.empty()) {
    std::string all_failures;
    for (const auto& e : failures) all_failures += "\n  " + e;
    throw CheckFailed("sweep: " + std::to_string(failures.size()) + " check(s) failed (also in " +
                      (dir / "sweep.md").string() + "):" + all_failures);
  }
}

}  // namespace phaco::perf
