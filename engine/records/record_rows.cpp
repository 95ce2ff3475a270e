#include "engine/records/record_rows.hpp"

#include "engine/core/error.hpp"
#include "engine/io/json_reader.hpp"

namespace phaco::records {

namespace {

using nlohmann::json;

std::string dump(const json& j) {
  // Replace rather than throw on invalid UTF-8 in a string: a name typed on a terminal in another
  // encoding should not lose a finished drill.
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

json json_column(const RowText& row, int col, const std::string& database, const char* name) {
  const std::string source =
      database + ": record " + std::to_string(row.id) + ", column '" + name + "'";
  json j = io::parse_json_text(row.columns[col], source);
  if (!j.is_object()) {
    throw InputError(source + ": expected a JSON object, got " + io::describe_value(j));
  }
  return j;
}

}  // namespace

RowText row_of(const SessionRecord& r) {
  RowText t;
  t.id = r.id;
  t.columns = {"",
               r.trainee,
               r.drill,
               r.scenario_name,
               r.started_utc,
               r.finished_utc,
               dump(r.settings),
               dump(r.metrics),
               "",
               r.state_hash,
               dump(r.recording),
               dump(r.report),
               r.uuid};
  t.score = r.score;
  return t;
}

SessionRecord record_from_row(const RowText& t, const std::string& database) {
  SessionRecord r;
  r.id = t.id;
  r.trainee = t.columns[1];
  r.drill = t.columns[2];
  r.scenario_name = t.columns[3];
  r.started_utc = t.columns[4];
  r.finished_utc = t.columns[5];
  r.settings = json_column(t, 6, database, "settings");
  r.metrics = json_column(t, 7, database, "metrics");
  r.score = t.score;
  r.state_hash = t.columns[9];
  r.recording = json_column(t, 10, database, "recording");
  r.report = json_column(t, 11, database, "report");
  r.uuid = t.columns[12];
  return r;
}

}  // namespace phaco::records
