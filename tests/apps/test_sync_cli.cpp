// `phaco sync` and `--db postgresql://…` as a centre's administrator meets them (issue 21): the
// binary against the throwaway server scripts/test.sh starts. No output ever shows the password.
#include <gtest/gtest.h>
#include <libpq-fe.h>

#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "engine/records/records.hpp"
#include "tests/apps/cli.hpp"
#include "tests/support/environment.hpp"

namespace {

namespace fs = std::filesystem;
using phaco::test::phaco;

std::string env(const char* name) {
  const char* v = std::getenv(name);
  return v ? v : "";
}

bool admin_sql(const std::string& uri, const std::string& sql) {
  PGconn* c = PQconnectdb(uri.c_str());
  PGresult* r = PQexec(c, sql.c_str());
  const bool ok = PQresultStatus(r) == PGRES_COMMAND_OK;
  PQclear(r);
  PQfinish(c);
  return ok;
}

std::string quoted(const std::string& s) {
  return "'" + s + "'";
}

TEST(SyncCli, BadTargetsAreNamedWithoutStartingAnything) {
  const fs::path dir = phaco::test::temp_dir("sync-bad");
  const auto no_uri = phaco("sync --to " + (dir / "centre.sqlite").string() + " --db " +
                            (dir / "station.sqlite").string());
  EXPECT_EQ(no_uri.code, 2);
  EXPECT_NE(no_uri.output.find("--to expects a postgresql:// URI"), std::string::npos)
      << no_uri.output;
  const auto no_to = phaco("sync --db x.sqlite", "PHACO_SYNC_TO=");
  EXPECT_EQ(no_to.code, 2);
  EXPECT_NE(no_to.output.find("give --to"), std::string::npos) << no_to.output;
  const auto batch = phaco("sync --to postgresql://u:pw@h/d --batch 0");
  EXPECT_EQ(batch.code, 2);
  EXPECT_NE(batch.output.find("--batch expects"), std::string::npos) << batch.output;
  EXPECT_EQ(batch.output.find(":pw@"), std::string::npos) << batch.output;
  fs::remove_all(dir);
}

TEST(SyncCli, AStationSyncsToTheCentreAndHistoryReadsTheCentre) {
  const std::string admin = env("PHACO_TEST_PG_URI");
  PHACO_REQUIRE_ENVIRONMENT(!admin.empty(), "no PostgreSQL test cluster (scripts/test.sh)");
  const std::string db = "phaco_cli" + std::to_string(::getpid());
  ASSERT_TRUE(admin_sql(admin, "CREATE DATABASE " + db));
  const size_t slash = admin.find("/postgres?");
  const std::string uri = admin.substr(0, slash) + "/" + db + admin.substr(slash + 9);
  const std::string password =
      uri.substr(uri.find(':', 13) + 1, uri.find('@') - uri.find(':', 13) - 1);
  const fs::path dir = phaco::test::temp_dir("sync");
  const fs::path station = dir / "station.sqlite";
  {
    phaco::RecordStore s(station);
    for (int i = 0; i < 3; ++i) {
      phaco::SessionRecord r;
      r.trainee = "Zoë O'Neill";
      r.drill = "capsulorhexis";
      r.scenario_name = "demo";
      r.started_utc = r.finished_utc = "2026-11-2" + std::to_string(i) + "T10:00:00.000Z";
      r.score = 70 + i;
      r.metrics = {{"score", 70 + i}, {"rhexis.diameter_mm", 5.2}};
      s.add_record(r);
    }
  }
  const auto first = phaco("sync --to " + quoted(uri) + " --db " + station.string());
  EXPECT_EQ(first.code, 0) << first.output;
  EXPECT_NE(first.output.find("3 to send, 3 uploaded, 0 already there, 0 refused"),
            std::string::npos)
      << first.output;
  EXPECT_EQ(first.output.find(password), std::string::npos) << first.output;
  const auto again =
      phaco("sync --db " + station.string() + " --json", "PHACO_SYNC_TO=" + quoted(uri));
  EXPECT_EQ(again.code, 0) << again.output;
  const auto j = nlohmann::json::parse(again.output.substr(again.output.find('{')));
  EXPECT_EQ(j["pending"], 0);
  EXPECT_EQ(again.output.find(password), std::string::npos);

  // The centre answers history and export like a station's file, through --db or PHACO_DB.
  const auto history = phaco("history \"Zoë O'Neill\" --db " + quoted(uri));
  EXPECT_EQ(history.code, 0) << history.output;
  EXPECT_NE(history.output.find("3 session(s)"), std::string::npos) << history.output;
  EXPECT_NE(history.output.find("70.0 -> 72.0"), std::string::npos) << history.output;
  EXPECT_EQ(history.output.find(password), std::string::npos) << history.output;
  const auto viaenv = phaco("history \"Zoë O'Neill\" --json", "PHACO_DB=" + quoted(uri));
  EXPECT_EQ(viaenv.code, 0) << viaenv.output;
  EXPECT_EQ(viaenv.output.find(password), std::string::npos) << viaenv.output;
  const auto missing = phaco("history nobody --db " + quoted(uri));
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.output.find("***"), std::string::npos) << missing.output;
  EXPECT_EQ(missing.output.find(password), std::string::npos) << missing.output;

  fs::remove_all(dir);
  admin_sql(admin, "DROP DATABASE IF EXISTS " + db + " WITH (FORCE)");
}

}  // namespace
