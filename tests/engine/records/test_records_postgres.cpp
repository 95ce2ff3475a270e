// Records on a real PostgreSQL server (issue 21): the throwaway cluster scripts/test.sh starts
// (scripts/pg_test_cluster.sh; PHACO_TEST_PG_URI, _DIR, _CTL). Nothing is mocked. Each test makes
// its own database on that server and drops it at the end. The fault tests stop and restart the
// server, so ctest runs this file's tests one at a time (RESOURCE_LOCK postgres).
#include <gtest/gtest.h>
#include <libpq-fe.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/error.hpp"
#include "engine/records/background_sync.hpp"
#include "engine/records/migrations.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/records.hpp"
#include "engine/records/sync.hpp"
#include "tests/engine/records/sample_record.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/expect_invalid.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using phaco::InputError;
using phaco::OpenMode;
using phaco::RecordStore;
using phaco::SessionRecord;
using phaco::test::input_error_of;

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

// The cluster's admin URI ends "/postgres?host=…&port=…"; a test database replaces "postgres".
std::string uri_of_database(const std::string& admin, const std::string& db) {
  const size_t slash = admin.find("/postgres?");
  return admin.substr(0, slash) + "/" + db + admin.substr(slash + 9);
}

// Raw SQL as the server's administrator (another program), for setting up what a test needs.
void admin_sql(const std::string& uri, const std::string& sql) {
  PGconn* c = PQconnectdb(uri.c_str());
  ASSERT_EQ(PQstatus(c), CONNECTION_OK) << PQerrorMessage(c);
  PGresult* r = PQexec(c, sql.c_str());
  const ExecStatusType st = PQresultStatus(r);
  const std::string err = PQresultErrorMessage(r);
  PQclear(r);
  PQfinish(c);
  ASSERT_TRUE(st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK) << sql << ": " << err;
}

int64_t admin_count(const std::string& uri, const std::string& sql) {
  PGconn* c = PQconnectdb(uri.c_str());
  PGresult* r = PQexec(c, sql.c_str());
  const int64_t n = PQresultStatus(r) == PGRES_TUPLES_OK ? std::atoll(PQgetvalue(r, 0, 0)) : -1;
  PQclear(r);
  PQfinish(c);
  return n;
}

void server(const std::string& what) {
  const std::string cmd =
      env("PHACO_TEST_PG_CTL") + " " + what + " " + env("PHACO_TEST_PG_DIR") + " >/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

SessionRecord sample(const std::string& trainee, const std::string& started, double score) {
  return phaco::test::sample_record(trainee, started, score);
}

std::string stamp(int i) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "2026-11-%02dT%02d:%02d:00.000Z", 1 + i / 1440 % 28, i / 60 % 24,
                i % 60);
  return buf;
}

// Stations as processes: forks one child per index, each running `station(i)` (true: it did its
// job) and leaving by _exit (an exception is printed and counts as a failure). Returns the
// children, for wait_stations.
std::vector<pid_t> start_stations(int n, const std::function<bool(int)>& station) {
  std::vector<pid_t> children;
  for (int i = 0; i < n; ++i) {
    const pid_t child = fork();
    if (child == 0) {
      int code = 4;
      try {
        code = station(i) ? 0 : 4;
      } catch (const std::exception& e) {
        std::fprintf(stderr, "station %d: %s\n", i, e.what());
        code = 5;
      }
      _exit(code);
    }
    children.push_back(child);
  }
  return children;
}

// How many of them failed (a fork that failed, a non-zero exit or a signal).
int wait_stations(const std::vector<pid_t>& children) {
  int failures = 0;
  for (const pid_t c : children) {
    int status = 0;
    failures +=
        c < 0 || waitpid(c, &status, 0) != c || !WIFEXITED(status) || WEXITSTATUS(status) != 0;
  }
  return failures;
}

