#include "apps/phaco/records_commands.hpp"

#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "apps/phaco/args.hpp"
#include "apps/phaco/commands.hpp"
#include "engine/core/error.hpp"
#include "engine/records/records.hpp"
#include "engine/records/xapi.hpp"

namespace phaco::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// The few metrics that say how a drill went at a glance; the rest are in the export.
const std::vector<std::string>& key_metrics(const std::string& drill) {
  static const std::map<std::string, std::vector<std::string>> kKeys = {
      {"corneal_incision",
       {"incision.width_mm", "incision.entry_angle_deg", "incision.tunnel_length_mm", "time_s"}},
      {"capsulorhexis",
       {"rhexis.diameter_mm", "rhexis.circularity", "rhexis.centering_mm", "rhexis.radial_tearouts",
        "time_s"}},
      {"phaco_sculpting", {"trench.depth_fraction", "trench.width_mm", "capsule_breach", "time_s"}},
      {"nucleus_removal",
       {"volume_removed_fraction", "cde_pct_s", "posterior_capsule.rupture", "time_s"}},
  };
  static const std::vector<std::string> kDefault = {"time_s"};
  const auto it = kKeys.find(drill);
  return it == kKeys.end() ? kDefault : it->second;
}

std::string show(const json& v) {
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number()) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.4g", v.get<double>());
    return buf;
  }
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

std::string show_score(const std::optional<double>& s) {
  if (!s) return "-";
  char buf[16];
  std::snprintf(buf, sizeof buf, "%.1f", *s);
  return buf;
}

// "2026-11-21T19:18:01.123Z" -> "2026-11-21 19:18:01": what a person reads in a table.
std::string show_date(const std::string& utc) {
  std::string d = utc.substr(0, 19);
  if (d.size() > 10 && d[10] == 'T') d[10] = ' ';
  return d;
}

fs::path db_path(const Args& a) {
  if (auto db = a.option("--db")) return *db;
  return default_records_db();
}

struct Trend {
  int sessions = 0, scored = 0;
  double first = 0, last = 0, best = 0;
  int64_t best_id = 0;
  std::string best_date;
};

std::map<std::string, Trend> trends(const std::vector<SessionRecord>& records) {
  std::map<std::string, Trend> out;
  for (const SessionRecord& r : records) {
    Trend& t = out[r.drill];
    ++t.sessions;
    if (!r.score) continue;
    if (t.scored == 0) t.first = *r.score;
    t.last = *r.score;
    if (t.scored == 0 || *r.score > t.best) {
      t.best = *r.score;
      t.best_id = r.id;
      t.best_date = r.started_utc;
    }
    ++t.scored;
  }
  return out;
}

}  // namespace

int history(const std::vector<std::string>& raw) {
  const Args a = parse_args("history", raw, {"--db"}, {"--json"});
  if (a.positional.size() != 1) throw InputError("history: give exactly one trainee name");
  const std::string& trainee = a.positional[0];
  const fs::path db = db_path(a);
  const RecordStore store(db, OpenMode::ExistingOnly);
  const std::vector<SessionRecord> records = store.records_of(trainee);
  if (records.empty()) {
    std::string known;
    for (const auto& name : store.trainees()) known += (known.empty() ? "" : ", ") + name;
    throw InputError("history: no records for trainee '" + trainee + "' in " + store.location() +
                     (known.empty() ? " (it holds no records)" : " (trainees: " + known + ")"));
  }
  const auto by_drill = trends(records);

  if (a.flag("--json")) {
    json out = {{"trainee", trainee}, {"db", store.location()}};
    json rows = json::array();
    for (const SessionRecord& r : records) {
      json keys = json::object();
      for (const auto& k : key_metrics(r.drill)) {
        if (r.metrics.contains(k)) keys[k] = r.metrics[k];
      }
      rows.push_back({{"id", r.id},
                      {"started_utc", r.started_utc},
                      {"drill", r.drill},
                      {"scenario", r.scenario_name},
                      {"score", r.score ? json(*r.score) : json(nullptr)},
                      {"metrics", keys}});
    }
    out["records"] = std::move(rows);
    json trend = json::object();
    for (const auto& [drill, t] : by_drill) {
      json d = {{"sessions", t.sessions}, {"scored", t.scored}};
      if (t.scored > 0) {
        d["first_score"] = t.first;
        d["last_score"] = t.last;
        d["change"] = t.last - t.first;
        d["best_score"] = t.best;
        d["best_id"] = t.best_id;
      }
      trend[drill] = std::move(d);
    }
    out["trend"] = std::move(trend);
    std::printf("%s\n", out.dump(2).c_str());
    return kOk;
  }

  std::printf("trainee %s: %zu session(s) in %s\n", trainee.c_str(), records.size(),
              store.location().c_str());
  std::printf("  %5s  %-19s  %-16s  %5s  %s\n", "id", "date (UTC)", "drill", "score",
              "key metrics");
  for (const SessionRecord& r : records) {
    std::string keys;
    for (const auto& k : key_metrics(r.drill)) {
      if (!r.metrics.contains(k)) continue;
      keys += (keys.empty() ? "" : ", ") + k + " " + show(r.metrics[k]);
    }
    std::printf("  %5lld  %-19s  %-16s  %5s  %s\n", static_cast<long long>(r.id),
                show_date(r.started_utc).c_str(), r.drill.c_str(), show_score(r.score).c_str(),
                keys.empty() ? "-" : keys.c_str());
  }
  std::printf("trend:\n");
  for (const auto& [drill, t] : by_drill) {
    if (t.scored == 0) {
      std::printf("  %-16s %d session(s), none scored\n", drill.c_str(), t.sessions);
      continue;
    }
    std::printf("  %-16s %d session(s), score %.1f -> %.1f (%+.1f), best %.1f (#%lld, %s)\n",
                drill.c_str(), t.sessions, t.first, t.last, t.last - t.first, t.best,
                static_cast<long long>(t.best_id), show_date(t.best_date).substr(0, 10).c_str());
  }
  return kOk;
}

