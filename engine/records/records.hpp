#pragma once
// Session records (issue 7 item 4, seed 000 §6.4): every finished drill stored in one SQLite
// file per site, so a trainee's progress can be shown over sessions, exported (XML, JSON) and any
// session replayed. A record keeps the recording that replays it — a scenario (DESIGN.md §7) —
// next to the metrics and state hash it produced, so a replay can be checked against it.
//
// Crash safety: the database runs in WAL mode and each record is written by one transaction
// (BEGIN IMMEDIATE … COMMIT, rolled back on any error). A process killed mid-drill, or even
// mid-write, leaves every committed record intact and readable; only the drill in progress is
// lost. docs/records.md gives the schema, the choices and the XML layout.
//
// Reads and writes: the database file (and its -wal/-shm companions). Not for hot paths: every
// call does file I/O and may throw InputError, whose message names the file and the problem.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/core/utc_time.hpp"

struct sqlite3;

namespace phaco {

// The schema this code writes (PRAGMA user_version). A file with a newer version is refused
// rather than misread; an older one would be migrated here when version 2 exists.
inline constexpr int kRecordsSchemaVersion = 1;

// One finished drill. Times are UTC, ISO 8601 with milliseconds ("2026-11-21T19:18:01.123Z"),
// so text order is date order.
struct SessionRecord {
  int64_t id = 0;  // assigned by the store; ignored by add_record
  std::string trainee;
  std::string drill;          // "corneal_incision", "capsulorhexis", "phaco_sculpting"
  std::string scenario_name;  // the scenario's name, or its file stem
  std::string started_utc, finished_utc;
  nlohmann::json settings = nlohmann::json::object();  // eye level/overrides, methods, seed, dt_s
  nlohmann::json metrics = nlohmann::json::object();   // the report's flat metric map
  std::optional<double> score;                         // 0..100, when the drill scores
  std::string state_hash;
  nlohmann::json recording = nlohmann::json::object();  // the scenario JSON that replays the run
  nlohmann::json report = nlohmann::json::object();     // the whole run report
};

enum class OpenMode : uint8_t {
  CreateIfMissing,  // recording a run: the file (not its directory) is created with the schema
  ExistingOnly,     // history/export: a missing file is an error, not a new empty database
};

class RecordStore {
 public:
  // Opens (or creates) the database and checks it: an SQLite file, not locked past the busy
  // timeout, an OpenPhaco schema no newer than kRecordsSchemaVersion. Throws InputError
  // "FILE: problem". `busy_timeout_ms`: how long a write waits for another process's write.
  explicit RecordStore(const std::filesystem::path& file, OpenMode mode = OpenMode::CreateIfMissing,
                       int busy_timeout_ms = 5000);
  ~RecordStore();
  RecordStore(const RecordStore&) = delete;
  RecordStore& operator=(const RecordStore&) = delete;

  // Stores `record` (its trainee created on first use) in one transaction and returns its id.
  // On any error nothing is stored and InputError names the file and the problem.
  int64_t add_record(const SessionRecord& record);

  // The trainee's records in date order (started_utc, then id); empty for an unknown trainee.
  std::vector<SessionRecord> records_of(const std::string& trainee) const;
  // One record, or nullopt when no record has that id.
  std::optional<SessionRecord> record(int64_t id) const;
  // Every trainee's name, alphabetically.
  std::vector<std::string> trainees() const;
  // PRAGMA integrity_check: "ok" for a sound file, else SQLite's first complaint.
  std::string integrity_check() const;

  const std::filesystem::path& file() const { return file_; }

 private:
  std::filesystem::path file_;
  sqlite3* db_ = nullptr;
};

// The record's time format: engine/core/utc_time.hpp (utc_now, format_utc).

// The unit of a metric named with its unit in the name (issue 7: "left.tool_speed_mm_s.mean" ->
// "mm/s", "incision.entry_angle_deg" -> "deg", "score" -> "points", "regrasps" -> "1").
std::string metric_unit(const std::string& name);

// Seed 000 §6.4's exchange format: one <session> per record in a fixed layout (docs/records.md),
// every metric with its unit, text escaped for XML 1.0.
std::string records_to_xml(const std::vector<SessionRecord>& records);
// The record as one JSON object (every column, the JSON columns as JSON).
nlohmann::json record_to_json(const SessionRecord& record);

}  // namespace phaco
