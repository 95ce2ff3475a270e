#include "procedures/scene/method_settings.hpp"

#include <cstdlib>

#include "engine/core/error.hpp"

namespace phaco {

const std::vector<MethodSetting>& method_settings() {
  static const std::vector<MethodSetting> table = {
      {"capsule.integrator",
       {"explicit_euler", "symplectic_euler", "semi_implicit_001", "implicit_euler",
        "implicit_predictor", "xpbd"}},
      {"capsule.spring_law", {"linear", "quadratic"}},
      {"capsule.stiffness", {"area_weighted", "uniform"}},
      {"capsule.pretension", {"cotangent", "uniform_prestretch"}},
      {"capsule.active_set", {"on", "off"}},
      {"capsule.cutting", {"on", "off"}},
      {"capsule.tear_rule", {"flap_force", "most_stressed_spring"}},
      {"capsule.preconditioner",
       {"jacobi", "block_jacobi", "incomplete_cholesky", "two_level", "deflation", "balancing"}},
      {"capsule.cg_tolerance", {}},
      {"lens.model", {"tets", "fragments"}},
      {"lens.broadphase", {"octree", "dbvt"}},
      {"lens.narrowphase", {"centre", "exact_gjk", "exact_mpr"}},
      {"tools.ports", {"off", "measure", "constrain"}},
  };
  return table;
}

std::string_view default_lens_model(Drill drill) {
  return drill == Drill::NucleusRemoval ? "fragments" : "tets";
}

const MethodSetting* find_method_setting(std::string_view key) {
  for (const MethodSetting& m : method_settings())
    if (m.key == key) return &m;
  return nullptr;
}

namespace {

[[noreturn]] void refuse(const Scenario& s, std::string_view key, const std::string& problem) {
  throw InputError(s.source + ": methods[\"" + std::string(key) + "\"]: " + problem);
}

void check_value(const Scenario& s, const MethodSetting& m, const std::string& value) {
  if (m.choices.empty()) {
    char* end = nullptr;
    const double v = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0' || !(v > 0.0 && v < 1.0))
      refuse(s, m.key, "expected a number in (0, 1), got '" + value + "'");
    return;
  }
  for (std::string_view c : m.choices)
    if (value == c) return;
  std::string names;
  for (std::string_view c : m.choices) names += (names.empty() ? "" : ", ") + std::string(c);
  refuse(s, m.key, "unknown choice '" + value + "'; expected one of: " + names);
}

}  // namespace

std::string method_value(const Scenario& scenario, std::string_view key,
                         std::string_view fallback) {
  const MethodSetting* m = find_method_setting(key);
  if (m == nullptr)
    throw std::logic_error("method_value: '" + std::string(key) + "' is not in the table");
  const auto it = scenario.methods.find(std::string(key));
  if (it == scenario.methods.end()) return std::string(fallback);
  check_value(scenario, *m, it->second);
  return it->second;
}

void check_method_values(const Scenario& s, const DrillFile& drill) {
  for (const auto& [key, value] : s.methods)
    if (const MethodSetting* m = find_method_setting(key)) check_value(s, *m, value);
  const std::string lens = method_value(s, "lens.model", default_lens_model(s.drill));
  if (s.drill == Drill::NucleusRemoval && lens != "fragments")
    refuse(s, "lens.model",
           "the nucleus_removal drill cracks and removes fragments: it runs lens.model fragments, "
           "got '" +
               lens + "'");
  if (lens == "fragments") {
    for (const char* key : {"lens.broadphase", "lens.narrowphase"})
      if (s.methods.count(key))
        refuse(s, key, "applies to lens.model tets (tetrahedral sculpting), not fragments");
  }
  const std::string ports = method_value(s, "tools.ports", drill.ports);
  if (ports != "off" && (!drill.guidance.incision_site || !drill.guidance.side_port))
    refuse(s, "tools.ports",
           ports + " needs the drill file's guidance.incision_site and guidance.side_port");
}

}  // namespace phaco
