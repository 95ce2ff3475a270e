#pragma once
// Internal to procedures/scene's drill metrics: the measures the report takes from the record and
// the scene at the end of a drill (drill_metrics.hpp lists them; docs/metrics.md).
#include <cstddef>
#include <vector>

#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/drill_record.hpp"

namespace phaco {

// Per hand: path length, speed and force statistics, the tear's force, and the decimated series
// (at the sample indices idx) with the speed and force histograms.
void hand_metrics(const DrillRecord& r, DrillReport& out, const std::vector<size_t>& idx);

// Grasps, the puncture, tear-outs and the opening (diameter, circularity, centring, outline).
void capsulorhexis_metrics(Scene& scene, const DrillRecord& r, DrillReport& out);

// Breaches, the tets and volume removed, each trench against the trench targets, the trench map.
void sculpting_metrics(Scene& scene, const DrillRecord& r, DrillReport& out);

}  // namespace phaco
