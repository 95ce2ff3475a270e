#pragma once
// The sweep's raw figures (issue 9): sweep.csv and sweep.json, one row per point, and the saved
// points (sweep_points.json) that `phaco-perf sweep --replot` redraws the report from.
#include <filesystem>
#include <vector>

#include "perf/sweep/sweep_data.hpp"
#include "perf/sweep/sweep_plan.hpp"

namespace phaco::perf {

// Writes sweep.csv and sweep.json, and (unless the run is a replot) sweep_points.json.
void write_sweep_figures(const std::vector<SweepRow>& rows, const SweepRun& run,
                         const std::filesystem::path& results_dir);

// Reads what write_sweep_figures saved: the run and its points. Throws InputError naming the file.
SweepRun read_saved_sweep(const std::filesystem::path& results_dir, std::vector<SweepRow>& rows);

}  // namespace phaco::perf
