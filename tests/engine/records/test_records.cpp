// RecordStore: round trip, date order, schema checks, errors that name the file, transactions
// that leave nothing behind, a writer killed mid-stream, and the XML/JSON export.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <thread>

#include "engine/core/error.hpp"
#include "engine/records/migrations.hpp"
#include "engine/records/record_location.hpp"
#include "engine/records/records.hpp"
#include "tests/engine/records/sample_record.hpp"
#include "tests/support/expect_invalid.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using phaco::InputError;
using phaco::OpenMode;
using phaco::RecordStore;
using phaco::SessionRecord;

fs::path temp_db(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("phaco-records-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d / "records.sqlite";
}

// The database's folder, removed when the test ends (a forked child leaves by _exit, not here).
struct TempDb {
  explicit TempDb(const std::string& name) : file(temp_db(name)) {}
  ~TempDb() {
    std::error_code ec;
    fs::remove_all(file.parent_path(), ec);
  }
  fs::path file;
};

SessionRecord sample(const std::string& trainee, const std::string& started, double score) {
  return phaco::test::sample_record(trainee, started, score);
}

// Raw SQL on the file, as another program (or a damaged disk) would touch it.
void raw_sql(const fs::path& file, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.string().c_str(), &db), SQLITE_OK);
  char* err = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
  const std::string msg = err ? err : "";
  sqlite3_free(err);
  sqlite3_close(db);
  ASSERT_EQ(rc, SQLITE_OK) << msg;
}

using phaco::test::input_error_of;

TEST(Records, RoundTripKeepsEveryField) {
  const TempDb tmp("roundtrip");
  const fs::path& file = tmp.file;
  SessionRecord in = sample("Ana Ruiz", "2026-11-21T10:00:00.000Z", 81.5);
  in.finished_utc = "2026-11-21T10:00:42.125Z";
  int64_t id = 0;
  {
    RecordStore store(file);
    id = store.add_record(in);
    EXPECT_GT(id, 0);
  }
  const RecordStore store(file, OpenMode::ExistingOnly);  // reopened: it was on disk
  const auto out = store.record(id);
  ASSERT_TRUE(out.has_value());
  EXPECT_EQ(out->id, id);
  EXPECT_EQ(out->trainee, in.trainee);
  EXPECT_EQ(out->drill, in.drill);
  EXPECT_EQ(out->scenario_name, in.scenario_name);
  EXPECT_EQ(out->started_utc, in.started_utc);
  EXPECT_EQ(out->finished_utc, in.finished_utc);
  EXPECT_EQ(out->settings, in.settings);  // doubles exact: 1/120 survives text
  EXPECT_EQ(out->metrics, in.metrics);
  ASSERT_TRUE(out->score.has_value());
  EXPECT_EQ(*out->score, 81.5);
  EXPECT_EQ(out->state_hash, in.state_hash);
  EXPECT_EQ(out->recording, in.recording);
  EXPECT_EQ(out->report, in.report);
  EXPECT_FALSE(store.record(id + 1).has_value());
  EXPECT_EQ(store.integrity_check(), "ok");

  SessionRecord unscored = sample("Ana Ruiz", "2026-11-22T10:00:00.000Z", 0);
  unscored.score.reset();
  RecordStore writer(file);
  const auto back = writer.record(writer.add_record(unscored));
  ASSERT_TRUE(back.has_value());
  EXPECT_FALSE(back->score.has_value());
}

TEST(Records, FileIsWalWithSchemaVersion) {
  const TempDb tmp("wal");
  const fs::path& file = tmp.file;
  { RecordStore store(file); }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.string().c_str(), &db), SQLITE_OK);
  auto pragma = [&](const char* sql) {
    sqlite3_stmt* s = nullptr;
    sqlite3_prepare_v2(db, sql, -1, &s, nullptr);
    std::string v;
    if (sqlite3_step(s) == SQLITE_ROW) v = reinterpret_cast<const char*>(sqlite3_column_text(s, 0));
    sqlite3_finalize(s);
    return v;
  };
  EXPECT_EQ(pragma("PRAGMA journal_mode"), "wal");  // WAL is persistent in the file
  EXPECT_EQ(pragma("PRAGMA user_version"), std::to_string(phaco::kRecordsSchemaVersion));
  sqlite3_close(db);
}

