// The station's records in one SQLite file (issue 7; since issue 21 one of two backends).
#include <sqlite3.h>

#include <cmath>
#include <filesystem>
#include <string_view>

#include "engine/core/error.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/records/migrations.hpp"
#include "engine/records/record_backend.hpp"
#include "engine/records/record_rows.hpp"

namespace phaco::records {

namespace {

namespace fs = std::filesystem;

constexpr const char* kRecordColumns =
    "r.id, t.name, r.drill, r.scenario_name, r.started_utc, r.finished_utc, r.settings, "
    "r.metrics, r.score, r.state_hash, r.recording, r.report, r.uuid";

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

[[noreturn]] void fail(const std::string& file, sqlite3* db, int rc, const std::string& doing) {
  std::string msg = file + ": " + doing + ": " + describe(rc);
  const char* detail = db ? sqlite3_errmsg(db) : nullptr;
  if (detail && describe(rc) != detail) msg += std::string(" (") + detail + ")";
  throw InputError(msg);
}

// A prepared statement, finalised on every path out.
class Statement {
 public:
  Statement(sqlite3* db, const std::string& file, const char* sql) : db_(db), file_(file) {
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
  void reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
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
  const std::string& file_;
  sqlite3_stmt* stmt_ = nullptr;
};

void exec(sqlite3* db, const std::string& file, const char* sql, const char* doing) {
  const int rc = sqlite3_exec(db, sql, nullptr, nullptr, nullptr);
  if (rc != SQLITE_OK) fail(file, db, rc, doing);
}

int64_t single_integer(sqlite3* db, const std::string& file, const char* sql, const char* doing) {
  Statement s(db, file, sql);
  return s.step(doing) ? s.integer(0) : 0;
}

SessionRecord read_row(const Statement& s, const std::string& file) {
  RowText t;
  t.id = s.integer(0);
  for (int c = 1; c < kRowColumns; ++c) t.columns[c] = s.text(c);
  if (!s.is_null(8)) t.score = s.real(8);
  return record_from_row(t, file);
}

// Runs `body` in one IMMEDIATE transaction (the write lock taken up front, so it cannot fail
// half-way with BUSY after reading); rolled back on any error.
template <class Body>
auto in_transaction(sqlite3* db, const std::string& file, const char* doing, Body&& body) {
  exec(db, file, "BEGIN IMMEDIATE", doing);
  try {
    auto out = body();
    exec(db, file, "COMMIT", doing);
    return out;
  } catch (...) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    throw;
  }
}

class SqliteRecords final : public RecordBackend {
 public:
  SqliteRecords(const std::string& file, OpenMode mode, int busy_timeout_ms) : file_(file) {
    if (mode == OpenMode::ExistingOnly && !fs::exists(file)) {
      throw InputError(file + ": no records database here (record a run first)");
    }
    int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_NOMUTEX;
    if (mode == OpenMode::CreateIfMissing) flags |= SQLITE_OPEN_CREATE;
    const int rc = sqlite3_open_v2(file.c_str(), &db_, flags, nullptr);
    try {
      if (rc != SQLITE_OK) fail(file_, db_, rc, "cannot open the records database");
      open_checked(busy_timeout_ms);
    } catch (...) {
      sqlite3_close(db_);
      db_ = nullptr;
      throw;
    }
  }
  ~SqliteRecords() override { sqlite3_close(db_); }

  std::vector<int64_t> add_records(std::span<const SessionRecord> records) override {
    return in_transaction(db_, file_, "cannot start writing the record", [&] {
      std::vector<int64_t> ids;
      Statement t(db_, file_, "INSERT OR IGNORE INTO trainees(name, created) VALUES(?, ?)");
      Statement q(db_, file_, "SELECT id FROM trainees WHERE name = ?");
      Statement ins(db_, file_,
                    "INSERT INTO records(trainee_id, drill, scenario_name, started_utc, "
                    "finished_utc, settings, metrics, score, state_hash, recording, report, uuid) "
                    "VALUES(?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT(uuid) DO NOTHING");
      const std::string now = utc_now();
      for (const SessionRecord& r : records) {
        t.reset(), q.reset(), ins.reset();
        t.bind(1, r.trainee);
        t.bind(2, now);
        t.step("cannot store the trainee");
        q.bind(1, r.trainee);
        if (!q.step("cannot read the trainee")) {
          throw InputError(file_ + ": trainee '" + r.trainee + "' vanished while writing");
        }
        const RowText row = row_of(r);
        ins.bind(1, q.integer(0));
        for (int c = 2; c < kRowColumns; ++c) {
          if (c == 8)
            ins.bind(8, r.score);
          else
            ins.bind(c, row.columns[c]);
        }
        ins.step("cannot store the record");
        ids.push_back(sqlite3_changes(db_) > 0 ? sqlite3_last_insert_rowid(db_) : 0);
      }
      return ids;
    });
  }

