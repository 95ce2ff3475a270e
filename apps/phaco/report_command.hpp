#pragma once
// `phaco report RUN.json --html OUT.html`: the run report (the JSON `phaco run --report` writes)
// as one self-contained HTML page (procedures/report/html_report.hpp, docs/report.md).
// Returns the exit code: 0 written; throws InputError (exit 2) for a missing, unreadable or
// malformed file, with the file name and the offending field in the message.
#include <string>
#include <vector>

namespace phaco::cli {

int report(const std::vector<std::string>& args);

}  // namespace phaco::cli
