#pragma once
// The sweep's RESULTS.md section (issue 9, issue 17 item 7): the references, the checks, the
// targets and what the figures show where one is missed, the per-level tables, every point, and
// the charts with their readings. The raw figures are sweep_figures.hpp's.
#include <filesystem>
#include <string>
#include <vector>

#include "perf/sweep/sweep_checks.hpp"
#include "perf/sweep/sweep_data.hpp"
#include "perf/sweep/sweep_plan.hpp"

namespace phaco::perf {

// The section's markdown; draws the charts into results_dir.
std::string sweep_section_md(const std::vector<SweepRow>& rows, const SweepRun& run,
                             const SweepAccuracy& accuracy,
                             const std::vector<std::string>& failures,
                             const std::filesystem::path& results_dir);

}  // namespace phaco::perf
