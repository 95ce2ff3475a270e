// A training centre's records on a PostgreSQL server (issue 21), through libpq. Same schema as a
// station's SQLite file (migrations.hpp); every value goes as a parameter ($1, $2, …), never into
// the SQL text. The URI (with any password) is given to libpq only; messages show it masked.
//
// Concurrency: many stations write at once. A record's uuid and a trainee's name are unique, and
// both inserts say ON CONFLICT DO NOTHING, so two stations storing the same record or creating the
// same trainee wait for each other and keep one. Two transactions that create trainees in
// opposite orders can deadlock; the server then aborts one, which is retried whole.
#include <libpq-fe.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <initializer_list>
#include <type_traits>

#include "engine/core/error.hpp"
#include "engine/core/utc_time.hpp"
#include "engine/records/migrations.hpp"
#include "engine/records/record_backend.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/record_rows.hpp"

namespace phaco::records {

namespace {

constexpr const char* kRecordColumns =
    "r.id, t.name, r.drill, r.scenario_name, r.started_utc, r.finished_utc, r.settings, "
    "r.metrics, r.score, r.state_hash, r.recording, r.report, r.uuid";

// SQLSTATEs after which the whole transaction may simply be run again.
bool retryable(const std::string& sqlstate) {
  return sqlstate == "40P01" /* deadlock */ || sqlstate == "40001" /* serialization */;
}

class Result {
 public:
  explicit Result(PGresult* r) : r_(r) {}
  ~Result() { PQclear(r_); }
  Result(Result&& o) noexcept : r_(o.r_) { o.r_ = nullptr; }
  Result(const Result&) = delete;
  Result& operator=(const Result&) = delete;
  int rows() const { return PQntuples(r_); }
  bool is_null(int row, int col) const { return PQgetisnull(r_, row, col); }
  std::string text(int row, int col) const {
    return std::string(PQgetvalue(r_, row, col), static_cast<size_t>(PQgetlength(r_, row, col)));
  }
  int64_t integer(int row, int col) const {
    const char* p = PQgetvalue(r_, row, col);
    int64_t v = 0;
    std::from_chars(p, p + std::strlen(p), v);
    return v;
  }
  double real(int row, int col) const { return std::strtod(PQgetvalue(r_, row, col), nullptr); }
  PGresult* raw() const { return r_; }