TEST(Records, TraineeRecordsComeInDateOrder) {
  const TempDb tmp("order");
  const fs::path& file = tmp.file;
  RecordStore store(file);
  // Written out of order; read back by date, ties by id.
  const int64_t c = store.add_record(sample("ana", "2026-11-23T09:00:00.000Z", 90));
  const int64_t a = store.add_record(sample("ana", "2026-11-21T09:00:00.000Z", 60));
  store.add_record(sample("ben", "2026-11-20T09:00:00.000Z", 10));
  const int64_t b1 = store.add_record(sample("ana", "2026-11-22T09:00:00.000Z", 70));
  const int64_t b2 = store.add_record(sample("ana", "2026-11-22T09:00:00.000Z", 75));
  const auto rows = store.records_of("ana");
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].id, a);
  EXPECT_EQ(rows[1].id, b1);
  EXPECT_EQ(rows[2].id, b2);
  EXPECT_EQ(rows[3].id, c);
  for (const auto& r : rows) EXPECT_EQ(r.trainee, "ana");
  EXPECT_TRUE(store.records_of("nobody").empty());
  EXPECT_EQ(store.trainees(), (std::vector<std::string>{"ana", "ben"}));
}

TEST(Records, NewerSchemaVersionIsRefused) {
  const TempDb tmp("version");
  const fs::path& file = tmp.file;
  { RecordStore store(file); }
  raw_sql(file, "PRAGMA user_version = 7");
  const std::string msg = input_error_of([&] { RecordStore store(file); });
  EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("schema version 7 is newer"), std::string::npos) << msg;
}

// Issue 21: a file an older phaco wrote (schema version 1, no uuids) is upgraded when opened:
// its records read as before and each gets a uuid, distinct, in the RFC 4122 version-4 form.
TEST(Records, AVersionOneFileIsUpgradedAndItsRecordsGetUuids) {
  const TempDb tmp("upgrade");
  const fs::path& file = tmp.file;
  raw_sql(file, std::string(phaco::records::migrations()[0].sqlite) +
                    "PRAGMA user_version = 1; INSERT INTO trainees(name, created) VALUES('ana', "
                    "'x'); INSERT INTO records(trainee_id, drill, scenario_name, started_utc, "
                    "finished_utc, settings, metrics, score, state_hash, recording, report) "
                    "SELECT id, 'capsulorhexis', 's', '2026-01-0' || n || 'T00:00:00.000Z', "
                    "'2026-01-0' || n || 'T00:00:01.000Z', '{}', '{\"score\": 7}', 7, 'h', '{}', "
                    "'{}' FROM trainees, (SELECT 1 AS n UNION SELECT 2 UNION SELECT 3)");
  RecordStore store(file, OpenMode::ExistingOnly);
  EXPECT_EQ(store.schema_version(), 2);
  const auto old = store.records_of("ana");
  ASSERT_EQ(old.size(), 3u);
  std::set<std::string> uuids;
  for (const auto& r : old) {
    EXPECT_EQ(*r.score, 7);
    ASSERT_EQ(r.uuid.size(), 36u);
    EXPECT_EQ(r.uuid[14], '4') << r.uuid;                                          // version 4
    EXPECT_NE(std::string("89ab").find(r.uuid[19]), std::string::npos) << r.uuid;  // variant
    uuids.insert(r.uuid);
  }
  EXPECT_EQ(uuids.size(), 3u);
  EXPECT_EQ(store.integrity_check(), "ok");
  // New records get a uuid of the same form, and a uuid is stored once.
  SessionRecord r = sample("ana", "2026-02-01T00:00:00.000Z", 9);
  r.uuid = phaco::new_record_uuid();
  EXPECT_EQ(r.uuid[14], '4');
  store.add_record(r);
  EXPECT_NE(input_error_of([&] { store.add_record(r); }).find("already stored"), std::string::npos);
  EXPECT_EQ(store.add_missing(std::vector<SessionRecord>{r}), 0u);
  EXPECT_EQ(store.count(), 4);
}