class PostgresRecords : public ::testing::Test {
 protected:
  void SetUp() override {
    admin_ = env("PHACO_TEST_PG_URI");
    PHACO_REQUIRE_ENVIRONMENT(!admin_.empty() && !env("PHACO_TEST_PG_CTL").empty(),
                              "no PostgreSQL test cluster (scripts/test.sh starts one)");
    db_ = "phaco_t" + std::to_string(::getpid()) + "_" + std::to_string(counter_++);
    admin_sql(admin_, "CREATE DATABASE " + db_);
    uri_ = uri_of_database(admin_, db_);
    dir_ = fs::temp_directory_path() / ("phaco-pgtest-" + db_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (db_.empty()) return;
    server("start");  // a fault test may have left it stopped
    admin_sql(admin_, "DROP DATABASE IF EXISTS " + db_ + " WITH (FORCE)");
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  // A station's SQLite file with n records of `trainee`.
  fs::path station(const std::string& name, int n, const std::string& trainee = "ana") {
    const fs::path file = dir_ / (name + ".sqlite");
    std::vector<SessionRecord> records;
    for (int i = 0; i < n; ++i) {
      records.push_back(sample(trainee, stamp(i), i % 101));
      records.back().uuid = phaco::new_record_uuid();
    }
    RecordStore(file).add_missing(records);  // one transaction: one fsync, not n
    return file;
  }
  int64_t centre_count() { return admin_count(uri_, "SELECT count(*) FROM records"); }
  int64_t centre_distinct() {
    return admin_count(uri_, "SELECT count(DISTINCT uuid) FROM records");
  }

  static inline int counter_ = 0;
  std::string admin_, db_, uri_;
  fs::path dir_;
};

TEST_F(PostgresRecords, RoundTripKeepsEveryFieldAndAnyText) {
  SessionRecord in =
      sample("O'Brien \"Bob\"; DROP TABLE records; --", "2026-11-21T10:00:00.000Z", 81.5);
  in.finished_utc = "2026-11-21T10:00:42.125Z";
  in.scenario_name = std::string(10 * 1024, 'x') + " Zoë 张伟 🙂 \\ ' \"";
  in.metrics["note"] = "Robert'); DROP TABLE trainees;-- ∑";
  int64_t id = 0;
  {
    RecordStore store(uri_);
    id = store.add_record(in);
    EXPECT_GT(id, 0);
  }
  const RecordStore store(uri_, OpenMode::ExistingOnly);
  const auto out = store.record(id);
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->trainee, in.trainee);
  EXPECT_EQ(out->drill, in.drill);
  EXPECT_EQ(out->scenario_name, in.scenario_name);
  EXPECT_EQ(out->started_utc, in.started_utc);
  EXPECT_EQ(out->finished_utc, in.finished_utc);
  EXPECT_EQ(out->settings, in.settings);  // 1/120 exact through the text
  EXPECT_EQ(out->metrics, in.metrics);
  ASSERT_TRUE(out->score.has_value());
  EXPECT_EQ(*out->score, 81.5);
  EXPECT_EQ(out->state_hash, in.state_hash);
  EXPECT_EQ(out->recording, in.recording);
  EXPECT_EQ(out->report, in.report);
  EXPECT_EQ(out->uuid.size(), 36u);
  EXPECT_EQ(store.trainees(), std::vector<std::string>{in.trainee});
  EXPECT_EQ(store.records_of(in.trainee).size(), 1u);
  EXPECT_EQ(store.integrity_check(), "ok");
  EXPECT_EQ(admin_count(uri_, "SELECT count(*) FROM pg_tables WHERE tablename = 'records'"), 1);

  SessionRecord unscored = sample("Zoë", "2026-11-22T10:00:00.000Z", 0);
  unscored.score.reset();
  RecordStore writer(uri_);
  const auto back = writer.record(writer.add_record(unscored));
  ASSERT_TRUE(back.has_value());
  EXPECT_FALSE(back->score.has_value());
  EXPECT_EQ(writer.schema_version(), phaco::kRecordsSchemaVersion);
}

TEST_F(PostgresRecords, DateOrderIsRecordedTimeOrder) {
  RecordStore store(uri_);
  store.add_record(sample("ana", "2026-11-21T09:00:00.000Z", 3));
  store.add_record(sample("ana", "2026-01-05T09:00:00.000Z", 1));
  store.add_record(sample("ana", "2026-11-21T08:59:59.999Z", 2));
  std::vector<double> scores;
  for (const auto& r : store.records_of("ana")) scores.push_back(*r.score);
  EXPECT_EQ(scores, (std::vector<double>{1, 2, 3}));
}

TEST_F(PostgresRecords, SchemaRulesHoldOnTheServerAndAFailedWriteLeavesNothing) {
  RecordStore store(uri_);
  store.add_record(sample("ana", "2026-11-21T09:00:00.000Z", 50));
  const std::string msg =
      input_error_of([&] { store.add_record(sample("carla", "2026-11-21T10:00:00.000Z", 150)); });
  EXPECT_NE(msg.find("cannot store the record"), std::string::npos) << msg;
  EXPECT_EQ(store.trainees(), std::vector<std::string>{"ana"});  // carla rolled back with it
  SessionRecord twice = sample("ana", "2026-11-21T11:00:00.000Z", 50);
  twice.uuid = phaco::new_record_uuid();
  store.add_record(twice);
  EXPECT_NE(input_error_of([&] { store.add_record(twice); }).find("already stored"),
            std::string::npos);
  EXPECT_EQ(store.count(), 2);
}

TEST_F(PostgresRecords, AVersionOneDatabaseIsUpgradedAndANewerOneRefused) {
  // What an older phaco made: version 1's tables and one record, without a uuid column.
  admin_sql(uri_, phaco::records::migrations()[0].postgres);
  admin_sql(uri_,
            "CREATE TABLE phaco_schema(version INTEGER NOT NULL); INSERT INTO phaco_schema "
            "VALUES(1); INSERT INTO trainees(name, created) VALUES('ana', 'x'); INSERT INTO "
            "records(trainee_id, drill, scenario_name, started_utc, finished_utc, settings, "
            "metrics, score, state_hash, recording, report) SELECT id, 'capsulorhexis', 's', "
            "'2026-01-01T00:00:00.000Z', '2026-01-01T00:00:01.000Z', '{}', '{\"score\": 7}', 7, "
            "'h', '{}', '{}' FROM trainees");
  {
    RecordStore store(uri_);
    EXPECT_EQ(store.schema_version(), 2);
    const auto old = store.records_of("ana");
    ASSERT_EQ(old.size(), 1u);
    EXPECT_EQ(*old[0].score, 7);
    EXPECT_EQ(old[0].uuid.size(), 36u);  // given one by the upgrade
  }
  EXPECT_EQ(admin_count(uri_, "SELECT version FROM phaco_schema"), 2);
  admin_sql(uri_, "UPDATE phaco_schema SET version = 9");
  const std::string msg = input_error_of([&] { RecordStore store(uri_); });
  EXPECT_NE(msg.find("schema version 9 is newer"), std::string::npos) << msg;
}

// Stations meeting a fresh centre database at the same moment: one creates the schema, the others
// wait for it and find it whole. (Found by phaco-perf records: a name lookup that missed the
// other station's commit took its tables for a foreign database's, or made them twice.)
TEST_F(PostgresRecords, StationsOpeningAFreshDatabaseAtOnceCreateItsSchemaOnce) {
  // Made deterministic: this test is the first station, half-way through creating the schema
  // (its tables made, not committed, the schema lock held) while eight others open the database
  // and wait for the lock. Once it commits they must find the schema whole.
  PGconn* first = PQconnectdb(uri_.c_str());
  ASSERT_EQ(PQstatus(first), CONNECTION_OK);
  std::string sql = "BEGIN; SELECT pg_advisory_xact_lock(" +
                    std::to_string(phaco::records::kPostgresSchemaLock) +
                    "); CREATE TABLE phaco_schema(version INTEGER NOT NULL); ";
  for (const auto& m : phaco::records::migrations()) sql += m.postgres;
  sql += "INSERT INTO phaco_schema VALUES(" + std::to_string(phaco::kRecordsSchemaVersion) + ");";
  PGresult* r = PQexec(first, sql.c_str());
  ASSERT_EQ(PQresultStatus(r), PGRES_COMMAND_OK) << PQerrorMessage(first);
  PQclear(r);

  constexpr int kStations = 8;
  const std::vector<pid_t> children = start_stations(kStations, [&](int) {
    return RecordStore(uri_).schema_version() == phaco::kRecordsSchemaVersion;
  });
  // Let the stations connect, look and queue for the lock (a wait for the others to get there,
  // not a measurement; 60 s only guards against a hang), then commit.
  for (int i = 0; i < 2400 && admin_count(admin_,
                                          "SELECT count(*) FROM pg_locks WHERE locktype = "
                                          "'advisory' AND NOT granted") < kStations;
       ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  EXPECT_EQ(admin_count(admin_,
                        "SELECT count(*) FROM pg_locks WHERE locktype = 'advisory' AND "
                        "NOT granted"),
            kStations);
  r = PQexec(first, "COMMIT");
  ASSERT_EQ(PQresultStatus(r), PGRES_COMMAND_OK) << PQerrorMessage(first);
  PQclear(r);
  PQfinish(first);
  const int failures = wait_stations(children);
  EXPECT_EQ(failures, 0);
  EXPECT_EQ(admin_count(uri_, "SELECT count(*) FROM phaco_schema"), 1);
  EXPECT_EQ(admin_count(uri_, "SELECT version FROM phaco_schema"), phaco::kRecordsSchemaVersion);
}

TEST_F(PostgresRecords, ForeignTablesOfTheSameNameAreRefused) {
  admin_sql(uri_, "CREATE TABLE records(x INTEGER)");
  const std::string msg = input_error_of([&] { RecordStore store(uri_); });
  EXPECT_NE(msg.find("no OpenPhaco records schema"), std::string::npos) << msg;
}

TEST_F(PostgresRecords, AWrongPasswordIsAClearErrorThatNeverShowsAPassword) {
  const std::string secret = "hunter2-not-the-password";
  std::string bad = uri_;
  bad.replace(bad.find(':', 13) + 1, bad.find('@') - bad.find(':', 13) - 1, secret);
  const std::string msg = input_error_of([&] { RecordStore store(bad); });
  EXPECT_NE(msg.find("password authentication failed"), std::string::npos) << msg;
  EXPECT_EQ(msg.find(secret), std::string::npos) << msg;
  EXPECT_NE(msg.find("***"), std::string::npos) << msg;
  // The right password never shows either, in a message after connecting.
  const std::string right =
      uri_.substr(uri_.find(':', 13) + 1, uri_.find('@') - uri_.find(':', 13) - 1);
  RecordStore store(uri_);
  EXPECT_EQ(store.location().find(right), std::string::npos) << store.location();
  store.add_record(sample("ana", "2026-11-21T09:00:00.000Z", 1));
  admin_sql(uri_, "UPDATE records SET metrics = '{broken'");
  const std::string after = input_error_of([&] { store.records_of("ana"); });
  EXPECT_NE(after.find("column 'metrics'"), std::string::npos) << after;
  EXPECT_EQ(after.find(right), std::string::npos) << after;
  // A password as a query parameter is masked too.
  EXPECT_EQ(phaco::shown_location("postgresql://u@h/d?password=abc&sslmode=disable"),
            "postgresql://u@h/d?password=***&sslmode=disable");
}

TEST_F(PostgresRecords, APasswordFromPgpassfileConnects) {
  const size_t colon = uri_.find(':', 13), at = uri_.find('@');
  const std::string password = uri_.substr(colon + 1, at - colon - 1);
  const std::string bare = uri_.substr(0, colon) + uri_.substr(at);  // no password in the URI
  const fs::path pass = dir_ / "pgpass";
  {
    std::ofstream out(pass);
    out << env("PHACO_TEST_PG_DIR") << ":*:" << db_ << ":phaco:" << password << "\n";
  }
  fs::permissions(pass, fs::perms::owner_read | fs::perms::owner_write);
  ::setenv("PGPASSFILE", pass.c_str(), 1);
  std::string msg;
  try {
    RecordStore store(bare);
    EXPECT_EQ(store.count(), 0);
  } catch (const InputError& e) {
    msg = e.what();
  }
  ::unsetenv("PGPASSFILE");
  EXPECT_EQ(msg, "");
}

TEST_F(PostgresRecords, SyncUploadsEachRecordOnceHoweverOftenItRuns) {
  const fs::path file = station("s1", 120);
  RecordStore st(file);
  RecordStore centre(uri_);
  phaco::SyncOptions o;
  o.batch = 25;
  const auto first = phaco::sync_records(st, centre, o);
  EXPECT_EQ(first.pending, 120u);
  EXPECT_EQ(first.uploaded, 120u);
  EXPECT_EQ(first.already_there, 0u);
  const auto again = phaco::sync_records(st, centre, o);
  EXPECT_EQ(again.pending, 0u);
  o.resend_all = true;
  const auto all = phaco::sync_records(st, centre, o);
  EXPECT_EQ(all.pending, 120u);
  EXPECT_EQ(all.already_there, 120u);
  EXPECT_EQ(centre_count(), 120);
  // Every record arrived whole: the centre's copy equals the station's.
  for (const SessionRecord& r : st.all_records()) {
    const auto c = centre.record_by_uuid(r.uuid);
    ASSERT_TRUE(c.has_value());
    EXPECT_EQ(c->metrics, r.metrics);
    EXPECT_EQ(c->started_utc, r.started_utc);
    EXPECT_EQ(c->trainee, r.trainee);
  }
  // A new record after a sync is the only one sent next time.
  st.add_record(sample("ana", "2026-12-01T00:00:00.000Z", 99));
  o.resend_all = false;
  EXPECT_EQ(phaco::sync_records(st, centre, o).uploaded, 1u);
  EXPECT_EQ(centre_count(), 121);
}

TEST_F(PostgresRecords, ACentreThatCommittedWhatTheStationNeverNotedKeepsItOnce) {
  // The station was killed after the centre's COMMIT and before its own note: the next sync
  // sends those records again.
  const fs::path file = station("s1", 40);
  RecordStore st(file);
  RecordStore centre(uri_);
  const auto records = st.all_records();
  EXPECT_EQ(centre.add_missing({records.data(), 15}), 15u);
  const auto r = phaco::sync_records(st, centre);
  EXPECT_EQ(r.pending, 40u);
  EXPECT_EQ(r.already_there, 15u);
  EXPECT_EQ(r.uploaded, 25u);
  EXPECT_EQ(centre_count(), 40);
}

TEST_F(PostgresRecords, TwoSyncsAtOnceStoreEachRecordOnce) {
  const fs::path file = station("s1", 300);
  std::atomic<int> errors{0};
  auto run = [&] {
    try {
      RecordStore st(file);
      RecordStore centre(uri_);
      phaco::SyncOptions o;
      o.batch = 7;
      phaco::sync_records(st, centre, o);
    } catch (const std::exception&) {
      ++errors;
    }
  };
  std::thread a(run), b(run);
  a.join();
  b.join();
  EXPECT_EQ(errors.load(), 0);
  EXPECT_EQ(centre_count(), 300);
  EXPECT_EQ(centre_distinct(), 300);
  RecordStore st(file);
  RecordStore centre(uri_);
  EXPECT_EQ(phaco::sync_records(st, centre).pending, 0u);
}

TEST_F(PostgresRecords, AStationKilledMidSyncLosesAndDuplicatesNothing) {
  const fs::path file = station("s1", 200);
  for (const int kill_after : {1, 4, 9}) {
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      try {
        RecordStore st(file);
        RecordStore centre(uri_);
        phaco::SyncOptions o;
        o.batch = 5;
        int batches = 0;
        o.progress = [&](size_t) {
          if (++batches == kill_after) ::kill(::getpid(), SIGKILL);
        };
        phaco::sync_records(st, centre, o);
      } catch (...) {
      }
      _exit(3);
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status));
  }
  EXPECT_LE(centre_count(), 200);
  RecordStore st(file);
  RecordStore centre(uri_);
  EXPECT_EQ(st.integrity_check(), "ok");
  const auto r = phaco::sync_records(st, centre);
  EXPECT_EQ(r.uploaded + r.already_there, r.pending);
  EXPECT_EQ(centre_count(), 200);
  EXPECT_EQ(centre_distinct(), 200);
}

