// `phaco run/validate/report/compare` on a procedure (issue 20 item 1, docs/procedures.md), as a
// user meets them: the summary's step scores and total, the JSON report, the HTML page with a
// page per step, a step-by-step comparison, each step stored as a record, and bad files named.
// Two short steps at level 0.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/apps/cli.hpp"

namespace {

namespace fs = std::filesystem;
using phaco::test::phaco;
using phaco::test::read_text;
using phaco::test::temp_dir;
using phaco::test::write_text;

std::string scenario(const char* name) {
  return (fs::path(PHACO_SOURCE_DIR) / "data/scenarios" / name).string();
}

fs::path short_procedure(const fs::path& dir, bool in_order = true) {
  const std::string incision =
                        R"({"scenario": ")" + scenario("corneal_incision_expert.json") + R"("})",
                    rhexis = R"({"scenario": ")" + scenario("capsulorhexis_expert.json") +
                             R"(", "duration_s": 0.5})";
  const fs::path file = dir / (in_order ? "p.json" : "bad.json");
  write_text(file, R"({"name": "short", "level": 0, "steps": [)" +
                       (in_order ? incision + ", " + rhexis : rhexis + ", " + incision) + "]}");
  return file;
}

TEST(ProcedureCli, RunsReportsAndComparesStepByStep) {
  const fs::path dir = temp_dir("procedure");
  const fs::path p = short_procedure(dir);
  auto r = phaco("validate " + p.string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("ok (procedure, 2 step(s)"), std::string::npos) << r.output;

  r = phaco("run " + p.string() + " --report " + (dir / "run.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("step corneal_incision   score 100.0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("procedure total"), std::string::npos) << r.output;
  const nlohmann::json j = nlohmann::json::parse(read_text(dir / "run.json"));
  ASSERT_EQ(j["steps"].size(), 2u);
  EXPECT_EQ(j["steps"][0]["drill"], "corneal_incision");
  EXPECT_TRUE(j["steps"][1]["carried_in"].contains("main_port"));
  const double s0 = j["step_scores"]["corneal_incision"], s1 = j["step_scores"]["capsulorhexis"];
  EXPECT_DOUBLE_EQ(j["total"].get<double>(), (s0 + s1) / 2.0);

  r = phaco("report " + (dir / "run.json").string() + " --html " + (dir / "run.html").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string html = read_text(dir / "run.html");
  EXPECT_NE(html.find("<h2>Total "), std::string::npos);
  size_t pages = 0;
  for (size_t at = html.find("<iframe srcdoc="); at != std::string::npos;
       at = html.find("<iframe srcdoc=", at + 1))
    ++pages;
  EXPECT_EQ(pages, 2u);

  r = phaco("compare " + (dir / "run.json").string() + " " + (dir / "run.json").string());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("step 2 (capsulorhexis)"), std::string::npos) << r.output;
}

TEST(ProcedureCli, BadProceduresAreNamed) {
  const fs::path dir = temp_dir("procedure-bad");
  auto r = phaco("validate " + short_procedure(dir, false).string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("steps[1].scenario: the steps go in the operation's order"),
            std::string::npos)
      << r.output;
  r = phaco("run " + short_procedure(dir).string() + " --haptics scripted");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--haptics is for a drill scenario"), std::string::npos) << r.output;
  r = phaco("run " + short_procedure(dir).string() + " --record " + (dir / "r.sqlite").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--record needs --trainee"), std::string::npos) << r.output;
}

// --record/--trainee store each step as its drill's record, marked with the procedure; the
// incision step (a fresh eye) replays from its export to the same state hash.
TEST(ProcedureCli, EachStepIsStoredAsItsDrillsRecord) {
  const fs::path dir = temp_dir("procedure-record");
  const fs::path db = dir / "records.sqlite";
  auto r = phaco("run " + short_procedure(dir).string() + " --record " + db.string() +
                 " --trainee ana --report " + (dir / "run.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("step 2 capsulorhexis recorded as record"), std::string::npos)
      << r.output;
  const nlohmann::json run = nlohmann::json::parse(read_text(dir / "run.json"));
  r = phaco("history ana --json --db " + db.string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json h = nlohmann::json::parse(r.output);
  ASSERT_EQ(h["records"].size(), 2u);
  EXPECT_EQ(h["records"][0]["drill"], "corneal_incision");
  EXPECT_EQ(h["records"][1]["drill"], "capsulorhexis");
  EXPECT_EQ(h["records"][1]["id"], run["steps"][1]["record_id"]);

  const std::string id = std::to_string(h["records"][0]["id"].get<int64_t>());
  r = phaco("export " + id + " --db " + db.string() + " --json " + (dir / "e.json").string() +
            " --scenario " + (dir / "step1.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json e = nlohmann::json::parse(read_text(dir / "e.json"));
  EXPECT_EQ(e["report"]["procedure"]["step"], 1);
  EXPECT_EQ(e["report"]["procedure"]["steps"], 2);
  EXPECT_DOUBLE_EQ(e["report"]["procedure"]["total"].get<double>(), run["total"].get<double>());
  r = phaco("run " + (dir / "step1.json").string() + " --report " + (dir / "again.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(nlohmann::json::parse(read_text(dir / "again.json"))["state_hash"],
            run["steps"][0]["state_hash"]);

  // Each step's record is dated when that step ran: it ended before the next began, and the last
  // ended by the time the run did (they were dated when stored, after the whole procedure, back
  // by each step's own wall time, so a long last step seemed to start before the others). The
  // dates sort as text.
  const std::string id2 = std::to_string(h["records"][1]["id"].get<int64_t>());
  r = phaco("export " + id2 + " --db " + db.string() + " --json " + (dir / "e2.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json e2 = nlohmann::json::parse(read_text(dir / "e2.json"));
  const std::string end1 = e["finished_utc"], start2 = e2["started_utc"], end2 = e2["finished_utc"];
  EXPECT_LE(e["started_utc"].get<std::string>(), end1);
  EXPECT_LE(end1, start2);
  EXPECT_LE(start2, end2);
  EXPECT_LE(end2, run["date"].get<std::string>()) << "the last step's record ends after the run";
  EXPECT_EQ(end2, run["steps"][1]["date"]);
}

}  // namespace
