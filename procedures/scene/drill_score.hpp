#pragma once
// Internal to procedures/scene's drill metrics: the score (docs/scoring.md).
#include <nlohmann/json.hpp>
#include <optional>

#include "procedures/scene/drill_metrics.hpp"

namespace phaco {

struct DrillFile;

// A target band as JSON: {"min": lo, "max": hi}, either left out when absent.
nlohmann::json band(std::optional<double> lo, std::optional<double> hi);

// The drill file's score terms (docs/scoring.md) against the targets in `out`. A step not
// attempted scores 0 (its safety terms included: "no contact" is no skill when nothing was done);
// a complication fails the drill and caps its score.
void score(DrillReport& out, const DrillFile& drill);

}  // namespace phaco
