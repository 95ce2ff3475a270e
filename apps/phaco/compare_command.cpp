#include "apps/phaco/compare_command.hpp"

#include <algorithm>
#include <cstdio>

#include "apps/phaco/args.hpp"
#include "apps/phaco/commands.hpp"
#include "engine/core/error.hpp"
#include "procedures/compare/compare.hpp"

namespace phaco::cli {

namespace {

bool is_procedure(const nlohmann::json& report) {
  return report.is_object() && report.contains("steps");
}

// Two procedures' reports, step by step (docs/procedures.md): each step the two both ran is
// compared as a drill's run; a step only one of them ran is named.
nlohmann::json compare_procedures(const nlohmann::json& run, const nlohmann::json& expert,
                                  const std::string& run_name, const std::string& expert_name,
                                  std::string& text) {
  if (!is_procedure(run) || !is_procedure(expert) || !run["steps"].is_array() ||
      !expert["steps"].is_array())
    throw InputError("compare: " + run_name + " and " + expert_name +
                     ": compare two procedures' reports or two drills' runs, not one of each");
  nlohmann::json steps = nlohmann::json::array();
  const nlohmann::json &a = run["steps"], &b = expert["steps"];
  for (size_t i = 0; i < std::max(a.size(), b.size()); ++i) {
    const std::string at = "steps[" + std::to_string(i) + "]";
    if (i >= a.size() || i >= b.size()) {
      text += at + ": only " + (i < a.size() ? run_name : expert_name) + " ran it\n";
      continue;
    }
    const compare::Comparison c =
        compare::compare_reports(a[i], b[i], run_name + ": " + at, expert_name + ": " + at);
    text += "step " + std::to_string(i + 1) + " (" + a[i].value("drill", std::string()) + ")\n" +
            compare::summary_text(c) + "\n";
    steps.push_back(compare::to_json(c));
  }
  return {{"steps", std::move(steps)},
          {"total", {{"run", run.value("total", 0.0)}, {"expert", expert.value("total", 0.0)}}}};
}

}  // namespace

int compare(const std::vector<std::string>& raw) {
  const Args a = parse_args("compare", raw, {"--json"}, {});
  if (a.positional.size() != 2) {
    throw InputError(
        "compare: give the run report and the expert's (phaco compare RUN.json "
        "EXPERT.json [--json OUT.json])");
  }
  const nlohmann::json run = compare::read_report(a.positional[0]),
                       expert = compare::read_report(a.positional[1]);
  nlohmann::json j;
  std::string text;
  if (is_procedure(run) || is_procedure(expert)) {
    j = compare_procedures(run, expert, a.positional[0], a.positional[1], text);
  } else {
    const compare::Comparison c =
        compare::compare_reports(run, expert, a.positional[0], a.positional[1]);
    j = compare::to_json(c);
    text = compare::summary_text(c);
  }
  if (auto out = a.option("--json")) write_text(*out, j.dump(2) + "\n");
  std::fputs(text.c_str(), stdout);
  if (auto out = a.option("--json")) std::printf("comparison written to %s\n", out->c_str());
  return kOk;
}

}  // namespace phaco::cli
