#include "engine/records/xapi.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "engine/core/utc_time.hpp"

namespace phaco {

namespace {

using nlohmann::json;

// Every metric as {"value": v, "unit": u}: an LMS reads the unit next to the number.
json metrics_with_units(const json& metrics) {
  json out = json::object();
  for (const auto& [name, value] : metrics.items())
    out[name] = {{"value", value}, {"unit", metric_unit(name)}};
  return out;
}

}  // namespace

std::string iso8601_duration(double seconds) {
  if (!(seconds > 0) || !std::isfinite(seconds)) return "PT0S";
  const long long ms = std::llround(seconds * 1000.0);
  const long long h = ms / 3600000, m = ms / 60000 % 60;
  const double s = static_cast<double>(ms % 60000) / 1000.0;
  std::string out = "PT";
  if (h) out += std::to_string(h) + "H";
  if (m) out += std::to_string(m) + "M";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", s);
  std::string sec = buf;
  while (sec.back() == '0') sec.pop_back();
  if (sec.back() == '.') sec.pop_back();
  if (sec != "0" || out == "PT") out += sec + "S";
  return out;
}

json record_to_xapi(const SessionRecord& r, const std::string& home_page) {
  const std::string ext = kXapiExtensionIri;
  json result = {{"completion", true}};
  if (r.score) {
    const double raw = std::clamp(*r.score, 0.0, 100.0);
    result["score"] = {{"scaled", raw / 100.0}, {"raw", raw}, {"min", 0}, {"max", 100}};
    result["success"] = raw >= kPassScore;
  }
  const auto started = parse_utc(r.started_utc), finished = parse_utc(r.finished_utc);
  if (started && finished) result["duration"] = iso8601_duration(*finished - *started);
  result["extensions"] = {{ext + "metrics", metrics_with_units(r.metrics)}};
  json statement = {
      {"actor",
       {{"objectType", "Agent"},
        {"name", r.trainee},
        {"account", {{"homePage", home_page}, {"name", r.trainee}}}}},
      {"verb",
       {{"id", "http://adlnet.gov/expapi/verbs/completed"}, {"display", {{"en-US", "completed"}}}}},
      {"object",
       {{"objectType", "Activity"},
        {"id", kXapiDrillIri + r.drill},
        {"definition",
         {{"name", {{"en-US", r.drill}}},
          {"type", "http://adlnet.gov/expapi/activities/simulation"}}}}},
      {"result", std::move(result)},
      {"context",
       {{"platform", "OpenPhaco"},
        {"language", "en-US"},
        {"extensions",
         {{ext + "scenario", r.scenario_name},
          {ext + "state_hash", r.state_hash},
          {ext + "settings", r.settings}}}}}};
  // The build that made the run (the report's "software": name, version, revision), when known.
  if (r.report.is_object() && r.report.contains("software"))
    statement["context"]["extensions"][ext + "software"] = r.report["software"];
  if (!r.uuid.empty()) statement["id"] = r.uuid;
  if (finished) statement["timestamp"] = r.finished_utc;
  return statement;
}

}  // namespace phaco
