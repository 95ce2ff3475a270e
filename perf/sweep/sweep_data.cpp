#include "perf/sweep/sweep_data.hpp"

#include <cmath>
#include <limits>

#include "perf/report.hpp"

namespace phaco::perf {

namespace {

double element(const SweepPointResult& r, const std::string& key) {
  const auto it = r.elements.find(key);
  return it == r.elements.end() ? 0.0 : double(it->second);
}

}  // namespace

double point_metric(const SweepPointResult& r, const std::string& name) {
  const auto it = r.metrics.find(name);
  return it != r.metrics.end() && it->is_number() ? it->get<double>()
                                                  : std::numeric_limits<double>::quiet_NaN();
}

const char* drill_elements_name(const std::string& drill) {
  if (drill == "capsulorhexis") return "capsule vertices";
  if (drill == "phaco_sculpting") return "lens tets";
  if (drill == "nucleus_removal") return "lens cells";
  return "cornea vertices";
}

double drill_elements(const SweepPointResult& r) {
  const std::string& d = r.config.drill;
  if (d == "capsulorhexis") return element(r, "capsule.particles");
  if (d == "phaco_sculpting") {
    // Tets left at the end plus those the probe removed: the lens as the drill began.
    const double removed = point_metric(r, "tets_removed");
    return element(r, "lens.tets") + (std::isfinite(removed) ? removed : 0.0);
  }
  if (d == "nucleus_removal") return physics_number(r, "lens_fragments", "cells");
  return element(r, "cornea.particles");
}

// The outcome a trainee is scored on, one metric per aspect: for the capsulorhexis the opening's
// size and roundness; for sculpting the volume removed and the trench's width and depth; for the
// incision its width and tunnel length; for nucleus removal the volume removed, the cracks made and
// the chopper's largest push (docs/metrics.md).
const std::vector<std::string>& accuracy_metrics(const std::string& drill) {
  static const std::vector<std::string> rhexis = {"rhexis.diameter_mm", "rhexis.circularity"};
  static const std::vector<std::string> sculpt = {"volume_removed_mm3", "trench.width_mm",
                                                  "trench.depth_fraction"};
  static const std::vector<std::string> incision = {"incision.width_mm",
                                                    "incision.tunnel_length_mm"};
  if (drill == "capsulorhexis") return rhexis;
  static const std::vector<std::string> nucleus = {"volume_removed_fraction", "cracks",
                                                   "chopper_force_mN.max"};
  if (drill == "phaco_sculpting") return sculpt;
  if (drill == "nucleus_removal") return nucleus;
  return incision;
}

double accuracy_error_pct(const SweepPointResult& r, const SweepPointResult& reference,
                          std::string* detail) {
  double worst = 0;
  for (const std::string& name : accuracy_metrics(r.config.drill)) {
    const double m = point_metric(r, name), ref = point_metric(reference, name);
    if (!std::isfinite(m) || !std::isfinite(ref) || ref == 0) {
      if (detail) *detail = name + " missing";
      return std::numeric_limits<double>::quiet_NaN();
    }
    const double e = 100.0 * std::abs(m - ref) / std::abs(ref);
    if (e >= worst) {
      worst = e;
      if (detail) *detail = name + " " + fmt("%.3f", m) + " vs " + fmt("%.3f", ref);
    }
  }
  return worst;
}

double physics_number(const SweepPointResult& r, const std::string& body, const std::string& k) {
  if (!r.physics.contains(body) || !r.physics[body].contains(k) || !r.physics[body][k].is_number())
    return std::numeric_limits<double>::quiet_NaN();
  return r.physics[body][k].get<double>();
}

double refresh_ms_per_patched_spring(const SweepPointResult& r) {
  const double springs = physics_number(r, "capsule_cutting", "physics_refresh_springs_mean");
  return springs > 0 ? physics_number(r, "capsule_cutting", "physics_refresh_ms_mean") / springs
                     : std::numeric_limits<double>::quiet_NaN();
}

double system_cost(const SweepPointResult& r, const std::string& name, double CostSummary::*field) {
  for (const auto& s : r.systems)
    if (s.name == name) return s.*field;
  return std::numeric_limits<double>::quiet_NaN();
}

const SweepRow* find_row(const std::vector<SweepRow>& rows, const std::string& drill, int level,
                         int threads, const std::string& variant) {
  for (const auto& row : rows)
    if (row.r.ok && row.r.config.drill == drill && row.r.config.level == level &&
        row.r.config.threads == threads && row.r.config.variant == variant)
      return &row;
  return nullptr;
}

}  // namespace phaco::perf
