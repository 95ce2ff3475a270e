#include "procedures/report/procedure_html.hpp"

#include <cstdio>

#include "engine/core/error.hpp"
#include "engine/core/markup.hpp"
#include "procedures/report/html_report.hpp"

namespace phaco::report {

namespace {

constexpr const char* kProcedureStyle = R"(
body { font-family: "DejaVu Sans", Helvetica, Arial, sans-serif; color: #222; margin: 24px auto;
       max-width: 1100px; }
table { border-collapse: collapse; margin: 12px 0; }
td, th { border: 1px solid #ccc; padding: 4px 10px; text-align: left; }
.fail { color: #b02a1a; font-weight: bold; }
iframe { width: 100%; height: 1400px; border: 1px solid #ccc; }
)";

std::string fixed(double v, const char* format = "%.1f") {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

// The eye a step started from, in a few words.
std::string carried_text(const nlohmann::json& c) {
  std::string out;
  if (c.contains("main_port")) {
    const auto& p = c["main_port"];
    out += "main port at " + fixed(p.value("clock_hour", 0.0)) + " o'clock, " +
           fixed(p.value("width_mm", 0.0), "%.2f") + " mm wide, tunnel " +
           fixed(p.value("tunnel_length_mm", 0.0), "%.2f") + " mm";
  }
  if (c.contains("rhexis_radius_mm"))
    out += (out.empty() ? "" : "; ") + std::string("rhexis ") +
           fixed(2.0 * c.value("rhexis_radius_mm", 0.0), "%.2f") + " mm";
  if (c.contains("lens_tets_removed"))
    out += (out.empty() ? "" : "; ") + std::string("trench of ") +
           std::to_string(c.value("lens_tets_removed", 0)) + " tets";
  return out.empty() ? "the drill's fresh eye" : out;
}

std::string step_row(size_t i, const nlohmann::json& step) {
  const nlohmann::json metrics = step.value("metrics", nlohmann::json::object());
  std::string complications;
  for (const auto& c : step.value("complications", nlohmann::json::array()))
    complications += (complications.empty() ? "" : "; ") + c.value("name", std::string());
  return "<tr><td>" + std::to_string(i + 1) + "</td><td>" +
         escape_markup(step.value("drill", std::string("?"))) + "</td><td>" +
         fixed(metrics.value("score", 0.0)) + "</td><td>" +
         (step.value("attempted", true) ? "yes" : "no") + "</td><td class=\"fail\">" +
         escape_markup(complications) + "</td><td>" +
         escape_markup(carried_text(step.value("carried_in", nlohmann::json::object()))) +
         "</td></tr>\n";
}

}  // namespace

bool is_procedure_report(const nlohmann::json& run) {
  return run.is_object() && run.contains("steps");
}

std::string procedure_html(const nlohmann::json& p) {
  if (!p.is_object() || !p["steps"].is_array())
    throw InputError("steps: expected an array of step reports");
  const std::string name = p.value("procedure", std::string("procedure"));
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<title>" +
      escape_markup(name) + "</title>\n<style>" + kProcedureStyle +
      "</style>\n</head>\n<body>\n<h1>Procedure: " + escape_markup(name) + "</h1>\n";
  html += "<p>" + escape_markup(p.value("scenario", std::string())) + " &middot; " +
          escape_markup(p.value("date", std::string())) + "</p>\n";
  html += "<h2>Total " + fixed(p.value("total", 0.0)) + " / 100</h2>\n";
  if (p.value("failed", false))
    html += "<p class=\"fail\">FAILED at " + escape_markup(p.value("failure", std::string())) +
            "</p>\n";
  html +=
      "<table>\n<tr><th>step</th><th>drill</th><th>score</th><th>attempted</th>"
      "<th>complications</th><th>started from</th></tr>\n";
  const nlohmann::json& steps = p["steps"];
  for (size_t i = 0; i < steps.size(); ++i) html += step_row(i, steps[i]);
  for (const auto& d : p.value("not_run", nlohmann::json::array()))
    html += "<tr><td>-</td><td>" + escape_markup(d.get<std::string>()) +
            "</td><td>0.0</td><td>not run</td><td></td><td></td></tr>\n";
  html +=
      "</table>\n<p>The total is the mean of the steps' scores, a step not run counting 0 "
      "(docs/procedures.md).</p>\n";
  for (size_t i = 0; i < steps.size(); ++i) {
    nlohmann::json step = steps[i];
    if (!step.contains("date") && p.contains("date")) step["date"] = p["date"];
    std::string page;
    try {
      page = html_report(step);
    } catch (const InputError& e) {
      throw InputError("steps[" + std::to_string(i) + "]." + e.what());
    }
    html += "<h2>Step " + std::to_string(i + 1) + ": " +
            escape_markup(step.value("drill", std::string("?"))) + "</h2>\n<iframe srcdoc=\"" +
            escape_markup(page) + "\"></iframe>\n";
  }
  return html + "</body>\n</html>\n";
}

}  // namespace phaco::report