// Issue 21: where records live, as it may be printed: a server URI's password never shows.
TEST(Records, ALocationIsShownWithoutItsPassword) {
  using phaco::is_postgres_uri;
  using phaco::shown_location;
  EXPECT_TRUE(is_postgres_uri("postgresql://u@h/d"));
  EXPECT_TRUE(is_postgres_uri("postgres://u@h/d"));
  EXPECT_FALSE(is_postgres_uri("/home/ana/records.sqlite"));
  EXPECT_FALSE(is_postgres_uri("postgresql:/x"));
  EXPECT_EQ(shown_location("postgresql://ana:s3cr:et@db.example:5432/centre"),
            "postgresql://ana:***@db.example:5432/centre");
  EXPECT_EQ(shown_location("postgresql://ana@db.example/centre"),
            "postgresql://ana@db.example/centre");
  EXPECT_EQ(shown_location("postgresql://ana:p%40ss@/centre?host=/run/pg&password=x&port=5"),
            "postgresql://ana:***@/centre?host=/run/pg&password=***&port=5");
  EXPECT_EQ(shown_location("postgres://h/d?sslmode=require&password=top"),
            "postgres://h/d?sslmode=require&password=***");
  EXPECT_EQ(shown_location("postgresql://u:a/b@h/d"), "postgresql://u:***@h/d");
  EXPECT_EQ(shown_location("/tmp/a:b@c/records.sqlite"), "/tmp/a:b@c/records.sqlite");
  EXPECT_NE(input_error_of([] { RecordStore store(""); }).find("no records database given"),
            std::string::npos);
}

TEST(Records, ForeignSqliteDatabaseIsRefused) {
  const TempDb tmp("foreign");
  const fs::path& file = tmp.file;
  raw_sql(file, "CREATE TABLE photos(id INTEGER)");
  const std::string msg = input_error_of([&] { RecordStore store(file); });
  EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("not an OpenPhaco records database"), std::string::npos) << msg;
}

TEST(Records, NonDatabaseFileNamesFileAndProblem) {
  const TempDb tmp("notadb");
  const fs::path& file = tmp.file;
  std::ofstream(file) << "this is a scenario, not a database\n" << std::string(4096, 'x');
  const std::string msg = input_error_of([&] { RecordStore store(file); });
  EXPECT_EQ(msg.rfind(file.string() + ": ", 0), 0u) << msg;
  EXPECT_NE(msg.find("not an SQLite database"), std::string::npos) << msg;

  const fs::path missing = file.parent_path() / "missing.sqlite";
  const std::string gone =
      input_error_of([&] { RecordStore store(missing, OpenMode::ExistingOnly); });
  EXPECT_NE(gone.find(missing.string()), std::string::npos) << gone;
  EXPECT_FALSE(fs::exists(missing)) << "history/export must not create a database";

  const fs::path no_dir = file.parent_path() / "no" / "such" / "dir.sqlite";
  const std::string cant = input_error_of([&] { RecordStore store(no_dir); });
  EXPECT_NE(cant.find(no_dir.string()), std::string::npos) << cant;
}

TEST(Records, LockedDatabaseIsReportedNotHung) {
  const TempDb tmp("locked");
  const fs::path& file = tmp.file;
  { RecordStore store(file); }
  // Another connection holds the write lock; ours waits its busy timeout (100 ms here) and then
  // reports the lock instead of hanging.
  sqlite3* other = nullptr;
  ASSERT_EQ(sqlite3_open(file.string().c_str(), &other), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(other, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr), SQLITE_OK);
  RecordStore store(file, OpenMode::CreateIfMissing, 100);  // WAL readers do not wait for it
  const std::string msg =
      input_error_of([&] { store.add_record(sample("ana", "2026-01-01T00:00:00.000Z", 5)); });
  sqlite3_exec(other, "ROLLBACK", nullptr, nullptr, nullptr);
  sqlite3_close(other);
  EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("locked"), std::string::npos) << msg;
  EXPECT_TRUE(store.records_of("ana").empty());
  // Once the other writer is gone the same store writes.
  EXPECT_GT(store.add_record(sample("ana", "2026-01-01T00:00:00.000Z", 5)), 0);
}