TEST_F(PostgresRecords, AServerRestartedMidSyncLosesAndDuplicatesNothing) {
  const fs::path file = station("s1", 200);
  {
    RecordStore st(file);
    RecordStore centre(uri_);
    phaco::SyncOptions o;
    o.batch = 10;
    int batches = 0;
    o.progress = [&](size_t) {
      if (++batches == 5) server("restart");
    };
    const std::string msg = input_error_of([&] { phaco::sync_records(st, centre, o); });
    EXPECT_NE(msg.find("***"), std::string::npos) << msg;  // names the centre, password masked
    EXPECT_EQ(centre_count(), 50);  // five batches committed before the restart
  }
  RecordStore st(file);
  RecordStore centre(uri_);
  const auto r = phaco::sync_records(st, centre);
  EXPECT_EQ(r.pending, 150u);
  EXPECT_EQ(centre_count(), 200);
  EXPECT_EQ(centre_distinct(), 200);
}

TEST_F(PostgresRecords, ACutNetworkIsAClearErrorAndTheNextSyncCompletes) {
  const fs::path file = station("s1", 60);
  server("stop");
  {
    RecordStore st(file);
    const std::string msg = input_error_of([&] { RecordStore centre(uri_); });
    EXPECT_NE(msg.find("cannot connect to the records server"), std::string::npos) << msg;
    EXPECT_EQ(st.count(), 60);  // the station's records are untouched
  }
  server("start");
  {
    RecordStore st(file);
    RecordStore centre(uri_);
    phaco::SyncOptions o;
    o.batch = 10;
    int batches = 0;
    o.progress = [&](size_t) {
      if (++batches == 2) server("stop");  // the cut comes mid-sync
    };
    EXPECT_THROW(phaco::sync_records(st, centre, o), InputError);
  }
  server("start");
  RecordStore st(file);
  RecordStore centre(uri_);
  phaco::sync_records(st, centre);
  EXPECT_EQ(centre_count(), 60);
  EXPECT_EQ(centre_distinct(), 60);
}

