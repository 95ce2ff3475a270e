#pragma once
// The run report's fields as the HTML page uses them (procedures/report/html_report): read and
// type-checked in one pass before anything is drawn, so a wrong type is reported with its JSON
// path ("series.hands.left.force_mN: expected an array of numbers") and the page's sections are
// written from plain structs. A missing field is never an error: its optional stays empty.
#include <array>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace phaco::report::fields {

using nlohmann::json;

struct Band {
  std::optional<double> min, max;
};

struct Term {
  std::string metric;
  json value, target;
  std::optional<double> weight, points;
};

struct Event {
  std::optional<double> t_s;
  std::string kind, hand;
  std::vector<std::pair<std::string, std::string>> details;
};

struct Hand {
  std::string name, tool;
  std::optional<std::vector<std::array<double, 3>>> pos;  // mm
  std::optional<std::vector<double>> speed;               // mm/s
  std::optional<std::vector<double>> force;               // mN
};

struct Rhexis {
  std::vector<std::array<double, 2>> outline;                           // mm
  std::optional<std::array<double, 2>> target_diameter, target_centre;  // mm
};

struct Trench {
  std::vector<std::array<double, 3>> removed;  // x mm, y mm, depth fraction
  std::optional<double> nucleus_radius;        // mm
};

struct Run {
  std::string drill, scenario, date, state_hash;
  std::string software;  // "OpenPhaco 0.1.0 (revision ...)": the build that made the run, if known
  std::optional<double> sim_time_s, frames;
  bool has_metrics = false;
  std::vector<std::pair<std::string, json>> metrics;  // in the file's (sorted) order
  std::optional<double> score;
  bool not_attempted = false;              // metrics.attempted 0: the step scored 0
  std::vector<std::string> complications;  // the names that failed the drill (score capped)
  bool has_targets = false;
  std::map<std::string, Band> targets;
  bool has_terms = false;
  std::vector<Term> terms;
  bool has_events = false;
  std::vector<Event> events;
  bool has_series = false;
  std::optional<std::vector<double>> t_s;
  std::vector<Hand> hands;  // left, right, then any other, in that order
  std::optional<Rhexis> rhexis;
  std::optional<Trench> trench;
};

// Field `key` of `object` (which may be any JSON value), or nullptr.
const json* member(const json& object, const char* key);

// Reads every field the page uses. Throws InputError naming the field's path.
Run read_run(const json& run);

// A JSON scalar as the page shows it: numbers to 4 significant digits (integers whole), yes/no,
// strings as they are, "—" for null, anything else as JSON cut to 80 characters.
std::string scalar_text(const json& j);
std::string fmt(double v);  // the number part of scalar_text; "n/a" when not finite

}  // namespace phaco::report::fields