TEST(Records, MalformedJsonInARowNamesRecordAndColumn) {
  const TempDb tmp("badjson");
  const fs::path& file = tmp.file;
  int64_t id = 0;
  {
    RecordStore store(file);
    id = store.add_record(sample("ana", "2026-11-21T09:00:00.000Z", 50));
  }
  raw_sql(file, "UPDATE records SET metrics = '{\"score\": 50,' WHERE id = " + std::to_string(id));
  const RecordStore store(file);
  const std::string msg = input_error_of([&] { store.record(id); });
  EXPECT_NE(msg.find(file.string() + ": record " + std::to_string(id) + ", column 'metrics'"),
            std::string::npos)
      << msg;
  EXPECT_NE(input_error_of([&] { store.records_of("ana"); }).find("column 'metrics'"),
            std::string::npos);

  raw_sql(file, "UPDATE records SET metrics = '{}', settings = '[1, 2]' WHERE id = " +
                    std::to_string(id));
  const std::string not_object = input_error_of([&] { store.record(id); });
  EXPECT_NE(not_object.find("column 'settings': expected a JSON object"), std::string::npos)
      << not_object;
}

TEST(Records, FailedWriteRollsBackEverything) {
  const TempDb tmp("rollback");
  const fs::path& file = tmp.file;
  RecordStore store(file);
  store.add_record(sample("ana", "2026-11-21T09:00:00.000Z", 50));
  // A new trainee's first record breaks the schema (score beyond 100) after the trainee row was
  // inserted in the same transaction: the trainee must not remain.
  const std::string msg =
      input_error_of([&] { store.add_record(sample("carla", "2026-11-21T10:00:00.000Z", 150)); });
  EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
  EXPECT_NE(msg.find("CHECK constraint failed"), std::string::npos) << msg;
  EXPECT_EQ(store.trainees(), std::vector<std::string>{"ana"});
  EXPECT_TRUE(store.records_of("carla").empty());
  // Finished before started is refused the same way.
  SessionRecord backwards = sample("dan", "2026-11-21T10:00:00.000Z", 50);
  backwards.finished_utc = "2026-11-21T09:59:59.000Z";
  EXPECT_THROW(store.add_record(backwards), InputError);
  EXPECT_EQ(store.trainees(), std::vector<std::string>{"ana"});
  // And the store still works after a rollback.
  EXPECT_GT(store.add_record(sample("carla", "2026-11-21T10:00:00.000Z", 99)), 0);
  EXPECT_EQ(store.records_of("carla").size(), 1u);
  EXPECT_EQ(store.records_of("ana").size(), 1u);
}

