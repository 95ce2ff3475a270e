#pragma once
// How a metric, its target and a score term read for a person (issue 24 item 3): one formatting
// for the HTML report (procedures/report/html_report) and the trainer's Result panel, so the two
// never disagree. Names lose their unit suffix and gain it in words ("rhexis.diameter_mm" →
// "rhexis diameter (mm)"); targets read as ranges with the unit ("5 – 5.5 mm", "≥ 0.9"); a verdict
// says whether a value meets its target.
#include <optional>
#include <string>

#include "procedures/report/report_fields.hpp"

namespace phaco::report {

// The unit in a metric key's last unit suffix ("_mm" → "mm", "_mm_s" → "mm/s", "_deg" → "°",
// "_s" → "s", "_pct_s" → "% s", "_mN" → "mN"); "" when it has none.
std::string metric_unit(const std::string& metric);
// The key in words with its unit: "rhexis.diameter_mm" → "rhexis diameter (mm)".
std::string metric_label(const std::string& metric);

// A number, or a yes/no as 1/0; empty otherwise.
std::optional<double> as_number(const nlohmann::json& j);
std::string band_text(const fields::Band& b, const std::string& unit = "");
bool within(double v, const fields::Band& b);
// A target as JSON ({"min": .., "max": ..}) as a range, with `unit`; other JSON as scalar_text.
std::string target_text(const nlohmann::json& target, const std::string& unit = "");
// Whether `value` (a number or a yes/no) meets `target`; empty when either is not comparable.
std::optional<bool> meets(const nlohmann::json& value, const nlohmann::json& target);

// One score term's row, every cell as it is shown.
struct TermText {
  std::string label;   // metric_label
  std::string value;   // scalar_text, with the unit
  std::string target;  // target_text, with the unit
  std::string weight, points;
  std::optional<bool> met;
};
TermText term_text(const fields::Term& t);

}  // namespace phaco::report
