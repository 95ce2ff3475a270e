#pragma once
// `phaco compare RUN.json EXPERT.json [--json OUT.json]`: a run report compared with an expert's
// (procedures/compare/compare.hpp, docs/compare.md). Prints a short table (per hand the
// DTW-aligned path distance, speed and force differences, the same at equal times, the time
// ratio, then run − expert per metric); --json writes the whole comparison with its aligned
// series. Returns 0; throws InputError (exit 2) naming the file and field of a malformed report.
#include <string>
#include <vector>

namespace phaco::cli {

int compare(const std::vector<std::string>& args);

}  // namespace phaco::cli
