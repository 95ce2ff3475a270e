#include "apps/phaco/procedure_command.hpp"

#include <cstdio>
#include <filesystem>
#include <optional>

#include "apps/phaco/commands.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_run.hpp"
#include "procedures/procedure/procedure_run.hpp"
#include "procedures/scene/scene_inputs.hpp"

namespace phaco::cli {

namespace {

// --record/--trainee (docs/records.md, docs/procedures.md): each step that ran is stored as its
// drill's record (the schema has no procedure table, and needs none): its recording is the step's
// scenario, its report the step's, with "procedure" saying which procedure, which step and the
// total, dated when that step ran (so the records keep the steps' order). A stored step replays
// as a drill on a fresh eye; the procedure's replay is its file.
void record_steps(const std::filesystem::path& db, const std::string& trainee,
                  const Procedure& procedure, const ProcedureReport& report, nlohmann::json& j) {
  for (size_t i = 0; i < report.steps.size(); ++i) {
    nlohmann::json step = j["steps"][i];
    const ProcedureStepReport& ran = report.steps[i];
    step["procedure"] = {{"name", report.name},
                         {"file", report.source},
                         {"step", i + 1},
                         {"steps", procedure.steps.size()},
                         {"total", report.total},
                         {"failed", report.failed},
                         {"failure", report.failure}};
    const int64_t id = record_run(db, trainee, procedure.steps[i], step,
                                  ran.finished_unix_s - ran.started_unix_s, ran.finished_unix_s);
    j["steps"][i]["record_id"] = id;
    std::fprintf(stderr, "step %zu %s recorded as record %lld in %s\n", i + 1,
                 std::string(to_string(procedure.steps[i].drill)).c_str(),
                 static_cast<long long>(id), shown_location(db.string()).c_str());
  }
}

}  // namespace

int run_procedure_file(const Args& a, const SceneOptions& options) {
  for (const char* o : {"--haptics", "--hand", "--duration", "--stall-at", "--stall-ms",
                        "--spin-us", "--max-spin-us"}) {
    if (a.option(o)) {
      throw InputError(std::string("run: ") + o +
                       " is for a drill scenario, not a procedure (docs/procedures.md: a live "
                       "procedure is recorded by phaco-trainer --procedure)");
    }
  }
  // Records: checked before the steps, stored after them (a step each).
  const std::optional<std::filesystem::path> db = record_target(a);
  const auto trainee = a.option("--trainee");
  Procedure procedure = load_procedure(a.positional[0]);
  if (auto level = a.option("--difficulty"))
    for (Scenario& s : procedure.steps) s.difficulty = *level;
  const ProcedureReport report = run_procedure(procedure, options);
  nlohmann::json j = to_json(report);
  j["date"] = utc_now();
  if (db) record_steps(*db, *trainee, procedure, report, j);
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
