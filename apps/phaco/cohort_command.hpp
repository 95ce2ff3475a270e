#pragma once
// `phaco cohort [--db DB] --html OUT.html [--title T] [--drill NAME]` (issue 21 item 4): a
// training centre's cohort on one page (procedures/report/cohort_dashboard.hpp), from a station's
// file or the centre's server. Exit codes as in commands.hpp.
#include <string>
#include <vector>

namespace phaco::cli {

int cohort(const std::vector<std::string>& args);

}  // namespace phaco::cli
