// XML and JSON export of session records (seed 000 §6.4); the layout is documented in
// docs/records.md and kept fixed so other programs can read it.
#include <cstdint>
#include <string_view>
#include <utility>
#include <vector>

#include "engine/core/markup.hpp"
#include "engine/io/json_reader.hpp"
#include "engine/records/records.hpp"

namespace phaco {

namespace {

using nlohmann::json;

bool ends_with(std::string_view s, std::string_view suffix) {
  return s.size() > suffix.size() && s.substr(s.size() - suffix.size()) == suffix;
}

// The unit of one name segment, or empty when the segment names none. Longer suffixes first:
// "_mm_s" before "_s", "_mN_mm" before "_mm".
std::string segment_unit(std::string_view seg) {
  static const std::pair<std::string_view, std::string_view> kSuffixes[] = {
      {"_mm_s", "mm/s"}, {"_mN_mm", "mN/mm"}, {"_mn_mm", "mN/mm"}, {"_mm3", "mm^3"},
      {"_mm2", "mm^2"},  {"_mm", "mm"},       {"_mN", "mN"},       {"_mn", "mN"},
      {"_kpa", "kPa"},   {"_kPa", "kPa"},     {"_deg", "deg"},     {"_rad", "rad"},
      {"_ms", "ms"},     {"_s", "s"},         {"_hz", "Hz"},       {"_Hz", "Hz"},
      {"_pct", "%"},     {"_fraction", "1"},
  };
  if (seg == "score") return "points";
  if (seg == "clock_hour") return "clock hour";
  for (const auto& [suffix, unit] : kSuffixes) {
    if (ends_with(seg, suffix)) return std::string(unit);
  }
  return {};
}

bool is_statistic(std::string_view seg) {
  static const std::string_view kStats[] = {
      "mean", "std", "max",  "min",   "median",    "p50",   "p90",    "p95", "p99",
      "rms",  "sum", "last", "first", "histogram", "edges", "counts", "bins"};
  for (auto s : kStats) {
    if (seg == s) return true;
  }
  return false;
}

std::string value_text(const json& v) {
  if (v.is_number_integer()) return v.dump();
  if (v.is_number_float()) return io::format_number(v.get<double>());
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_string()) return v.get<std::string>();
  if (v.is_null()) return "";
  return v.dump(-1, ' ', false, json::error_handler_t::replace);  // arrays: the JSON text
}

std::string value_type(const json& v) {
  if (v.is_number()) return "number";
  if (v.is_boolean()) return "bool";
  if (v.is_string()) return "string";
  if (v.is_null()) return "null";
  return "array";
}

// Nested objects flattened to dotted names, leaves in key order (a fixed, sorted layout).
void flatten(const json& j, const std::string& prefix,
             std::vector<std::pair<std::string, json>>& out) {
  for (const auto& [key, value] : j.items()) {
    const std::string name = prefix.empty() ? key : prefix + "." + key;
    if (value.is_object() && !value.empty()) {
      flatten(value, name, out);
    } else {
      out.emplace_back(name, value);
    }
  }
}

// <TAG name=".." unit=".." type="..">value</TAG>, one per leaf; unit only on numbers and bools.
void write_values(std::string& out, const json& j, const char* tag, const char* indent) {
  std::vector<std::pair<std::string, json>> leaves;
  if (j.is_object()) flatten(j, "", leaves);
  for (const auto& [name, value] : leaves) {
    out += indent;
    out += "<";
    out += tag;
    out += " name=\"" + escape_markup(name) + "\"";
    if (value.is_number() || value.is_boolean())
      out += " unit=\"" + escape_markup(metric_unit(name)) + "\"";
    out += " type=\"" + value_type(value) + "\">";
    append_escaped_markup(out, value_text(value));
    out += "</";
    out += tag;
    out += ">\n";
  }
}

void element(std::string& out, const char* indent, const char* tag, std::string_view text) {
  out += indent;
  out += "<";
  out += tag;
  out += ">";
  append_escaped_markup(out, text);
  out += "</";
  out += tag;
  out += ">\n";
}

}  // namespace

std::string metric_unit(const std::string& name) {
  // From the right, skip statistic segments ("mean", "max", ...); the first other segment names
  // the unit, or the quantity is a count or a ratio.
  std::vector<std::string_view> segments;
  std::string_view rest = name;
  for (size_t dot; (dot = rest.find('.')) != std::string_view::npos; rest.remove_prefix(dot + 1)) {
    segments.push_back(rest.substr(0, dot));
  }
  segments.push_back(rest);
  for (size_t i = segments.size(); i-- > 0;) {
    if (i > 0 && is_statistic(segments[i])) continue;
    const std::string unit = segment_unit(segments[i]);
    return unit.empty() ? "1" : unit;
  }
  return "1";
}

std::string records_to_xml(const std::vector<SessionRecord>& records) {
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  out += "<openphaco_records schema=\"" + std::to_string(kRecordsSchemaVersion) + "\">\n";
  for (const SessionRecord& r : records) {
    out += "  <session id=\"" + std::to_string(r.id) + "\"";
    // The uuid (schema 2): the record's identity across stations and the centre.
    if (!r.uuid.empty()) out += " uuid=\"" + r.uuid + "\"";
    out += ">\n";
    element(out, "    ", "trainee", r.trainee);
    element(out, "    ", "drill", r.drill);
    element(out, "    ", "scenario", r.scenario_name);
    element(out, "    ", "started_utc", r.started_utc);
    element(out, "    ", "finished_utc", r.finished_utc);
    out += "    <settings>\n";
    write_values(out, r.settings, "setting", "      ");
    out += "    </settings>\n";
    out += "    <metrics>\n";
    write_values(out, r.metrics, "metric", "      ");
    out += "    </metrics>\n";
    if (r.score) {
      out += "    <score unit=\"points\">" + io::format_number(*r.score) + "</score>\n";
    }
    element(out, "    ", "state_hash", r.state_hash);
    out += "  </session>\n";
  }
  out += "</openphaco_records>\n";
  return out;
}

json record_to_json(const SessionRecord& r) {
  json j = {{"id", r.id},
            {"trainee", r.trainee},
            {"drill", r.drill},
            {"scenario_name", r.scenario_name},
            {"started_utc", r.started_utc},
            {"finished_utc", r.finished_utc},
            {"settings", r.settings},
            {"metrics", r.metrics},
            {"score", r.score ? json(*r.score) : json(nullptr)},
            {"state_hash", r.state_hash},
            {"uuid", r.uuid},
            {"recording", r.recording},
            {"report", r.report}};
  return j;
}

}  // namespace phaco
