// How metrics, targets and score terms read (procedures/report/term_text, issue 24 item 3): the
// one formatting the HTML report and the trainer's Result panel share.
#include <gtest/gtest.h>

#include "procedures/report/html_report.hpp"
#include "procedures/report/term_text.hpp"

namespace phaco::report {
namespace {

using nlohmann::json;

TEST(TermText, NamesWithUnits) {
  EXPECT_EQ(metric_label("rhexis.diameter_mm"), "rhexis diameter (mm)");
  EXPECT_EQ(metric_label("rhexis.complete"), "rhexis complete");
  EXPECT_EQ(metric_label("time_s"), "time (s)");
  EXPECT_EQ(metric_label("left.tool_speed_mm_s.mean"), "left tool speed mean (mm/s)");
  EXPECT_EQ(metric_label("incision.entry_angle_deg"), "incision entry angle (°)");
  EXPECT_EQ(metric_label("cde_pct_s"), "cde (% s)");
  EXPECT_EQ(metric_label("lens_contacts"), "lens contacts");
  EXPECT_EQ(metric_unit("corneal_stress_events"), "");
}

TEST(TermText, TargetsAsRangesAndVerdicts) {
  EXPECT_EQ(target_text(json{{"min", 5.0}, {"max", 5.5}}, "mm"), "5 – 5.5 mm");
  EXPECT_EQ(target_text(json{{"min", 0.9}}), "≥ 0.9");
  EXPECT_EQ(target_text(json{{"max", 0}}), "≤ 0");
  EXPECT_EQ(target_text(json(nullptr)), "—");
  EXPECT_EQ(meets(5.24, json{{"min", 5.0}, {"max", 5.5}}), true);
  EXPECT_EQ(meets(1, json{{"max", 0}}), false);
  EXPECT_EQ(meets(true, json{{"min", 1}}), true);
  EXPECT_FALSE(meets("text", json{{"min", 1}}).has_value());

  fields::Term t;
  t.metric = "rhexis.diameter_mm";
  t.value = 5.24;
  t.target = json{{"min", 5.0}, {"max", 5.5}};
  t.weight = 20;
  t.points = 20;
  const TermText r = term_text(t);
  EXPECT_EQ(r.label, "rhexis diameter (mm)");
  EXPECT_EQ(r.value, "5.24 mm");
  EXPECT_EQ(r.target, "5 – 5.5 mm");
  EXPECT_EQ(r.points, "20");
  EXPECT_EQ(r.met, true);
}

// The HTML report's score table prints the very same cells.
TEST(TermText, TheHtmlReportUsesIt) {
  json run = {{"drill", "capsulorhexis"},
              {"metrics", {{"score", 80}, {"rhexis.diameter_mm", 5.24}}},
              {"score_terms", json::array({{{"metric", "rhexis.diameter_mm"},
                                            {"value", 5.24},
                                            {"target", {{"min", 5.0}, {"max", 5.5}}},
                                            {"weight", 20},
                                            {"points", 20}}})}};
  const std::string html = html_report(run);
  EXPECT_NE(html.find("<td>rhexis diameter (mm)</td><td class=\"num\">5.24 mm</td><td>5 – 5.5 mm"),
            std::string::npos);
}

}  // namespace
}  // namespace phaco::report
