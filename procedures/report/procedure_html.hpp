#pragma once
// A procedure's report (`phaco run PROCEDURE.json --report RUN.json`, docs/procedures.md) as one
// self-contained HTML page: the total and the failure if any, a table of the steps (score,
// attempted, complications, the eye each started from: main port, rhexis radius, trench), then
// each step's own drill page (html_report.hpp) inline as an iframe's srcdoc — no file beside it,
// no script.
#include <nlohmann/json.hpp>
#include <string>

namespace phaco::report {

// Whether `run` is a procedure's report (it has "steps").
bool is_procedure_report(const nlohmann::json& run);

// Throws InputError naming the field when a step or a field has the wrong type.
std::string procedure_html(const nlohmann::json& procedure);

}  // namespace phaco::report