TEST(Records, WriterKilledMidStreamLeavesCommittedRecordsIntact) {
  const TempDb tmp("kill");
  const fs::path& file = tmp.file;
  RecordStore(file).add_record(sample("ana", "2026-11-21T09:00:00.000Z", 42));
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // Writes big records as fast as it can until killed, so the kill lands mid-transaction
    // (most of the time is spent inside one).
    try {
      RecordStore store(file);
      SessionRecord r = sample("ben", "2026-11-22T09:00:00.000Z", 1);
      r.report["padding"] = std::string(256 * 1024, 'p');
      for (int i = 0; i < 100000; ++i) store.add_record(r);
    } catch (...) {
    }
    _exit(3);
  }
  // Wait until the child has committed a few records, then kill it without warning.
  int committed = 0;
  for (int tries = 0; tries < 2000 && committed < 5; ++tries) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    try {
      committed = static_cast<int>(RecordStore(file).records_of("ben").size());
    } catch (const InputError&) {
    }
  }
  ASSERT_EQ(kill(child, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the writer finished before it was killed";
  ASSERT_GE(committed, 5);

  RecordStore store(file);
  EXPECT_EQ(store.integrity_check(), "ok");
  const auto ana = store.records_of("ana");
  ASSERT_EQ(ana.size(), 1u);
  EXPECT_EQ(*ana[0].score, 42);
  const auto ben = store.records_of("ben");  // every row whole: all JSON columns parse
  EXPECT_GE(ben.size(), static_cast<size_t>(committed));
  for (const auto& r : ben) EXPECT_EQ(r.report["padding"].get<std::string>().size(), 256u * 1024u);
  EXPECT_GT(store.add_record(sample("ana", "2026-11-23T09:00:00.000Z", 43)), 0);
}

// Runs `body` in a forked child and returns what it reports through a pipe (at most 4 kB): the
// fault tests change process-wide limits (file size, user id) that the test runner must keep.
std::string in_child(const std::function<std::string()>& body) {
  int fds[2];
  if (pipe(fds) != 0) return "pipe failed";
  const pid_t child = fork();
  if (child == 0) {
    close(fds[0]);
    std::string out;
    try {
      out = body();
    } catch (const std::exception& e) {
      out = std::string("unexpected exception: ") + e.what();
    }
    const ssize_t w = write(fds[1], out.data(), std::min<size_t>(out.size(), 4096));
    _exit(w < 0 ? 4 : 0);
  }
  close(fds[1]);
  std::string got;
  char buf[4096];
  for (ssize_t n; (n = read(fds[0], buf, sizeof buf)) > 0;) got.append(buf, static_cast<size_t>(n));
  close(fds[0]);
  int status = 0;
  waitpid(child, &status, 0);
  if (!WIFEXITED(status)) return "child died: signal " + std::to_string(WTERMSIG(status));
  return got;
}

// Issue 18 item 6: a full disk. The child may grow no file past the size the database has now
// (RLIMIT_FSIZE; SIGXFSZ ignored, so the write fails with EFBIG as on a full file system) and
// adds big records until one fails: the error names the database, and every record stored
// before it is intact afterwards.
TEST(Records, AFullDiskNamesTheDatabaseAndKeepsEveryEarlierRecord) {
  const TempDb tmp("full");
  const fs::path& file = tmp.file;
  RecordStore(file).add_record(sample("ana", "2026-11-21T09:00:00.000Z", 42));
  const std::string child = in_child([&] {
    signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{static_cast<rlim_t>(fs::file_size(file) + 64 * 1024),
                       static_cast<rlim_t>(fs::file_size(file) + 64 * 1024)};
    if (setrlimit(RLIMIT_FSIZE, &limit) != 0) return std::string("setrlimit failed");
    RecordStore store(file);
    SessionRecord r = sample("ben", "2026-11-22T09:00:00.000Z", 1);
    r.report["padding"] = std::string(40 * 1024, 'p');
    int stored = 0;
    try {
      for (; stored < 1000; ++stored) store.add_record(r);
    } catch (const InputError& e) {
      return "stored " + std::to_string(stored) + ": " + e.what();
    }
    return std::string("never failed");
  });
  ASSERT_EQ(child.rfind("stored ", 0), 0u) << child;
  EXPECT_NE(child.find(file.string()), std::string::npos) << child;
  EXPECT_TRUE(child.find("full") != std::string::npos ||
              child.find("disk I/O") != std::string::npos)
      << child;
  const int stored_before_full = std::stoi(child.substr(7));
  RecordStore store(file);
  EXPECT_EQ(store.integrity_check(), "ok");
  ASSERT_EQ(store.records_of("ana").size(), 1u);
  EXPECT_EQ(*store.records_of("ana")[0].score, 42);
  EXPECT_EQ(store.records_of("ben").size(), static_cast<size_t>(stored_before_full));
  // With room again the same file takes the next record.
  EXPECT_GT(store.add_record(sample("ana", "2026-11-23T09:00:00.000Z", 43)), 0);
}

// A database the user may read but not write (another user's file, a read-only share): the
// child drops to the unprivileged user `nobody` (root ignores file modes), opens the file,
// reads it, and its write fails naming the database.
TEST(Records, AReadOnlyDatabaseNamesTheDatabaseAndKeepsItsRecords) {
  const TempDb tmp("readonly");
  const fs::path& file = tmp.file;
  RecordStore(file).add_record(sample("ana", "2026-11-21T09:00:00.000Z", 42));
  fs::permissions(file.parent_path(), fs::perms::owner_all | fs::perms::group_read |
                                          fs::perms::group_exec | fs::perms::others_read |
                                          fs::perms::others_exec);
  for (const char* suffix : {"", "-wal", "-shm"}) {
    const fs::path f = file.string() + suffix;
    if (fs::exists(f))
      fs::permissions(f, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read |
                             fs::perms::others_read);
  }
  const std::string child = in_child([&] {
    if (geteuid() == 0 && setuid(65534) != 0) return std::string("setuid failed");
    try {
      RecordStore store(file);
      const size_t before = store.records_of("ana").size();
      store.add_record(sample("ben", "2026-11-22T09:00:00.000Z", 1));
      return "wrote (read " + std::to_string(before) + ")";
    } catch (const InputError& e) {
      return std::string("error: ") + e.what();
    }
  });
  ASSERT_EQ(child.rfind("error: ", 0), 0u) << child;
  EXPECT_NE(child.find(file.string()), std::string::npos) << child;
  EXPECT_TRUE(child.find("read-only") != std::string::npos ||
              child.find("cannot open") != std::string::npos ||
              child.find("unable to open") != std::string::npos)
      << child;
  const RecordStore store(file, OpenMode::ExistingOnly);
  EXPECT_EQ(store.integrity_check(), "ok");
  EXPECT_EQ(store.records_of("ana").size(), 1u);
  EXPECT_TRUE(store.records_of("ben").empty());
}

// A file damaged on disk (bytes overwritten inside the records' pages): every call either works
// or throws an InputError that names the file; none crashes.
TEST(Records, ACorruptDatabaseNamesTheFileAndNeverCrashes) {
  const TempDb tmp("corrupt");
  const fs::path& file = tmp.file;
  {
    RecordStore store(file);
    SessionRecord r = sample("ana", "2026-11-21T09:00:00.000Z", 42);
    r.report["padding"] = std::string(20 * 1024, 'p');
    for (int i = 0; i < 10; ++i) store.add_record(r);
  }
  raw_sql(file, "PRAGMA wal_checkpoint(TRUNCATE)");
  const auto size = fs::file_size(file);
  ASSERT_GT(size, 8u * 4096u);
  {
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    for (std::streamoff at = 4096; at < static_cast<std::streamoff>(size); at += 4096 * 3) {
      f.seekp(at);  // the page's header and cell pointers, and the start of its cells
      const std::string junk(300, '\xA5');
      f.write(junk.data(), static_cast<std::streamsize>(junk.size()));
    }
  }
  int errors = 0;
  auto attempt = [&](const std::function<void()>& call) {
    try {
      call();
    } catch (const InputError& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    }
  };
  attempt([&] {
    RecordStore store(file);
    attempt([&] { (void)store.records_of("ana"); });
    attempt([&] { (void)store.trainees(); });
    attempt([&] { (void)store.integrity_check(); });
    attempt([&] { store.add_record(sample("ben", "2026-11-22T09:00:00.000Z", 1)); });
  });
  EXPECT_GT(errors, 0) << "the damage went unnoticed";
}

TEST(Records, MetricUnitsComeFromTheNames) {
  using phaco::metric_unit;
  EXPECT_EQ(metric_unit("time_s"), "s");
  EXPECT_EQ(metric_unit("incision.width_mm"), "mm");
  EXPECT_EQ(metric_unit("incision.entry_angle_deg"), "deg");
  EXPECT_EQ(metric_unit("incision.clock_hour"), "clock hour");
  EXPECT_EQ(metric_unit("left.tool_speed_mm_s.mean"), "mm/s");
  EXPECT_EQ(metric_unit("left.contact_force_mN.max"), "mN");
  EXPECT_EQ(metric_unit("volume_removed_mm3"), "mm^3");
  EXPECT_EQ(metric_unit("haptic_model.lens_stiffness_mn_mm"), "mN/mm");
  EXPECT_EQ(metric_unit("score"), "points");
  EXPECT_EQ(metric_unit("rhexis.circularity"), "1");
  EXPECT_EQ(metric_unit("regrasps"), "1");
  EXPECT_EQ(metric_unit("trench.depth_fraction"), "1");
  EXPECT_EQ(metric_unit("eye.overrides.capsule.youngs_modulus_kpa"), "kPa");
}

TEST(Records, XmlExportEscapesAndListsEveryMetricWithUnit) {
  SessionRecord r = sample("O'Brien <&> \"Jo\"", "2026-11-21T09:00:00.000Z", 77.25);
  r.id = 12;
  r.uuid = "0f8e7a52-7d0c-4c55-9f4e-2b1d6c3a9e10";
  r.trainee += std::string("\x01\xff", 2);  // a control character and a byte that is not UTF-8
  r.metrics["left.contact_force_mN.max"] = 12.5;
  r.metrics["left.contact_force_mN.histogram"] = json::array({1, 2, 3});
  const std::string xml = phaco::records_to_xml({r});
  EXPECT_EQ(
      xml.rfind("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<openphaco_records schema=\"2\">", 0),
      0u);
  EXPECT_NE(xml.find("<session id=\"12\" uuid=\"0f8e7a52-7d0c-4c55-9f4e-2b1d6c3a9e10\">"),
            std::string::npos);
  EXPECT_NE(
      xml.find(
          "<trainee>O&apos;Brien &lt;&amp;&gt; &quot;Jo&quot;\xEF\xBF\xBD\xEF\xBF\xBD</trainee>"),
      std::string::npos)
      << xml;
  EXPECT_NE(
      xml.find("<metric name=\"rhexis.diameter_mm\" unit=\"mm\" type=\"number\">5.25</metric>"),
      std::string::npos)
      << xml;
  EXPECT_NE(xml.find("<metric name=\"rhexis.complete\" unit=\"1\" type=\"bool\">true</metric>"),
            std::string::npos);
  EXPECT_NE(
      xml.find(
          "<metric name=\"left.contact_force_mN.max\" unit=\"mN\" type=\"number\">12.5</metric>"),
      std::string::npos);
  EXPECT_NE(xml.find("type=\"array\">[1,2,3]</metric>"), std::string::npos);
  EXPECT_NE(xml.find("<setting name=\"eye.level\" unit=\"1\" type=\"number\">2</setting>"),
            std::string::npos);
  EXPECT_NE(
      xml.find("<setting name=\"dt_s\" unit=\"s\" type=\"number\">0.008333333333333333</setting>"),
      std::string::npos)
      << xml;
  EXPECT_NE(xml.find("<score unit=\"points\">77.25</score>"), std::string::npos);
  EXPECT_EQ(xml.find('\x01'), std::string::npos);
  // Every metric appears once.
  size_t count = 0;
  for (size_t p = 0; (p = xml.find("<metric ", p)) != std::string::npos; ++p) ++count;
  EXPECT_EQ(count, r.metrics.size());

  const json j = phaco::record_to_json(r);
  EXPECT_EQ(j["id"], 12);
  EXPECT_EQ(j["score"], 77.25);
  EXPECT_EQ(j["metrics"], r.metrics);
  EXPECT_EQ(j["recording"], r.recording);
}

TEST(Records, UtcFormatSortsAsDates) {
  EXPECT_EQ(phaco::format_utc(0), "1970-01-01T00:00:00.000Z");
  EXPECT_EQ(phaco::format_utc(1795000000.9996), "2026-11-18T11:06:41.000Z");  // rounds up a second
  EXPECT_LT(phaco::format_utc(1795000000.5), phaco::format_utc(1795000001.0));
  EXPECT_EQ(phaco::utc_now().size(), 24u);
}

}  // namespace
