#pragma once
// Session records (issue 7 item 4, seed 000 §6.4; issue 21): every finished drill stored in a
// station's SQLite file or a training centre's PostgreSQL database (record_location.hpp), so a
// trainee's progress can be shown over sessions, exported (XML, JSON) and any session replayed. A
// record keeps the recording that replays it — a scenario (DESIGN.md §7) — next to the metrics and
// state hash it produced, so a replay can be checked against it.
//
// Crash safety (SQLite): the database runs in WAL mode and each record is written by one
// transaction (BEGIN IMMEDIATE … COMMIT, rolled back on any error). A process killed mid-drill, or
// even mid-write, leaves every committed record intact and readable; only the drill in progress is
// lost. docs/records.md gives the schema, the choices and the XML layout.
//
// Identity: each record carries a UUID made where it was recorded. A station uploads its records
// to a centre keyed by it (sync.hpp), so an upload repeated or interrupted never duplicates one.
//
// Reads and writes: the database file (and its -wal/-shm companions) or the server. Not for hot
// paths: every call does I/O and may throw InputError, whose message names the database (a URI
// with its password masked) and the problem. Not thread-safe: one RecordStore per thread.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "engine/core/utc_time.hpp"

namespace phaco {

namespace records {
class RecordBackend;
}

// The schema this code writes (migrations.hpp). A database with a newer version is refused
// rather than misread; an older one is upgraded when opened (history and export too).
inline constexpr int kRecordsSchemaVersion = 2;

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
  std::string
      uuid;  // the record's identity everywhere (RFC 4122 v4); add_record makes one if empty
  nlohmann::json recording = nlohmann::json::object();  // the scenario JSON that replays the run
  nlohmann::json report = nlohmann::json::object();     // the whole run report
};

enum class OpenMode : uint8_t {
  CreateIfMissing,  // recording a run: the file (not its directory) is created with the schema
  ExistingOnly,     // history/export: a missing file is an error, not a new empty database
};
// (A PostgreSQL database must exist on the server either way; its schema is created in it.)

// How long a connection to a server may take before it is reported as unreachable, s.
inline constexpr int kConnectTimeoutS = 10;

class RecordStore {
 public:
  // Opens (or creates) the database and checks it: an SQLite file (not locked past the busy
  // timeout) or a PostgreSQL URI (reached within kConnectTimeoutS), with an OpenPhaco schema no
  // newer than kRecordsSchemaVersion; an older schema is upgraded. Throws InputError
  // "DATABASE: problem". `busy_timeout_ms`: how long an SQLite write waits for another's.
  explicit RecordStore(const std::filesystem::path& location,
                       OpenMode mode = OpenMode::CreateIfMissing, int busy_timeout_ms = 5000);
  ~RecordStore();
  RecordStore(const RecordStore&) = delete;
  RecordStore& operator=(const RecordStore&) = delete;

  // Stores `record` (its trainee created on first use) in one transaction and returns its id; a
  // record without a uuid gets a new one. On any error nothing is stored and InputError names the
  // database and the problem. A uuid already stored is refused as a duplicate.
  int64_t add_record(const SessionRecord& record);
  // Stores those of `records` whose uuid is not stored yet, in one transaction (all or nothing);
  // returns how many were new. What a sync sends to a centre; each record must have its uuid.
  size_t add_missing(std::span<const SessionRecord> records);

  // The trainee's records in date order (started_utc, then id); empty for an unknown trainee.
  std::vector<SessionRecord> records_of(const std::string& trainee) const;
  // One record, or nullopt when no record has that id.
  std::optional<SessionRecord> record(int64_t id) const;
  std::optional<SessionRecord> record_by_uuid(const std::string& uuid) const;
  // Every record, in date order (started_utc, then id).
  std::vector<SessionRecord> all_records() const;
  // Every trainee's name, alphabetically.
  std::vector<std::string> trainees() const;
  int64_t count() const;
  // SQLite: PRAGMA integrity_check, "ok" for a sound file, else SQLite's first complaint.
  // PostgreSQL: "ok" when every record has its trainee and a uuid (the server keeps its own pages).
  std::string integrity_check() const;
  int schema_version() const;

  // A station's sync notes (SQLite only): its records that `target` (a shown_location) has not
  // acknowledged, in date order; and the acknowledgement of those uuids.
  std::vector<SessionRecord> not_synced_to(const std::string& target) const;
  void mark_synced(const std::string& target, std::span<const std::string> uuids);

  // The database as it may be printed (a URI's password masked).
  const std::string& location() const { return shown_; }
  bool is_server() const { return server_; }
  // False once a server's connection is lost (a file is always "connected").
  bool connected() const;

 private:
  std::string shown_;
  bool server_ = false;
  std::unique_ptr<records::RecordBackend> backend_;
};

// A new random (version 4) UUID, lower-case text.
std::string new_record_uuid();

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
