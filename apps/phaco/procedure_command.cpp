#include "apps/phaco/procedure_command.hpp"

#include <cstdio>

#include "apps/phaco/commands.hpp"
#include "engine/core/utc_time.hpp"
#include "procedures/procedure/procedure_run.hpp"
#include "procedures/scene/scene_inputs.hpp"

namespace phaco::cli {

int run_procedure_file(const Args& a, const SceneOptions& options) {
  for (const char* o : {"--haptics", "--hand", "--duration", "--stall-at", "--stall-ms",
                        "--spin-us", "--record", "--trainee"}) {
    if (a.option(o)) {
      throw InputError(std::string("run: ") + o +
                       " is for a drill scenario, not a procedure (docs/procedures.md: a live "
                       "procedure is recorded by phaco-trainer --procedure)");
    }
  }
  Procedure procedure = load_procedure(a.positional[0]);
  if (auto level = a.option("--difficulty"))
    for (Scenario& s : procedure.steps) s.difficulty = *level;
  const ProcedureReport report = run_procedure(procedure, options);
  nlohmann::json j = to_json(report);
  j["date"] = utc_now();
  if (auto path = a.option("--report")) write_text(*path, j.dump(2) + "\n");
  print_run(a, j, summary_text(report));
  return kOk;
}

void validate_procedure_file(const std::string& file) {
  const Procedure p = load_procedure(file);
  double duration = 0;
  for (const Scenario& s : p.steps) {
    check_scene_inputs(s);
    duration += s.duration_s;
  }
  std::printf("%s: ok (procedure, %zu step(s), %.3f s)\n", file.c_str(), p.steps.size(), duration);
}

}  // namespace phaco::cli
