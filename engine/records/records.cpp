#include "engine/records/records.hpp"

#include <sqlite3.h>

#include <cmath>
#include <cstdio>
#include <ctime>
#include <string_view>

#include "engine/core/error.hpp"
#include "engine/io/json_reader.hpp"

namespace phaco {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Version 1. CHECKs keep a half-built row out even if a caller skips validation; the index serves
// the one frequent query, a trainee's records in date order.
constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE trainees(
  id      INTEGER PRIMARY KEY,
  name    TEXT NOT NULL UNIQUE CHECK(length(name) > 0),
  created TEXT NOT NULL
);
CREATE TABLE records(
  id            INTEGER PRIMARY KEY,
  trainee_id    INTEGER NOT NULL REFERENCES trainees(id),
  drill         TEXT NOT NULL CHECK(length(drill) > 0),
  scenario_name TEXT NOT NULL,
  started_utc   TEXT NOT NULL,
  finished_utc  TEXT NOT NULL CHECK(finished_utc >= started_utc),
  settings      TEXT NOT NULL,
  metrics       TEXT NOT NULL,
  score         REAL CHECK(score IS NULL OR (score >= 0 AND score <= 100)),
  state_hash    TEXT NOT NULL,
  recording     TEXT NOT NULL,
  report        TEXT NOT NULL
);
CREATE INDEX records_by_trainee_date ON records(trainee_id, started_utc, id);
PRAGMA user_version = 1;
)sql";

constexpr const char* kRecordColumns =
    "r.id, t.name, r.drill, r.scenario_name, r.started_utc, r.finished_utc, r.settings, "
    "r.metrics, r.score, r.state_hash, r.recording, r.report";

// What an SQLite result code means to the person who gave us the file.
std::string describe(int rc) {
  switch (rc & 0xff) {
    case SQLITE_NOTADB:
      return "not an SQLite database";
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
      return "the database is locked by another process (try again when it has finished)";
    case SQLITE_CORRUPT:
      return "the database file is corrupt";
    case SQLITE_READONLY:
      return "the database is read-only";
    case SQLITE_CANTOPEN:
      return "cannot open the file";
    case SQLITE_FULL:
      return "the disk is full";
    case SQLITE_CONSTRAINT:
      return "a value breaks the schema's rules";
    default:
      return sqlite3_errstr(rc);
  }
}

[[noreturn]] void fail(const fs::path& file, sqlite3* db, int rc, const std::string& doing) {
  std::string msg = file.string() + ": " + doing + ": " + describe(rc);
  const char* detail = db ? sqlite3_errmsg(db) : nullptr;
  if (detail && describe(rc) != detail) msg += std::string(" (") + detail + ")";
  throw InputError(msg);
}

// A prepared statement, finalised on every path out.
class Statement {
 public:
  Statement(sqlite3* db, const fs::path& file, const char* sql) : db_(db), file_(file) {
    const int rc = sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr);
    if (rc != SQLITE_OK) fail(file, db, rc, "cannot read the records");
  }
  ~Statement() { sqlite3_finalize(stmt_); }
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  void bind(int i, const std::string& text) {
    check(
        sqlite3_bind_text(stmt_, i, text.data(), static_cast<int>(text.size()), SQLITE_TRANSIENT));
  }
  void bind(int i, int64_t v) { check(sqlite3_bind_int64(stmt_, i, v)); }
  void bind(int i, const std::optional<double>& v) {
    check(v ? sqlite3_bind_double(stmt_, i, *v) : sqlite3_bind_null(stmt_, i));
  }
  // True while there is a row; false when done; throws on error.
  bool step(const char* doing) {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail(file_, db_, rc, doing);
  }
  int64_t integer(int col) const { return sqlite3_column_int64(stmt_, col); }
  bool is_null(int col) const { return sqlite3_column_type(stmt_, col) == SQLITE_NULL; }
  double real(int col) const { return sqlite3_column_double(stmt_, col); }
  std::string text(int col) const {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, col));
    return p ? std::string(p, static_cast<size_t>(sqlite3_column_bytes(stmt_, col)))
             : std::string();
  }

 private:
  void check(int rc) {
    if (rc != SQLITE_OK) fail(file_, db_, rc, "cannot bind a value");
  }
  sqlite3* db_;
  const fs::path& file_;
  sqlite3_stmt* stmt_ = nullptr;
};

