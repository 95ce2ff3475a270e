#pragma once
// Running a procedure (procedure_file.hpp, docs/procedures.md): each step is its drill's scene,
// built on the eye the earlier steps left (carry.hpp) and scored as that drill scores it
// (procedures/scene/drill_metrics). The procedure's total is the mean of its steps' scores, a
// step not run counting 0. A complication in a step (the drill file's "complications": a radial
// tear-out, a posterior capsule rupture, iris trauma) fails the procedure there, and so does an
// incision that never entered the anterior chamber when steps follow it: the steps after are not
// run, and the report says why.
//
// Step by step (the trainer): start_step builds the next step's scene, the caller steps it,
// finish_step scores it and carries its eye on. run_procedure does all of it headless.
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "procedures/procedure/procedure_file.hpp"
#include "procedures/scene/carried_state.hpp"
#include "procedures/scene/run.hpp"

namespace phaco {

struct ProcedureStepReport {
  RunReport run;                                         // as its drill scores it
  nlohmann::json carried_in = nlohmann::json::object();  // the eye it started from
  // When the step ran, wall clock (s since the Unix epoch): its scene built, its score taken. Each
  // step's record is dated by these, so the records keep the steps' order.
  double started_unix_s = 0, finished_unix_s = 0;
};

struct ProcedureReport {
  std::string source, name;
  std::vector<ProcedureStepReport> steps;  // the steps that ran, in order
  std::vector<std::string> not_run;        // the drills of the steps a failure left out
  double total = 0;                        // 0..100: mean step score, a step not run 0
  bool failed = false;
  std::string failure;  // "<drill>: <why>" when failed
  double wall_time_s = 0;
};

struct ProcedureState {
  const Procedure* procedure = nullptr;
  size_t next = 0;  // the step start_step builds
  CarriedState carried;
  ProcedureReport report;
  double step_started_unix_s = 0;  // when start_step began building the next step's scene
};

ProcedureState begin_procedure(const Procedure& procedure);
// Whether every step ran or one failed the procedure.
bool procedure_done(const ProcedureState& state);
// The next step's scene on the carried eye (options.carried is set here).
std::unique_ptr<Scene> start_step(ProcedureState& state, SceneOptions options);
// Scores the step's scene as it stands, carries its eye on, fails the procedure on a complication;
// when done, fills the total and the steps not run.
void finish_step(ProcedureState& state, Scene& scene, double wall_time_s);

ProcedureReport run_procedure(const Procedure& procedure, const SceneOptions& options);
nlohmann::json to_json(const ProcedureReport& report);
std::string summary_text(const ProcedureReport& report);

}  // namespace phaco
