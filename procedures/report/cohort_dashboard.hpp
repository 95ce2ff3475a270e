#pragma once
// A training centre's cohort on one page (issue 21 item 4): `phaco cohort --html OUT.html` draws,
// from the records of every trainee,
//   - per drill, every trainee's learning curve (score against attempt number) with the pass line;
//   - per drill, the cohort's pass rates: the share of trainees whose latest attempt passes, and of
//     all attempts;
//   - per trainee, the weakest metrics: the score terms that lost the most points on average over
//     their attempts (from each record's run report, "score_terms").
// One self-contained HTML5 page: inline SVG and CSS, no script, no external resource. Each curve
// is an SVG polyline of class "curve" with data-trainee and data-drill attributes, so a browser
// test can find one per trainee.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace phaco::report {

// One finished drill, as the dashboard needs it (the CLI fills it from the records).
struct CohortAttempt {
  std::string trainee, drill, started_utc;
  std::optional<double> score;  // 0..100; unscored attempts are listed, not drawn
  nlohmann::json score_terms;   // the run report's [{metric, value, target, weight, points}]
};

struct CohortOptions {
  std::string title = "Cohort";
  std::string source;        // where the records came from (shown, password masked by the caller)
  double pass_score = 75.0;  // the pass line
  int weakest = 3;           // metrics listed per trainee
};

// The page. Attempts are taken in started_utc order per trainee and drill.
std::string cohort_dashboard(std::vector<CohortAttempt> attempts, const CohortOptions& options);

}  // namespace phaco::report