 private:
  PGresult* r_;
};

// An error from the server, with its SQLSTATE so a deadlock can be retried.
struct ServerError : InputError {
  ServerError(const std::string& what, std::string state)
      : InputError(what), sqlstate(std::move(state)) {}
  std::string sqlstate;
};

std::string trimmed(const char* text) {
  std::string s = text ? text : "";
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

std::string number_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

class PostgresRecords final : public RecordBackend {
 public:
  PostgresRecords(const std::string& uri, int connect_timeout_s) : shown_(shown_location(uri)) {
    // connect_timeout first: the URI's own value, if it has one, overrides it (expand_dbname).
    const std::string timeout = std::to_string(connect_timeout_s);
    const char* keys[] = {"connect_timeout", "application_name", "dbname", nullptr};
    const char* values[] = {timeout.c_str(), "openphaco", uri.c_str(), nullptr};
    conn_ = PQconnectdbParams(keys, values, 1);
    if (!conn_) throw InputError(shown_ + ": cannot connect: out of memory");
    if (PQstatus(conn_) != CONNECTION_OK) {
      const std::string why = trimmed(PQerrorMessage(conn_));
      PQfinish(conn_);
      conn_ = nullptr;
      throw InputError(shown_ + ": cannot connect to the records server: " + why);
    }
    try {
      // Warnings (NOTICEs) would go to stderr by default; they carry nothing a trainee needs.
      PQsetNoticeProcessor(
          conn_, [](void*, const char*) {}, nullptr);
      exec("SET client_encoding = 'UTF8'", {}, "cannot configure the connection");
      upgrade();
    } catch (...) {
      PQfinish(conn_);
      conn_ = nullptr;
      throw;
    }
  }
  ~PostgresRecords() override { PQfinish(conn_); }

  std::vector<int64_t> add_records(std::span<const SessionRecord> records) override {
    return in_transaction("cannot store the records", [&] {
      std::vector<int64_t> ids;
      const std::string now = utc_now();
      for (const SessionRecord& r : records) {
        exec("INSERT INTO trainees(name, created) VALUES($1, $2) ON CONFLICT (name) DO NOTHING",
             {r.trainee, now}, "cannot store the trainee");
        const Result t =
            exec("SELECT id FROM trainees WHERE name = $1", {r.trainee}, "cannot read the trainee");
        if (t.rows() != 1) throw InputError(shown_ + ": trainee '" + r.trainee + "' vanished");
        const RowText row = row_of(r);
        const std::optional<std::string> score =
            r.score ? std::optional<std::string>(number_text(*r.score)) : std::nullopt;
        const Result ins = exec(
            "INSERT INTO records(trainee_id, drill, scenario_name, started_utc, finished_utc, "
            "settings, metrics, score, state_hash, recording, report, uuid) "
            "VALUES($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11, $12) "
            "ON CONFLICT (uuid) DO NOTHING RETURNING id",
            {t.text(0, 0), row.columns[2], row.columns[3], row.columns[4], row.columns[5],
             row.columns[6], row.columns[7], score, row.columns[9], row.columns[10],
             row.columns[11], row.columns[12]},
            "cannot store the record");
        ids.push_back(ins.rows() == 1 ? ins.integer(0, 0) : 0);
      }
      return ids;
    });
  }

  std::vector<SessionRecord> records_of(const std::string& trainee) const override {
    return rows(exec(select("WHERE t.name = $1 ORDER BY r.started_utc, r.id"), {trainee},
                     "cannot read the records"));
  }
  std::optional<SessionRecord> record(int64_t id) const override {
    return first(exec(select("WHERE r.id = $1"), {std::to_string(id)}, "cannot read the record"));
  }
  std::optional<SessionRecord> record_by_uuid(const std::string& uuid) const override {
    return first(exec(select("WHERE r.uuid = $1"), {uuid}, "cannot read the record"));
  }
  std::vector<SessionRecord> all_records() const override {
    return rows(exec(select("ORDER BY r.started_utc, r.id"), {}, "cannot read the records"));
  }
  std::vector<std::string> trainees() const override {
    const Result r =
        exec("SELECT name FROM trainees ORDER BY name COLLATE \"C\"", {}, "cannot read trainees");
    std::vector<std::string> out;
    for (int i = 0; i < r.rows(); ++i) out.push_back(r.text(i, 0));
    return out;
  }
  int64_t count() const override {
    return exec("SELECT count(*) FROM records", {}, "cannot count the records").integer(0, 0);
  }
  std::string integrity_check() const override {
    const Result r = exec(
        "SELECT count(*) FROM records r LEFT JOIN trainees t ON t.id = r.trainee_id "
        "WHERE t.id IS NULL OR r.uuid IS NULL",
        {}, "cannot check integrity");
    const int64_t bad = r.integer(0, 0);
    return bad == 0 ? "ok" : std::to_string(bad) + " record(s) without a trainee or a uuid";
  }
  int schema_version() const override { return version_; }
  bool connected() const override { return PQstatus(conn_) == CONNECTION_OK; }

  std::vector<SessionRecord> not_synced_to(const std::string&) const override {
    throw InputError(shown_ + ": a server is what a station syncs to, not from");
  }
  void mark_synced(const std::string&, std::span<const std::string>) override {
    throw InputError(shown_ + ": a server keeps no sync notes");
  }

 private:
  using Param = std::optional<std::string>;

  Result exec(const std::string& sql, std::initializer_list<Param> params,
              const char* doing) const {
    std::vector<const char*> values;
    std::vector<int> lengths;
    for (const Param& p : params) {
      values.push_back(p ? p->c_str() : nullptr);
      lengths.push_back(p ? static_cast<int>(p->size()) : 0);
    }
    Result r(PQexecParams(conn_, sql.c_str(), static_cast<int>(values.size()), nullptr,
                          values.data(), lengths.data(), nullptr, 0));
    const ExecStatusType st = PQresultStatus(r.raw());
    if (st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK) return r;
    const char* state = PQresultErrorField(r.raw(), PG_DIAG_SQLSTATE);
    std::string why = trimmed(PQresultErrorField(r.raw(), PG_DIAG_MESSAGE_PRIMARY));
    if (why.empty()) why = trimmed(PQerrorMessage(conn_));
    if (PQstatus(conn_) != CONNECTION_OK) why = "lost the connection to the server (" + why + ")";
    throw ServerError(shown_ + ": " + doing + ": " + why, state ? state : "");
  }

  // Runs `body` in one transaction; rolled back on any error, and run again (up to 5 times) when
  // the server aborted it for a deadlock with another station.
  template <class Body>
  std::invoke_result_t<Body&> in_transaction(const char* doing, Body&& body) const {
    for (int attempt = 1;; ++attempt) {
      try {
        exec("BEGIN", {}, doing);
        auto out = body();
        exec("COMMIT", {}, doing);
        return out;
      } catch (const ServerError& e) {
        rollback();
        if (!retryable(e.sqlstate) || attempt == 5) throw;
      } catch (...) {
        rollback();
        throw;
      }
    }
  }
  void rollback() const {
    if (PQstatus(conn_) == CONNECTION_OK) PQclear(PQexec(conn_, "ROLLBACK"));
  }

  static std::string select(const char* rest) {
    return std::string("SELECT ") + kRecordColumns +
           " FROM records r JOIN trainees t ON t.id = r.trainee_id " + rest;
  }
  SessionRecord read_row(const Result& r, int i) const {
    RowText t;
    t.id = r.integer(i, 0);
    for (int c = 1; c < kRowColumns; ++c) t.columns[c] = r.text(i, c);
    if (!r.is_null(i, 8)) t.score = r.real(i, 8);
    return record_from_row(t, shown_);
  }
  std::vector<SessionRecord> rows(const Result& r) const {
    std::vector<SessionRecord> out;
    for (int i = 0; i < r.rows(); ++i) out.push_back(read_row(r, i));
    return out;
  }
  std::optional<SessionRecord> first(const Result& r) const {
    if (r.rows() == 0) return std::nullopt;
    return read_row(r, 0);
  }

  // How many of `names` (comma-separated) are tables of the current schema. A query over the
  // catalog, not to_regclass(): that name lookup may answer from a cache not yet told of another
  // session's commit (seen: after waiting for the schema lock, it missed phaco_schema).
  int64_t tables_named(const char* names) const {
    return exec(
               "SELECT count(*) FROM information_schema.tables WHERE table_schema = "
               "current_schema() AND table_name = ANY(string_to_array($1, ','))",
               {std::string(names)}, "cannot read the schema")
        .integer(0, 0);
  }

  // The version, or 0 when the database has no phaco_schema table yet.
  int stored_version() const {
    if (tables_named("phaco_schema") == 0) return 0;
    const Result v = exec("SELECT version FROM phaco_schema", {}, "cannot read the version");
    return v.rows() == 1 ? static_cast<int>(v.integer(0, 0)) : 0;
  }

  void refuse_newer(int version) const {
    if (version > newest_schema_version()) {
      throw InputError(shown_ + ": records schema version " + std::to_string(version) +
                       " is newer than this phaco understands (" +
                       std::to_string(newest_schema_version()) + "); use a newer phaco");
    }
  }

  // Each missing migration in one transaction with its version bump, under an advisory lock so
  // that stations meeting a fresh or old centre database at the same moment apply it once. What
  // is there is judged only under the lock: outside it, another station's schema may appear
  // between two reads (its tables, then its version), which would look like a foreign database.
  void upgrade() {
    version_ = stored_version();
    refuse_newer(version_);
    if (version_ == newest_schema_version()) return;
    in_transaction("cannot upgrade the records schema", [&] {
      exec("SELECT pg_advisory_xact_lock($1)", {std::to_string(kPostgresSchemaLock)},
           "cannot lock the schema");
      int now = stored_version();
      refuse_newer(now);
      if (now == 0) {
        if (tables_named("trainees,records") > 0 && tables_named("phaco_schema") == 0) {
          throw InputError(shown_ +
                           ": this database has tables named trainees or records but no "
                           "OpenPhaco records schema version (phaco_schema); use a database of "
                           "its own");
        }
        exec("CREATE TABLE IF NOT EXISTS phaco_schema(version INTEGER NOT NULL)", {},
             "cannot create the schema");
        if (exec("SELECT count(*) FROM phaco_schema", {}, "cannot read").integer(0, 0) == 0)
          exec("INSERT INTO phaco_schema(version) VALUES(0)", {}, "cannot create the schema");
      }
      for (const Migration& m : migrations()) {
        if (m.version <= now) continue;
        Result r(PQexec(conn_, m.postgres));  // several statements, no parameters
        if (PQresultStatus(r.raw()) != PGRES_COMMAND_OK) {
          const char* state = PQresultErrorField(r.raw(), PG_DIAG_SQLSTATE);
          throw ServerError(shown_ + ": cannot upgrade the records schema to version " +
                                std::to_string(m.version) + " (" + m.what +
                                "): " + trimmed(PQresultErrorMessage(r.raw())),
                            state ? state : "");
        }
        exec("UPDATE phaco_schema SET version = $1", {std::to_string(m.version)},
             "cannot upgrade the records schema");
        now = m.version;
      }
      version_ = now;
      return 0;
    });
  }

  std::string shown_;
  PGconn* conn_ = nullptr;
  int version_ = 0;
};

}  // namespace

std::unique_ptr<RecordBackend> open_postgres(const std::string& uri, int connect_timeout_s) {
  return std::make_unique<PostgresRecords>(uri, connect_timeout_s);
}

}  // namespace phaco::records