  std::vector<SessionRecord> records_of(const std::string& trainee) const override {
    Statement s(db_, file_, select("WHERE t.name = ? ORDER BY r.started_utc, r.id").c_str());
    s.bind(1, trainee);
    return rows(s);
  }
  std::optional<SessionRecord> record(int64_t id) const override {
    Statement s(db_, file_, select("WHERE r.id = ?").c_str());
    s.bind(1, id);
    if (!s.step("cannot read the record")) return std::nullopt;
    return read_row(s, file_);
  }
  std::optional<SessionRecord> record_by_uuid(const std::string& uuid) const override {
    Statement s(db_, file_, select("WHERE r.uuid = ?").c_str());
    s.bind(1, uuid);
    if (!s.step("cannot read the record")) return std::nullopt;
    return read_row(s, file_);
  }
  std::vector<SessionRecord> all_records() const override {
    Statement s(db_, file_, select("ORDER BY r.started_utc, r.id").c_str());
    return rows(s);
  }
  std::vector<std::string> trainees() const override {
    Statement s(db_, file_, "SELECT name FROM trainees ORDER BY name");
    std::vector<std::string> out;
    while (s.step("cannot read the trainees")) out.push_back(s.text(0));
    return out;
  }
  int64_t count() const override {
    return single_integer(db_, file_, "SELECT count(*) FROM records", "cannot count the records");
  }
  std::string integrity_check() const override {
    Statement s(db_, file_, "PRAGMA integrity_check");
    return s.step("cannot check integrity") ? s.text(0) : std::string("no answer");
  }
  int schema_version() const override { return version_; }
  bool connected() const override { return true; }

  std::vector<SessionRecord> not_synced_to(const std::string& target) const override {
    Statement s(db_, file_,
                select("WHERE NOT EXISTS (SELECT 1 FROM synced y WHERE y.target = ? AND "
                       "y.uuid = r.uuid) ORDER BY r.started_utc, r.id")
                    .c_str());
    s.bind(1, target);
    return rows(s);
  }
  void mark_synced(const std::string& target, std::span<const std::string> uuids) override {
    in_transaction(db_, file_, "cannot note the upload", [&] {
      Statement s(db_, file_,
                  "INSERT OR IGNORE INTO synced(target, uuid, synced_utc) VALUES(?, ?, ?)");
      const std::string now = utc_now();
      for (const std::string& u : uuids) {
        s.reset();
        s.bind(1, target);
        s.bind(2, u);
        s.bind(3, now);
        s.step("cannot note the upload");
      }
      return 0;
    });
  }

 private:
  static std::string select(const char* rest) {
    return std::string("SELECT ") + kRecordColumns +
           " FROM records r JOIN trainees t ON t.id = r.trainee_id " + rest;
  }
  std::vector<SessionRecord> rows(Statement& s) const {
    std::vector<SessionRecord> out;
    while (s.step("cannot read the records")) out.push_back(read_row(s, file_));
    return out;
  }

  void open_checked(int busy_timeout_ms) {
    // A second writer (two trainers on one file) waits for the other's short transaction instead
    // of failing at once; past this it is reported as locked.
    sqlite3_busy_timeout(db_, busy_timeout_ms);
    sqlite3_extended_result_codes(db_, 1);
    // The first read of the header: a file that is not SQLite fails here with NOTADB.
    const int64_t objects = single_integer(db_, file_, "SELECT count(*) FROM sqlite_master",
                                           "cannot read the records database");
    version_ = static_cast<int>(
        single_integer(db_, file_, "PRAGMA user_version", "cannot read the schema version"));
    check_version(objects);
    {
      // WAL: a reader never blocks the writer, and a crash mid-write leaves the committed state
      // in the main file plus whole frames in the log (see docs/records.md).
      Statement wal(db_, file_, "PRAGMA journal_mode=WAL");
      if (!wal.step("cannot switch to WAL journal mode") || wal.text(0) != "wal") {
        throw InputError(file_ + ": cannot switch to WAL journal mode");
      }
    }
    // FULL: a committed record survives a power cut too, not only a killed process; one fsync
    // per finished drill costs nothing a trainee notices.
    exec(db_, file_, "PRAGMA synchronous=FULL; PRAGMA foreign_keys=ON", "cannot configure");
    upgrade();
  }

  void check_version(int64_t objects) const {
    if (version_ > newest_schema_version()) {
      throw InputError(file_ + ": records schema version " + std::to_string(version_) +
                       " is newer than this phaco understands (" +
                       std::to_string(newest_schema_version()) + "); use a newer phaco");
    }
    if (version_ == 0 && objects > 0) {
      throw InputError(file_ +
                       ": an SQLite database, but not an OpenPhaco records database (it has "
                       "tables and no records schema version)");
    }
  }

  // Each missing migration in its own transaction with its version bump; another process may
  // have applied it between our read and our lock, so the version is read again inside.
  void upgrade() {
    for (const Migration& m : migrations()) {
      if (m.version <= version_) continue;
      version_ = in_transaction(db_, file_, "cannot upgrade the records schema", [&] {
        const int now = static_cast<int>(
            single_integer(db_, file_, "PRAGMA user_version", "cannot read the schema version"));
        if (now < m.version) {
          exec(db_, file_, m.sqlite,
               ("cannot upgrade the records schema to version " + std::to_string(m.version) + " (" +
                m.what + ")")
                   .c_str());
          exec(db_, file_, ("PRAGMA user_version = " + std::to_string(m.version)).c_str(),
               "cannot upgrade the records schema");
          return m.version;
        }
        return now;
      });
    }
  }

  std::string file_;
  sqlite3* db_ = nullptr;
  int version_ = 0;
};

}  // namespace

std::unique_ptr<RecordBackend> open_sqlite(const std::string& file, OpenMode mode,
                                           int busy_timeout_ms) {
  return std::make_unique<SqliteRecords>(file, mode, busy_timeout_ms);
}

}  // namespace phaco::records
