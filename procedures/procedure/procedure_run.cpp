#include "procedures/procedure/procedure_run.hpp"

#include <cstdio>

#include "engine/core/clock.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/core/version.hpp"
#include "procedures/procedure/carry.hpp"

namespace phaco {

namespace {

double step_score(const RunReport& r) {
  return r.metrics.value("score", 0.0);
}

// Why the step fails the procedure ("" when it does not).
std::string failure_of(Scene& scene, const RunReport& r, bool last) {
  std::string why;
  for (const auto& c : r.complications)
    why += (why.empty() ? "" : "; ") + c.value("name", std::string("complication"));
  if (why.empty() && !last && scene.scenario.drill == Drill::CornealIncision &&
      !incision_entered_chamber(scene))
    why = "the blade did not enter the anterior chamber: no main port for the next steps";
  return why.empty() ? why : r.drill + ": " + why;
}

void finish_procedure(ProcedureState& s) {
  const auto& steps = s.procedure->steps;
  for (size_t i = s.report.steps.size(); i < steps.size(); ++i)
    s.report.not_run.push_back(std::string(to_string(steps[i].drill)));
  double sum = 0;
  for (const auto& step : s.report.steps) sum += step_score(step.run);
  s.report.total = steps.empty() ? 0.0 : sum / static_cast<double>(steps.size());
  s.next = steps.size();
}

}  // namespace

ProcedureState begin_procedure(const Procedure& procedure) {
  ProcedureState s;
  s.procedure = &procedure;
  s.report.source = procedure.source;
  s.report.name = procedure.name;
  return s;
}

bool procedure_done(const ProcedureState& s) {
  return s.report.failed || s.next >= s.procedure->steps.size();
}

std::unique_ptr<Scene> start_step(ProcedureState& s, SceneOptions options) {
  s.step_started_unix_s = unix_now_s();
  options.carried = &s.carried;
  return build_scene(s.procedure->steps.at(s.next), options);
}

void finish_step(ProcedureState& s, Scene& scene, double wall_time_s) {
  ProcedureStepReport step;
  step.finished_unix_s = unix_now_s();
  // A scene not built by start_step (the trainer's session builds its own) ran for its wall time.
  step.started_unix_s =
      s.step_started_unix_s > 0 ? s.step_started_unix_s : step.finished_unix_s - wall_time_s;
  s.step_started_unix_s = 0;
  step.carried_in = carried_json(s.carried);
  step.run = report_of(scene);
  step.run.wall_time_s = wall_time_s;
  s.report.wall_time_s += wall_time_s;
  const bool last = s.next + 1 >= s.procedure->steps.size();
  if (const std::string why = failure_of(scene, step.run, last); !why.empty()) {
    s.report.failed = true;
    s.report.failure = why;
  }
  carry_out(scene, s.carried);
  s.report.steps.push_back(std::move(step));
  ++s.next;
  if (procedure_done(s)) finish_procedure(s);
}

ProcedureReport run_procedure(const Procedure& procedure, const SceneOptions& options) {
  ProcedureState s = begin_procedure(procedure);
  while (!procedure_done(s)) {
    auto scene = start_step(s, options);
    const uint64_t frames = scene->scenario.frame_count();
    Stopwatch wall;
    for (uint64_t f = 0; f < frames; ++f) step(*scene);
    finish_step(s, *scene, wall.elapsed_s());
  }
  return std::move(s.report);
}

nlohmann::json to_json(const ProcedureReport& r) {
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& step : r.steps) {
    nlohmann::json j = to_json(step.run);
    j["carried_in"] = step.carried_in;
    if (step.finished_unix_s > 0) j["date"] = format_utc(step.finished_unix_s);  // as a drill's
    steps.push_back(std::move(j));
  }
  nlohmann::json scores = nlohmann::json::object();
  for (const auto& step : r.steps) scores[step.run.drill] = step_score(step.run);
  return {{"procedure", r.name},
          {"scenario", r.source},
          {"steps", std::move(steps)},
          {"step_scores", scores},
          {"not_run", r.not_run},
          {"total", r.total},
          {"failed", r.failed},
          {"failure", r.failure},
          {"wall_time_s", r.wall_time_s},
          {"software", {{"name", "OpenPhaco"}, {"version", version()}, {"revision", revision()}}}};
}

std::string summary_text(const ProcedureReport& r) {
  std::string out = r.source + "  procedure " + (r.name.empty() ? "(unnamed)" : r.name) + "\n";
  char line[256];
  for (const auto& step : r.steps) {
    out += summary_text(step.run);
    std::snprintf(line, sizeof line, "step %-18s score %5.1f / 100  (%.3f s wall)\n\n",
                  step.run.drill.c_str(), step_score(step.run), step.run.wall_time_s);
    out += line;
  }
  out += "procedure steps:";
  for (const auto& step : r.steps) {
    std::snprintf(line, sizeof line, "  %s %.1f", step.run.drill.c_str(), step_score(step.run));
    out += line;
  }
  for (const auto& d : r.not_run) out += "  " + d + " not run (0)";
  std::snprintf(line, sizeof line, "\nprocedure total %.1f / 100%s  (stepping took %.3f s wall)\n",
                r.total, r.failed ? "   FAILED" : "", r.wall_time_s);
  out += line;
  if (r.failed) out += "failed at " + r.failure + "\n";
  return out;
}

}  // namespace phaco
