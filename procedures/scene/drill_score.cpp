// The drill's score; see drill_score.hpp and band_points in drill_metrics.hpp.
#include "procedures/scene/drill_score.hpp"

#include <algorithm>
#include <string>

#include "engine/io/drill_file.hpp"

namespace phaco {

nlohmann::json band(std::optional<double> lo, std::optional<double> hi) {
  nlohmann::json j = nlohmann::json::object();
  if (lo) j["min"] = *lo;
  if (hi) j["max"] = *hi;
  return j;
}

void score(DrillReport& out, const DrillFile& drill) {
  const auto number = [&out](const std::string& metric) {
    return out.metrics.contains(metric) && out.metrics[metric].is_number()
               ? std::optional<double>(out.metrics[metric].get<double>())
               : std::nullopt;
  };
  out.attempted = drill.attempted_if_any.empty();
  for (const std::string& m : drill.attempted_if_any) out.attempted |= number(m).value_or(0.0) > 0;
  for (const ScoreTerm& t : drill.scoring) {
    const nlohmann::json value =
        out.metrics.contains(t.metric) ? out.metrics[t.metric] : nlohmann::json();
    const nlohmann::json target =
        out.targets.contains(t.metric) ? out.targets[t.metric] : nlohmann::json::object();
    const double points = out.attempted ? band_points(value, target, t.falloff, t.weight) : 0.0;
    out.score_terms.push_back({{"metric", t.metric},
                               {"value", value},
                               {"target", target},
                               {"weight", t.weight},
                               {"points", points}});
    out.score += points;
  }
  out.score = std::clamp(out.score, 0.0, 100.0);
  for (const Complication& c : drill.complications) {
    const auto v = number(c.metric);
    if (!v || *v <= c.above) continue;
    out.complications.push_back(
        {{"name", c.name}, {"metric", c.metric}, {"value", *v}, {"score_cap", c.score_cap}});
    out.score = std::min(out.score, c.score_cap);
  }
  out.metrics["attempted"] = out.attempted ? 1 : 0;
  out.metrics["drill_failed"] = out.complications.empty() ? 0 : 1;
}

double band_points(const nlohmann::json& value, const nlohmann::json& target, double falloff,
                   double weight) {
  if (!value.is_number()) return 0.0;
  const double v = value.get<double>();
  double outside = 0.0;
  if (target.contains("min")) outside = std::max(outside, target["min"].get<double>() - v);
  if (target.contains("max")) outside = std::max(outside, v - target["max"].get<double>());
  if (outside <= 0.0) return weight;
  if (falloff <= 0.0) return 0.0;
  return weight * std::max(0.0, 1.0 - outside / falloff);
}

}  // namespace phaco
