// The sweep's accuracy and checks; see sweep_checks.hpp.
#include "perf/sweep/sweep_checks.hpp"

#include <cmath>

#include "perf/report.hpp"
#include "perf/sweep/sweep_levels.hpp"
#include "perf/sweep/sweep_plan.hpp"
#include "procedures/eye/eye_params.hpp"

namespace phaco::perf {

namespace fs = std::filesystem;

Bound bound_of(const std::string& drill) {
  if (drill == "capsulorhexis") return {2, 10.0};
  if (drill == "phaco_sculpting") return {1, 15.0};
  return {1, 10.0};
}

fs::path results_file(const fs::path& dir, const char* name) {
  if (fs::exists(dir / name)) return dir / name;
  return fs::path(PHACO_SOURCE_DIR) / "perf" / "results" / name;
}

SweepAccuracy assess_accuracy(std::vector<SweepRow>& rows, const std::vector<std::string>& drills,
                              const fs::path& dir, int finest_level) {
  SweepAccuracy a;
  for (const auto& row : rows)
    if (row.r.ok && row.r.config.variant == "default" && row.r.config.threads == 1 &&
        row.r.config.level == finest_level)
      a.finest[row.r.config.drill] = &row;
  const auto file = load_reference_file(results_file(dir, "sweep_reference.json"));
  for (const std::string& drill : drills) {
    std::string current;
    if (file && file->drills.count(drill))
      current =
          reference_key(file->drills.at(drill).recipe, reference_inputs(eye::data_dir(), drill));
    const auto it = a.finest.find(drill);
    a.references[drill] = choose_reference(drill, file ? &*file : nullptr, current,
                                           it == a.finest.end() ? nullptr : it->second);
  }
  measure_accuracy(rows, a.references);
  const Baseline b = load_baseline(results_file(dir, "sweep_baseline.json"));
  a.baseline_source = b.source;
  for (const auto& p : b.points) a.baseline.push_back(SweepRow{.r = p});
  measure_accuracy(a.baseline, a.references);
  return a;
}

void check_points(const std::vector<SweepRow>& rows, const SweepAccuracy& accuracy,
                  const std::vector<std::string>& drills, int reference_level,
                  std::vector<std::string>& failures) {
  const auto& reference = accuracy.finest;
  std::map<std::string, std::string> hash_of;
  for (const auto& row : rows) {
    if (!row.r.ok) continue;
    const SweepPointConfig& c = row.r.config;
    auto [it, fresh] = hash_of.emplace(point_key(c), row.r.state_hash);
    if (!fresh && it->second != row.r.state_hash)
      failures.push_back(point_label(c) + ": state hash " + row.r.state_hash +
                         " differs from the 1-thread run's " + it->second +
                         " (runs must be bit-identical whatever the thread count)");
    if (!row.r.metrics.contains("score") || !row.r.metrics["score"].is_number())
      failures.push_back(point_label(c) + ": no score in the run's metrics");
    if (c.variant != "default") continue;
    const double divergences = physics_number(row.r, "capsule", "divergences");
    if (std::isfinite(divergences) && divergences > 0)
      failures.push_back(point_label(c) + ": the capsule diverged " + fmt("%.0f", divergences) +
                         " times");
    const Bound b = bound_of(c.drill);
    const auto fin = reference.find(c.drill);
    std::string detail;
    const double converge =
        fin != reference.end() ? accuracy_error_pct(row.r, fin->second->r, &detail) : std::nan("");
    if (c.level >= b.from_level && !(converge <= b.max_error_pct))
      failures.push_back(point_label(c) + ": accuracy error " + fmt_or_dash("%.2f", converge) +
                         " % against level " + std::to_string(reference_level) +
                         " exceeds its bound " + fmt("%.0f", b.max_error_pct) + " % (" + detail +
                         ")");
  }
  if (reference.size() < drills.size())
    failures.push_back("a drill has no reference point (level " + std::to_string(reference_level) +
                       ", 1 thread)");
}

}  // namespace phaco::perf