void exec(sqlite3* db, const fs::path& file, const char* sql, const char* doing) {
  const int rc = sqlite3_exec(db, sql, nullptr, nullptr, nullptr);
  if (rc != SQLITE_OK) fail(file, db, rc, doing);
}

int64_t single_integer(sqlite3* db, const fs::path& file, const char* sql, const char* doing) {
  Statement s(db, file, sql);
  return s.step(doing) ? s.integer(0) : 0;
}

// A JSON column back into a tree; a row edited by hand or damaged names its record and column.
json json_column(const Statement& s, int col, const fs::path& file, int64_t id, const char* name) {
  const std::string source =
      file.string() + ": record " + std::to_string(id) + ", column '" + name + "'";
  json j = io::parse_json_text(s.text(col), source);
  if (!j.is_object()) {
    throw InputError(source + ": expected a JSON object, got " + io::describe_value(j));
  }
  return j;
}

SessionRecord read_row(const Statement& s, const fs::path& file) {
  SessionRecord r;
  r.id = s.integer(0);
  r.trainee = s.text(1);
  r.drill = s.text(2);
  r.scenario_name = s.text(3);
  r.started_utc = s.text(4);
  r.finished_utc = s.text(5);
  r.settings = json_column(s, 6, file, r.id, "settings");
  r.metrics = json_column(s, 7, file, r.id, "metrics");
  if (!s.is_null(8)) r.score = s.real(8);
  r.state_hash = s.text(9);
  r.recording = json_column(s, 10, file, r.id, "recording");
  r.report = json_column(s, 11, file, r.id, "report");
  return r;
}

std::string dump(const json& j) {
  // Replace rather than throw on invalid UTF-8 in a string: a name typed on a terminal in another
  // encoding should not lose a finished drill.
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

}  // namespace

