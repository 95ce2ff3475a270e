#pragma once
// `phaco run PROCEDURE.json` and `phaco validate PROCEDURE.json` (issue 20 item 1,
// docs/procedures.md): the steps run headless in one eye, each scored as its drill, the total.
#include <string>

#include "apps/phaco/args.hpp"
#include "procedures/scene/scene.hpp"

namespace phaco::cli {

// Runs the procedure file a.positional[0]; --report, --json and --difficulty as for a scenario.
int run_procedure_file(const Args& a, const SceneOptions& options);

// Checks a procedure file and each step's inputs as `run` reads them; prints one line.
void validate_procedure_file(const std::string& file);

}  // namespace phaco::cli
