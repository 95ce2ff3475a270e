// xAPI statements (issue 21 item 3): their fields from a record, checked here, and every exported
// statement validated by Learning Locker's validator (a real one, from npm; tests/tools/xapi),
// which must also refuse a statement broken on purpose, so the check can fail.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "engine/core/utc_time.hpp"
#include "engine/records/xapi.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/shell.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using phaco::SessionRecord;

SessionRecord sample(const std::string& trainee, double score) {
  SessionRecord r;
  r.trainee = trainee;
  r.drill = "capsulorhexis";
  r.scenario_name = "capsulorhexis expert";
  r.started_utc = "2026-11-21T10:00:00.000Z";
  r.finished_utc = "2026-11-21T10:01:02.125Z";
  r.settings = {{"dt_s", 1.0 / 120.0}, {"eye", {{"level", 3}}}};
  r.metrics = {{"rhexis.diameter_mm", 5.25}, {"left.tool_speed_mm_s.mean", 1.5}, {"score", score}};
  r.score = score;
  r.state_hash = "0123456789abcdef";
  r.uuid = "0f8e7a52-7d0c-4c55-9f4e-2b1d6c3a9e10";
  r.report = {
      {"software", {{"name", "OpenPhaco"}, {"version", "0.1.0"}, {"revision", "d46c276214a3"}}}};
  return r;
}

TEST(Xapi, AStatementCarriesScoreSuccessDurationAndMetricsWithUnits) {
  const json s = phaco::record_to_xapi(sample("Ana Ruiz", 81.5), "https://centre.example/t");
  EXPECT_EQ(s["id"], "0f8e7a52-7d0c-4c55-9f4e-2b1d6c3a9e10");
  EXPECT_EQ(s["actor"]["account"]["homePage"], "https://centre.example/t");
  EXPECT_EQ(s["actor"]["account"]["name"], "Ana Ruiz");
  EXPECT_EQ(s["verb"]["id"], "http://adlnet.gov/expapi/verbs/completed");
  EXPECT_EQ(s["object"]["id"], std::string(phaco::kXapiDrillIri) + "capsulorhexis");
  EXPECT_DOUBLE_EQ(s["result"]["score"]["scaled"].get<double>(), 0.815);
  EXPECT_EQ(s["result"]["score"]["raw"], 81.5);
  EXPECT_EQ(s["result"]["success"], true);  // 81.5 ≥ kPassScore
  EXPECT_EQ(s["result"]["completion"], true);
  EXPECT_EQ(s["result"]["duration"], "PT1M2.125S");
  const json& m = s["result"]["extensions"][std::string(phaco::kXapiExtensionIri) + "metrics"];
  EXPECT_EQ(m["rhexis.diameter_mm"]["unit"], "mm");
  EXPECT_EQ(m["left.tool_speed_mm_s.mean"]["unit"], "mm/s");
  EXPECT_EQ(m["rhexis.diameter_mm"]["value"], 5.25);
  EXPECT_EQ(s["context"]["extensions"][std::string(phaco::kXapiExtensionIri) + "state_hash"],
            "0123456789abcdef");
  EXPECT_EQ(s["timestamp"], "2026-11-21T10:01:02.125Z");
  // The build that made the run (issue 23), from the record's report; none for an older report.
  const std::string software = std::string(phaco::kXapiExtensionIri) + "software";
  EXPECT_EQ(s["context"]["extensions"][software]["revision"], "d46c276214a3");
  EXPECT_EQ(s["context"]["extensions"][software]["version"], "0.1.0");
  SessionRecord older = sample("c", 50);
  older.report = json::object();
  EXPECT_FALSE(phaco::record_to_xapi(older)["context"]["extensions"].contains(software));
  EXPECT_EQ(phaco::record_to_xapi(sample("b", 74.9))["result"]["success"], false);

  EXPECT_EQ(phaco::iso8601_duration(3723.5), "PT1H2M3.5S");
  EXPECT_EQ(phaco::iso8601_duration(60), "PT1M");
  EXPECT_EQ(phaco::iso8601_duration(0), "PT0S");
  EXPECT_EQ(phaco::iso8601_duration(-3), "PT0S");
  ASSERT_TRUE(phaco::parse_utc("2026-11-21T10:01:02.125Z").has_value());
  EXPECT_EQ(phaco::format_utc(*phaco::parse_utc("2026-11-21T10:01:02.125Z")),
            "2026-11-21T10:01:02.125Z");
  EXPECT_FALSE(phaco::parse_utc("2026-13-21T10:01:02.125Z").has_value());
  EXPECT_FALSE(phaco::parse_utc("yesterday").has_value());
}

// Runs the validator on `statements`; its exit code and output.
phaco::test::ShellResult validate(const json& statements, const std::string& name) {
  const fs::path file = fs::temp_directory_path() /
                        ("phaco-xapi-" + name + "-" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << statements.dump(2, ' ', false, json::error_handler_t::replace);
  auto r = phaco::test::shell("node " + std::string(std::getenv("PHACO_XAPI_VALIDATOR")) + " " +
                              file.string());
  fs::remove(file);
  return r;
}

TEST(Xapi, EveryExportedStatementPassesLearningLockersValidator) {
  const char* validator = std::getenv("PHACO_XAPI_VALIDATOR");
  PHACO_REQUIRE_ENVIRONMENT(validator && fs::exists(validator),
                            "no xAPI validator (scripts/test.sh installs it from npm)");
  json all = json::array();
  // Scored and unscored, names with quotes, Unicode and a byte that is not UTF-8, each drill.
  for (const char* drill : {"capsulorhexis", "phaco_sculpting", "corneal_incision"}) {
    SessionRecord r = sample("O'Brien \"Zoë\" 张伟", 90);
    r.drill = drill;
    all.push_back(phaco::record_to_xapi(r));
    r.score.reset();
    r.trainee = std::string("bad\xff byte");
    r.uuid = "1f8e7a52-7d0c-4c55-9f4e-2b1d6c3a9e1" + std::to_string(all.size());
    all.push_back(phaco::record_to_xapi(r));
  }
  const auto ok = validate(all, "good");
  EXPECT_EQ(ok.code, 0) << ok.output;
  EXPECT_NE(ok.output.find("6 statement(s), 0 problem(s)"), std::string::npos) << ok.output;

  json broken = all[0];
  broken["verb"]["id"] = "completed";         // not an IRI
  broken["result"]["score"]["scaled"] = 1.5;  // beyond 1
  const auto bad = validate(json::array({broken}), "bad");
  EXPECT_EQ(bad.code, 1) << bad.output;
  EXPECT_NE(bad.output.find("verb.id"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("scaled"), std::string::npos) << bad.output;
}

}  // namespace