// `phaco export --xapi OUT.json [--trainee NAME] [--home-page IRI]` without an id: every finished
// drill (or the trainee's) as xAPI statements, one JSON array (engine/records/xapi.hpp).
int export_xapi(const Args& a, const std::optional<int64_t>& id) {
  for (const char* o : {"--xml", "--json", "--scenario"})
    if (a.option(o)) throw InputError(std::string("export: --xapi cannot go with ") + o);
  const fs::path db = db_path(a);
  const RecordStore store(db, OpenMode::ExistingOnly);
  std::vector<SessionRecord> records;
  if (id) {
    auto r = store.record(*id);
    if (!r)
      throw InputError("export: no record " + std::to_string(*id) + " in " + store.location());
    records.push_back(std::move(*r));
  } else if (auto trainee = a.option("--trainee")) {
    records = store.records_of(*trainee);
    if (records.empty())
      throw InputError("export: no records for trainee '" + *trainee + "' in " + store.location());
  } else {
    records = store.all_records();
  }
  const std::string home = a.option("--home-page").value_or(kXapiDefaultHomePage);
  if (home.rfind("http://", 0) != 0 && home.rfind("https://", 0) != 0)
    throw InputError("export: --home-page expects an http(s):// IRI, got '" + home + "'");
  json out = json::array();
  for (const SessionRecord& r : records) out.push_back(record_to_xapi(r, home));
  const std::string path = *a.option("--xapi");
  write_text(path, out.dump(2, ' ', false, json::error_handler_t::replace) + "\n");
  std::printf("%zu xAPI statement(s) written to %s\n", records.size(), path.c_str());
  return kOk;
}

int export_record(const std::vector<std::string>& raw) {
  const Args a = parse_args(
      "export", raw,
      {"--db", "--xml", "--json", "--scenario", "--xapi", "--trainee", "--home-page"}, {});
  if (a.positional.size() > 1) throw InputError("export: give at most one record id");
  std::optional<int64_t> id;
  if (!a.positional.empty()) {
    const std::string& text = a.positional[0];
    int64_t v = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (ec != std::errc{} || end != text.data() + text.size() || v < 1) {
      throw InputError("export: a record id is a positive integer, got '" + text + "'");
    }
    id = v;
  }
  if (a.option("--xapi")) return export_xapi(a, id);
  for (const char* o : {"--trainee", "--home-page"})
    if (a.option(o)) throw InputError(std::string("export: ") + o + " goes with --xapi");
  if (!id) throw InputError("export: give a record id (or --xapi OUT for every record)");
  const std::string text = std::to_string(*id);
  const auto xml = a.option("--xml");
  const auto js = a.option("--json");
  const auto scen = a.option("--scenario");
  if (!xml && !js && !scen)
    throw InputError("export: give --xml OUT, --json OUT or --scenario OUT");
  const fs::path db = db_path(a);
  const RecordStore store(db, OpenMode::ExistingOnly);
  const auto record = store.record(*id);
  if (!record) throw InputError("export: no record " + text + " in " + store.location());
  if (xml) {
    write_text(*xml, records_to_xml({*record}));
    std::printf("record %lld written as XML to %s\n", static_cast<long long>(*id), xml->c_str());
  }
  if (js) {
    write_text(*js, record_to_json(*record).dump(2) + "\n");
    std::printf("record %lld written as JSON to %s\n", static_cast<long long>(*id), js->c_str());
  }
  if (scen) {
    write_text(*scen, record->recording.dump(2) + "\n");
    std::printf("record %lld written as a scenario to %s (replay: phaco run %s)\n",
                static_cast<long long>(*id), scen->c_str(), scen->c_str());
  }
  return kOk;
}

}  // namespace phaco::cli
