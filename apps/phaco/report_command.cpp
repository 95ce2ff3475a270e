#include "apps/phaco/report_command.hpp"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/phaco/commands.hpp"
#include "engine/core/error.hpp"
#include "procedures/report/compare_section.hpp"
#include "procedures/report/html_report.hpp"
#include "procedures/report/procedure_html.hpp"

namespace phaco::cli {

namespace {

// The file's modification time in UTC, for reports that carry no date of their own.
std::string file_date(const std::filesystem::path& path) {
  std::error_code ec;
  const auto t = std::filesystem::last_write_time(path, ec);
  if (ec) return {};
  const auto sys = std::chrono::file_clock::to_sys(t);
  const std::time_t tt = std::chrono::system_clock::to_time_t(sys);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC (report file time)", &tm);
  return buf;
}

}  // namespace

int report(const std::vector<std::string>& args) {
  std::string in, out, expert;  // --expert: docs/compare.md
  for (size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--html") {
      if (i + 1 >= args.size()) throw InputError("report: option --html needs a value");
      out = args[++i];
    } else if (args[i] == "--expert") {
      if (i + 1 >= args.size()) throw InputError("report: option --expert needs a value");
      expert = args[++i];
    } else if (args[i].rfind("--", 0) == 0) {
      throw InputError("report: unknown option '" + args[i] + "' (try 'phaco --help')");
    } else if (in.empty()) {
      in = args[i];
    } else {
      throw InputError("report: unexpected argument '" + args[i] + "' (give one RUN.json)");
    }
  }
  if (in.empty())
    throw InputError("report: give the run report file (phaco report RUN.json --html OUT.html)");
  if (out.empty()) throw InputError("report: --html OUT.html is required");

  std::ifstream file(in);
  if (!file) throw InputError(in + ": cannot open the run report");
  nlohmann::json run;
  try {
    run = nlohmann::json::parse(file);
  } catch (const nlohmann::json::parse_error& e) {
    throw InputError(in + ": not valid JSON (" + e.what() + ")");
  }
  if (run.is_object() && !run.contains("date")) {
    if (const std::string d = file_date(in); !d.empty()) run["date"] = d;
  }
  if (report::is_procedure_report(run) && !expert.empty())
    throw InputError("report: --expert compares a drill's run; " + in +
                     " is a procedure's (compare its steps: docs/procedures.md)");
  // Compared before the page is drawn, so a bad expert file fails with its own name.
  const std::string compared = expert.empty() ? std::string()
                                              : report::compare_section(compare::compare_reports(
                                                    run, compare::read_report(expert), in, expert));
  std::string html;
  try {
    // A procedure's report: its steps' pages under the total (docs/procedures.md).
    html = report::is_procedure_report(run) ? report::procedure_html(run)
                                            : report::html_report(run, compared);
  } catch (const InputError& e) {
    throw InputError(in + ": " + e.what());
  }
  std::ofstream page(out, std::ios::binary);
  if (!page) throw InputError("report: cannot write '" + out + "'");
  page << html;
  if (!page.flush()) throw InputError("report: cannot write '" + out + "'");
  std::printf("%s: wrote %s (%zu bytes)\n", in.c_str(), out.c_str(), html.size());
  return kOk;
}

}  // namespace phaco::cli
