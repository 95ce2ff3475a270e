#include "perf/sweep/sweep_mechanics.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "perf/report.hpp"
#include "perf/sweep/sweep_levels.hpp"

namespace phaco::perf {

namespace fs = std::filesystem;

namespace {

constexpr const char* kIntegratorVariant = "capsule.integrator=";

// The membrane study's label for a scene integrator ("" when it has no static-load row).
std::string study_method(const std::string& integrator) {
  if (integrator == "xpbd") return "xpbd 8 it";
  if (integrator == "implicit_euler" || integrator == "implicit_predictor" ||
      integrator == "semi_implicit_001")
    return integrator;
  return "";
}

std::string pct(double error) {
  return fmt("%.1f", 100.0 * error) + " %";
}

}  // namespace

std::map<std::string, MembraneError> membrane_static_errors(const fs::path& file,
                                                            const std::string& setting) {
  std::map<std::string, MembraneError> out;
  std::ifstream in(file);
  if (!in) return out;
  const nlohmann::json rows = nlohmann::json::parse(in, nullptr, false);
  if (!rows.is_array()) return out;
  for (const std::string integrator :
       {"implicit_euler", "implicit_predictor", "semi_implicit_001", "xpbd"})
    for (const auto& row : rows)
      if (row.value("part", "") == "accuracy" &&
          row.value("method", "") == study_method(integrator) &&
          row.value("setting", "") == setting && row.contains("error") && row["error"].is_number())
        out[integrator] = {study_method(integrator), row["error"].get<double>()};
  return out;
}

std::string integrator_mechanics_md(const std::vector<SweepRow>& rows,
                                    const fs::path& membrane_file,
                                    const std::string& skip_variant) {
  const std::string drill = "capsulorhexis";
  const SweepRow* d = find_row(rows, drill, 3, 1);
  if (!d || d->r.sim_s <= 0 || d->r.frames == 0) return "";
  const DrillFront front = drill_front(rows, drill, skip_variant);
  for (const SweepRow* p : front.front)
    if (p->r.config.variant == "default" && p->r.config.level == 3) return "";

  // Integrators that contend: on the front, or faster and closer than the default at level 3.
  std::vector<std::string> contenders;
  const auto add = [&contenders](const std::string& variant) {
    if (variant.rfind(kIntegratorVariant, 0) != 0) return;
    const std::string name = variant.substr(std::string(kIntegratorVariant).size());
    if (std::find(contenders.begin(), contenders.end(), name) == contenders.end())
      contenders.push_back(name);
  };
  for (const SweepRow* p : front.front) add(p->r.config.variant);
  for (const SweepRow* p : front.points)
    if (p->r.config.level == 3 && p->r.frame.mean_ms < d->r.frame.mean_ms &&
        p->error_pct < d->error_pct)
      add(p->r.config.variant);
  if (contenders.empty()) return "";

  const long steps_per_s = std::lround(double(d->r.frames) / d->r.sim_s);
  const std::string setting = "dt 1/" + std::to_string(steps_per_s) + " s";
  const auto errors = membrane_static_errors(membrane_file, setting);
  const auto base = errors.find("implicit_euler");
  std::string md =
      "**The integrator behind the capsulorhexis front.** The drill's outcome is drawn by the "
      "forceps' track and the tear rule, which every integrator shares, so the front cannot see "
      "how the membrane itself answers a load. The membrane section's static-load case does, at "
      "the scene's step (" +
      setting + "): the error after one frame of a point load against the static equilibrium. ";
  if (base == errors.end())
    return md + "It has no row for implicit Euler at that step in " +
           membrane_file.filename().string() + " (run `phaco-perf membrane`), so no integrator " +
           "on the front is judged here.\n\n";
  md += "Implicit Euler (the default): " + pct(base->second.error) +
        ". An alternative replaces it " + "only within " + fmt("%.0f", kMechanicsTolerance) +
        "× of that.";
  for (const std::string& name : contenders) {
    const auto it = errors.find(name);
    md += " " + name + ": ";
    if (it == errors.end()) {
      md += "not measured in the static-load case, so not judged.";
      continue;
    }
    const bool fit = it->second.error <= kMechanicsTolerance * base->second.error;
    md += pct(it->second.error) +
          (it->second.method != name ? " (" + it->second.method + ")" : "") +
          (fit ? ": **it may replace the default.**" : ", so the default stays.");
  }
  return md + "\n\n";
}

}  // namespace phaco::perf