RecordStore::RecordStore(const fs::path& file, OpenMode mode, int busy_timeout_ms) : file_(file) {
  if (mode == OpenMode::ExistingOnly && !fs::exists(file)) {
    throw InputError(file.string() + ": no records database here (record a run first)");
  }
  int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX;
  if (mode == OpenMode::CreateIfMissing) flags |= SQLITE_OPEN_CREATE;
  int rc = sqlite3_open_v2(file.string().c_str(), &db_, flags, nullptr);
  try {
    if (rc != SQLITE_OK) fail(file_, db_, rc, "cannot open the records database");
    // A second writer (two trainers on one file) waits for the other's short transaction instead
    // of failing at once; past this it is reported as locked.
    sqlite3_busy_timeout(db_, busy_timeout_ms);
    sqlite3_extended_result_codes(db_, 1);
    // The first read of the header: a file that is not SQLite fails here with NOTADB.
    const int64_t objects = single_integer(db_, file_, "SELECT count(*) FROM sqlite_master",
                                           "cannot read the records database");
    int64_t version =
        single_integer(db_, file_, "PRAGMA user_version", "cannot read the schema version");
    if (version > kRecordsSchemaVersion) {
      throw InputError(file_.string() + ": records schema version " + std::to_string(version) +
                       " is newer than this phaco understands (" +
                       std::to_string(kRecordsSchemaVersion) + "); use a newer phaco");
    }
    if (version == 0 && objects > 0) {
      throw InputError(file_.string() +
                       ": an SQLite database, but not an OpenPhaco records database (it has "
                       "tables and no records schema version)");
    }
    {
      // WAL: a reader never blocks the writer, and a crash mid-write leaves the committed state
      // in the main file plus whole frames in the log (see docs/records.md).
      Statement wal(db_, file_, "PRAGMA journal_mode=WAL");
      if (!wal.step("cannot switch to WAL journal mode") || wal.text(0) != "wal") {
        throw InputError(file_.string() + ": cannot switch to WAL journal mode");
      }
    }
    // FULL: a committed record survives a power cut too, not only a killed process; one fsync
    // per finished drill costs nothing a trainee notices.
    exec(db_, file_, "PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON", "cannot configure");
    if (version == 0) {
      exec(db_, file_, "BEGIN IMMEDIATE", "cannot create the schema");
      try {
        // Another process may have created it between our check and our lock.
        version =
            single_integer(db_, file_, "PRAGMA user_version", "cannot read the schema version");
        if (version == 0) exec(db_, file_, kSchemaV1, "cannot create the schema");
        exec(db_, file_, "COMMIT", "cannot create the schema");
      } catch (...) {
        sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
        throw;
      }
    }
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

RecordStore::~RecordStore() {
  sqlite3_close(db_);
}

int64_t RecordStore::add_record(const SessionRecord& r) {
  if (r.trainee.empty()) throw InputError(file_.string() + ": a record needs a trainee name");
  if (r.score && !std::isfinite(*r.score)) {
    throw InputError(file_.string() + ": record score is not a finite number");
  }
  // IMMEDIATE takes the write lock up front, so the transaction cannot fail half-way with BUSY
  // after reading; everything below commits together or not at all.
  exec(db_, file_, "BEGIN IMMEDIATE", "cannot start writing the record");
  try {
    {
      Statement t(db_, file_, "INSERT OR IGNORE INTO trainees(name, created) VALUES(?, ?)");
      t.bind(1, r.trainee);
      t.bind(2, utc_now());
      t.step("cannot store the trainee");
    }
    int64_t trainee_id = 0;
    {
      Statement q(db_, file_, "SELECT id FROM trainees WHERE name = ?");
      q.bind(1, r.trainee);
      if (!q.step("cannot read the trainee")) {
        throw InputError(file_.string() + ": trainee '" + r.trainee + "' vanished while writing");
      }
      trainee_id = q.integer(0);
    }
    Statement ins(db_, file_,
                  "INSERT INTO records(trainee_id, drill, scenario_name, started_utc, "
                  "finished_utc, settings, metrics, score, state_hash, recording, report) "
                  "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    ins.bind(1, trainee_id);
    ins.bind(2, r.drill);
    ins.bind(3, r.scenario_name);
    ins.bind(4, r.started_utc);
    ins.bind(5, r.finished_utc);
    ins.bind(6, dump(r.settings));
    ins.bind(7, dump(r.metrics));
    ins.bind(8, r.score);
    ins.bind(9, r.state_hash);
    ins.bind(10, dump(r.recording));
    ins.bind(11, dump(r.report));
    ins.step("cannot store the record");
    const int64_t id = sqlite3_last_insert_rowid(db_);
    exec(db_, file_, "COMMIT", "cannot commit the record");
    return id;
  } catch (...) {
    // Undo the trainee row too: a failed drill leaves no trace.
    sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

std::vector<SessionRecord> RecordStore::records_of(const std::string& trainee) const {
  const std::string sql = std::string("SELECT ") + kRecordColumns +
                          " FROM records r JOIN trainees t ON t.id = r.trainee_id"
                          " WHERE t.name = ? ORDER BY r.started_utc, r.id";
  Statement s(db_, file_, sql.c_str());
  s.bind(1, trainee);
  std::vector<SessionRecord> out;
  while (s.step("cannot read the records")) out.push_back(read_row(s, file_));
  return out;
}

std::optional<SessionRecord> RecordStore::record(int64_t id) const {
  const std::string sql = std::string("SELECT ") + kRecordColumns +
                          " FROM records r JOIN trainees t ON t.id = r.trainee_id WHERE r.id = ?";
  Statement s(db_, file_, sql.c_str());
  s.bind(1, id);
  if (!s.step("cannot read the record")) return std::nullopt;
  return read_row(s, file_);
}

std::vector<std::string> RecordStore::trainees() const {
  Statement s(db_, file_, "SELECT name FROM trainees ORDER BY name");
  std::vector<std::string> out;
  while (s.step("cannot read the trainees")) out.push_back(s.text(0));
  return out;
}

std::string RecordStore::integrity_check() const {
  Statement s(db_, file_, "PRAGMA integrity_check");
  return s.step("cannot check integrity") ? s.text(0) : std::string("no answer");
}


}  // namespace phaco