// The trainer's background upload: it syncs when asked, and while the centre is down it keeps
// retrying, so the station's records reach the centre once the centre is back.
TEST_F(PostgresRecords, TheBackgroundSyncRetriesUntilTheCentreIsBack) {
  const fs::path file = station("s1", 30);
  server("stop");
  {
    phaco::BackgroundSync sync(file, uri_, 0.2);
    // Wait (up to 60 s, a hang guard) for two failed attempts while the centre is down.
    for (int i = 0; i < 600 && sync.attempts() < 2; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    ASSERT_GE(sync.attempts(), 2);
    EXPECT_NE(sync.status().find("cannot connect"), std::string::npos) << sync.status();
    EXPECT_EQ(sync.status().find(uri_.substr(uri_.find(':', 13) + 1, 8)), std::string::npos);
    server("start");
    for (int i = 0; i < 600 && sync.status().find("all synced") == std::string::npos; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_NE(sync.status().find("30 uploaded, all synced"), std::string::npos) << sync.status();
    // A record stored later goes up when asked.
    RecordStore(file).add_record(sample("ana", "2026-12-01T00:00:00.000Z", 1));
    const int before = sync.attempts();
    sync.request();
    for (int i = 0; i < 600 && sync.attempts() == before; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_NE(sync.status().find("1 uploaded"), std::string::npos) << sync.status();
  }
  EXPECT_EQ(centre_count(), 31);
}

// Issue 21's load target: 16 stations (processes) each syncing 200 records to one server at
// once; every record present once. (Throughput and latency: `phaco-perf records`.)
TEST_F(PostgresRecords, SixteenStationsSyncingAtOnceStoreEveryRecordOnce) {
  constexpr int kStations = 16, kEach = 200;
  std::vector<fs::path> files;
  for (int s = 0; s < kStations; ++s)
    files.push_back(station("s" + std::to_string(s), kEach, "trainee " + std::to_string(s % 5)));
  const std::vector<pid_t> children = start_stations(kStations, [&](int i) {
    RecordStore st(files[static_cast<size_t>(i)]);
    RecordStore centre(uri_);
    phaco::SyncOptions o;
    o.batch = 20;
    return phaco::sync_records(st, centre, o).uploaded == static_cast<size_t>(kEach);
  });
  EXPECT_EQ(wait_stations(children), 0);
  EXPECT_EQ(centre_count(), kStations * kEach);
  EXPECT_EQ(centre_distinct(), kStations * kEach);
  EXPECT_EQ(admin_count(uri_, "SELECT count(*) FROM trainees"), 5);
}

}  // namespace
