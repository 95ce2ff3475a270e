#pragma once
// The report page's "Compared with the expert" section (docs/compare.md, docs/report.md):
// `phaco report RUN.json --html OUT.html --expert EXPERT.json`. Reads a Comparison
// (procedures/compare/compare.hpp) and returns an HTML fragment: the time ratio, per hand the
// DTW-aligned path distance, speed and force differences (and the same at equal times, for
// contrast), the metric differences (run − expert), and one OpenCV figure, inlined as a PNG data:
// URI: the aligned path distance (mm) above the force difference (mN), per hand, over the run.
#include <string>

#include "procedures/compare/compare.hpp"

namespace phaco::report {

std::string compare_section(const compare::Comparison& comparison);

}  // namespace phaco::report
