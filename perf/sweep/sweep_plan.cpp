// The sweep's plan; see sweep_plan.hpp.
#include "perf/sweep/sweep_plan.hpp"

#include <algorithm>
#include <string>

#include "engine/core/error.hpp"
#include "perf/sweep/sweep_data.hpp"
#include "procedures/eye/resolution.hpp"

namespace phaco::perf {

namespace fs = std::filesystem;

std::vector<Variant> variants_of(const std::string& drill) {
  std::vector<Variant> v;
  auto method = [&](const std::string& k, const std::string& value) {
    v.push_back({k + "=" + value, "", {{k, value}}});
  };
  if (drill == "capsulorhexis") {
    for (const char* i :
         {"implicit_predictor", "semi_implicit_001", "symplectic_euler", "explicit_euler", "xpbd"})
      method("capsule.integrator", i);
    // The default (deflation, ≤ 40 CG iterations: issue 17 item 2) against the one it replaced.
    method("capsule.preconditioner", "block_jacobi");
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

SweepArgs parse_sweep_args(const StudyOptions& options) {
  SweepArgs a;
  a.max_level = options.quick ? 3 : eye::kMaxLevel;
  bool drills_given = false;
  auto number = [&](size_t& i, const char* what, int lo, int hi) {
    const int v = option_int("sweep", what, options.extra[++i]);
    if (v < lo || v > hi)
      throw InputError(std::string("sweep: ") + what + " out of " + std::to_string(lo) + ".." +
                       std::to_string(hi));
    return v;
  };
  for (size_t i = 0; i < options.extra.size(); ++i) {
    const std::string& o = options.extra[i];
    const bool has_value = i + 1 < options.extra.size();
    if (o == "--replot") {
      a.replot = true;
    } else if (o == "--reference") {
      a.reference = true;
    } else if (o == "--reference-level" && has_value) {
      a.reference_level = number(i, "--reference-level", 0, eye::kMaxLevel);
    } else if (o == "--reference-dt-divisor" && has_value) {
      a.reference_dt_divisor = number(i, "--reference-dt-divisor", 1, 64);
    } else if (o == "--speedup-reps" && has_value) {
      a.speedup_reps = number(i, "--speedup-reps", 1, 20);
    } else if (o == "--max-level" && has_value) {
      a.max_level = number(i, "--max-level", 1, eye::kMaxLevel);
    } else if (o == "--drill" && has_value) {
      const std::string d = options.extra[++i];
      if (d != "capsulorhexis" && d != "phaco_sculpting" && d != "corneal_incision")
        throw InputError(
            "sweep: --drill expects capsulorhexis, phaco_sculpting or corneal_incision, got '" + d +
            "'");
      if (!drills_given) a.drills.clear(), drills_given = true;
      if (std::find(a.drills.begin(), a.drills.end(), d) == a.drills.end()) a.drills.push_back(d);
    } else {
      throw InputError("sweep: unknown option '" + o + "'");
    }
  }
  if (a.speedup_reps > 0 && (a.reference || a.replot))
    throw InputError("sweep: --speedup-reps goes with a sweep that measures");
  if ((a.reference_level >= 0 || a.reference_dt_divisor > 0) && !a.reference)
    throw InputError("sweep: --reference-level and --reference-dt-divisor go with --reference");
  return a;
}

fs::path sweep_cache_dir(const fs::path& results_dir) {
  const char* env_cache = std::getenv("PHACO_CACHE_DIR");
  return env_cache && *env_cache ? fs::path(env_cache) : results_dir / ".mesh-cache";
}

SweepPlan plan_sweep(const SweepRun& run, bool quick, const fs::path& scenarios,
                     const fs::path& cache) {
  const std::vector<std::string>& drills = run.drills;
  const std::vector<int>& threads = run.threads;
  const std::vector<int>& variant_levels = run.variant_levels;
  const int max_level = run.max_level;
  std::vector<int> levels;
  for (int l = 0; l <= max_level; ++l) levels.push_back(l);
  const char* kNoHaptics = kNoHapticsVariant;
  const char* kGraphEveryFrame = kGraphEveryFrameVariant;
  // The plan: a warm-up per (drill, level, layout) builds the meshes into the cache, so that no
  // measured point pays for (or keeps the memory of) mesh generation.
  SweepPlan p;
  std::vector<SweepPointConfig>& warm = p.warm;
  std::vector<SweepPointConfig>& plan = p.points;
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
        SweepPointConfig c{
            .drill = drill, .scenario = scenario, .level = level, .threads = t, .cache_dir = cache};
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
        c.variant = kGraphEveryFrame;
        c.haptics = true;
        c.graph_every_frame = true;
        plan.push_back(c);
      }
    }
    for (const Variant& v : variants_of(drill)) {
      for (int level : variant_levels) {
        if (level > max_level || level > v.max_level || (quick && !v.quick)) continue;
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
  // The speed-up's repeats: the capsulorhexis default points again, after everything else, so
  // that a repetition is minutes away from the first and a slow spell of the machine does not
  // pair with itself; the thread order alternates (ABBA) from one repetition to the next.
  if (std::find(drills.begin(), drills.end(), "capsulorhexis") != drills.end()) {
    const fs::path scenario = scenarios / "capsulorhexis_expert.json";
    for (int rep = 2; rep <= run.speedup_reps; ++rep)
      for (int level : levels)
        for (size_t k = 0; k < threads.size(); ++k) {
          const int t = rep % 2 == 0 ? threads[threads.size() - 1 - k] : threads[k];
          plan.push_back(SweepPointConfig{.drill = "capsulorhexis",
                                          .scenario = scenario,
                                          .level = level,
                                          .threads = t,
                                          .variant = repeat_variant(rep),
                                          .cache_dir = cache});
        }
  }
  return p;
}

std::string point_key(const SweepPointConfig& c) {
  // A repeat is the default point again: same key, so its state hash must be the same.
  return c.drill + "/" + std::to_string(c.level) + "/" +
         (is_repeat_variant(c.variant) ? std::string("default") : c.variant);
}

std::string point_label(const SweepPointConfig& c) {
  return c.drill + " level " + std::to_string(c.level) + ", " + std::to_string(c.threads) +
         " thread" + (c.threads > 1 ? "s" : "") + (c.variant == "default" ? "" : ", " + c.variant);
}

}  // namespace phaco::perf
