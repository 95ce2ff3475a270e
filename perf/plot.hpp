#pragma once
// The perf harness draws with the engine's chart library (engine/plot/chart.hpp); its studies use
// the names unqualified, as they did when the library lived here.
#include "engine/plot/chart.hpp"

namespace phaco::perf {

using plot::Axis;
using plot::Chart;
using plot::fit_power_law;
using plot::Marker;
using plot::pareto_indices;
using plot::PowerFit;
using plot::render_chart;
using plot::RenderReport;
using plot::save_chart;
using plot::Scale;
using plot::Series;
using plot::Style;

}  // namespace phaco::perf
