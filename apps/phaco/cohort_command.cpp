#include "apps/phaco/cohort_command.hpp"

#include <cstdio>
#include <fstream>

#include "apps/phaco/args.hpp"
#include "apps/phaco/commands.hpp"
#include "engine/core/error.hpp"
#include "engine/records/record_run.hpp"
#include "engine/records/records.hpp"
#include "engine/records/xapi.hpp"
#include "procedures/report/cohort_dashboard.hpp"

namespace phaco::cli {

int cohort(const std::vector<std::string>& raw) {
  const Args a = parse_args("cohort", raw, {"--db", "--html", "--title", "--drill"}, {});
  if (!a.positional.empty())
    throw InputError("cohort: unexpected argument '" + a.positional[0] + "'");
  const auto html = a.option("--html");
  if (!html) throw InputError("cohort: give --html OUT.html");
  const std::filesystem::path db =
      a.option("--db") ? std::filesystem::path(*a.option("--db")) : default_records_db();
  const RecordStore store(db, OpenMode::ExistingOnly);
  std::vector<report::CohortAttempt> attempts;
  for (const SessionRecord& r : store.all_records()) {
    if (a.option("--drill") && r.drill != *a.option("--drill")) continue;
    report::CohortAttempt at{r.trainee, r.drill, r.started_utc, r.score, nlohmann::json::array()};
    if (r.report.contains("score_terms") && r.report["score_terms"].is_array())
      at.score_terms = r.report["score_terms"];
    attempts.push_back(std::move(at));
  }
  report::CohortOptions o;
  o.title = a.option("--title").value_or("Cohort");
  o.source = store.location();
  o.pass_score = kPassScore;
  const std::string page = report::cohort_dashboard(attempts, o);
  std::ofstream out(*html, std::ios::binary);
  out << page;
  if (!out.flush()) throw InputError("cohort: cannot write '" + *html + "'");
  std::printf("cohort page of %zu drill(s) written to %s\n", attempts.size(), html->c_str());
  return kOk;
}

}  // namespace phaco::cli
