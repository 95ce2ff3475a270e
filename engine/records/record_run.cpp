#include "engine/records/record_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "engine/core/error.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/io/user_dirs.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/records.hpp"

namespace phaco {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

void check_trainee(const std::string& trainee) {
  if (trainee.empty()) throw InputError("the trainee needs a name");
  if (trainee.size() > 200) throw InputError("the trainee's name is over 200 characters");
  for (const char c : trainee) {
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      throw InputError("the trainee's name contains a control character");
  }
}

void make_parent_dir(const fs::path& db) {
  if (is_postgres_uri(db.string()) || !db.has_parent_path()) return;
  std::error_code ec;
  fs::create_directories(db.parent_path(), ec);
  if (ec)
    throw InputError("cannot create '" + db.parent_path().string() + "': " + ec.message() +
                     "; give --db FILE|URI or set PHACO_DB (or XDG_DATA_HOME) to a writable place");
}

// How long the run took, wall seconds: it started that long before now.
double run_seconds(const json& report, std::optional<double> run_s) {
  if (run_s) return std::isfinite(*run_s) ? std::max(0.0, *run_s) : 0.0;
  double took = 0;
  for (const char* k : {"wall_time_s", "mesh_load_s"}) {
    if (report.contains(k) && report[k].is_number() && std::isfinite(report[k].get<double>()))
      took += std::max(0.0, report[k].get<double>());
  }
  return took;
}

}  // namespace

fs::path default_records_db() {
  for (const char* name : {"PHACO_DB", "PHACO_RECORDS_DB"})
    if (const char* env = std::getenv(name); env && *env) return env;
  try {
    return io::user_dir(io::UserDir::Data) / "records.sqlite";
  } catch (const InputError& e) {
    throw InputError(std::string(e.what()) + "; give --db FILE|URI or set PHACO_DB");
  }
}

void check_record_target(const fs::path& db, const std::string& trainee) {
  check_trainee(trainee);
  make_parent_dir(db);
  const RecordStore store(db, OpenMode::CreateIfMissing);
}

int64_t record_run(const fs::path& db, const std::string& trainee, const Scenario& scenario,
                   const json& report, std::optional<double> run_s,
                   std::optional<double> finished_unix_s) {
  check_trainee(trainee);
  SessionRecord r;
  r.trainee = trainee;
  r.drill = std::string(to_string(scenario.drill));
  r.scenario_name =
      scenario.name.empty() ? fs::path(scenario.source).stem().string() : scenario.name;
  const double now = finished_unix_s.value_or(unix_now_s());
  r.started_utc = format_utc(now - run_seconds(report, run_s));
  r.finished_utc = format_utc(now);
  r.recording = to_json(scenario);
  // Settings: the recording less its tracks, names and drill (a column of its own) — eye,
  // methods, seed, dt, duration and whatever the scenario format gains (difficulty), without a
  // list to keep in step.
  r.settings = r.recording;
  for (const char* k : {"hands", "name", "description", "drill"}) r.settings.erase(k);
  if (report.contains("metrics") && report["metrics"].is_object()) r.metrics = report["metrics"];
  if (r.metrics.contains("score") && r.metrics["score"].is_number())
    r.score = r.metrics["score"].get<double>();
  if (report.contains("state_hash") && report["state_hash"].is_string())
    r.state_hash = report["state_hash"].get<std::string>();
  r.report = report.is_object() ? report : json::object();
  make_parent_dir(db);
  RecordStore store(db, OpenMode::CreateIfMissing);
  return store.add_record(r);
}

}  // namespace phaco
