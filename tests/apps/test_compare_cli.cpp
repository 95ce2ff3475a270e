// `phaco compare`, `phaco report --expert` and `phaco run --haptics --record` as a user meets
// them: exit codes, what is printed and written, and that a recorded real-time run replays.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "tests/apps/cli.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using phaco::test::phaco;
using phaco::test::read_text;
using phaco::test::temp_dir;
using phaco::test::write_text;
using Result = phaco::test::ShellResult;
using phaco::test::shell;

const fs::path kCompareFixture = fs::path(PHACO_SOURCE_DIR) / "tests/apps/data/report_fixture.json";

TEST(CompareCli, HelpNamesTheCommand) {
  const Result r = phaco("compare --help");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find("phaco compare RUN.json EXPERT.json"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--expert EXPERT.json"), std::string::npos) << r.output;
}

TEST(CompareCli, ReportWithItselfDiffersByNothingAndWritesJson) {
  const fs::path dir = temp_dir("self");
  const Result r = phaco("compare " + kCompareFixture.string() + " " + kCompareFixture.string() +
                         " --json " + (dir / "c.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("ratio 1.000"), std::string::npos) << r.output;
  const json c = json::parse(read_text(dir / "c.json"));
  for (const char* hand : {"left", "right"}) {
    EXPECT_EQ(c["hands"][hand]["aligned"]["path_distance_mm"]["max"].get<double>(), 0.0);
    EXPECT_EQ(c["hands"][hand]["aligned"]["force_diff_mN"]["rms"].get<double>(), 0.0);
    EXPECT_EQ(c["hands"][hand]["series"]["t_s"].size(), 300u);
  }
  EXPECT_EQ(c["metrics"]["score"]["difference"].get<double>(), 0.0);
  fs::remove_all(dir);
}

TEST(CompareCli, MalformedOrMissingInputIsBadInputNamingFileAndField) {
  const fs::path dir = temp_dir("bad");
  json j = json::parse(read_text(kCompareFixture));
  j["series"]["hands"]["right"]["speed_mm_s"][7] = "fast";
  write_text(dir / "bad.json", j.dump());
  Result r = phaco("compare " + (dir / "bad.json").string() + " " + kCompareFixture.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("bad.json: series.hands.right.speed_mm_s[7]: expected a number"),
            std::string::npos)
      << r.output;
  r = phaco("compare " + kCompareFixture.string());
  EXPECT_EQ(r.code, 2);
  r = phaco("compare " + kCompareFixture.string() + " " + (dir / "none.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("none.json: cannot open"), std::string::npos) << r.output;
  j = json::parse(read_text(kCompareFixture));
  j["drill"] = "phaco_sculpting";
  write_text(dir / "other.json", j.dump());
  r = phaco("report " + kCompareFixture.string() + " --html " + (dir / "o.html").string() +
            " --expert " + (dir / "other.json").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("drill"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "o.html"));
  fs::remove_all(dir);
}

TEST(CompareCli, ReportWithExpertHasTheComparisonSection) {
  const fs::path dir = temp_dir("report");
  Result r =
      phaco("report " + kCompareFixture.string() + " --html " + (dir / "plain.html").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(read_text(dir / "plain.html").find("id=\"compare\""), std::string::npos);
  r = phaco("report " + kCompareFixture.string() + " --html " + (dir / "with.html").string() +
            " --expert " + kCompareFixture.string());
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string page = read_text(dir / "with.html");
  EXPECT_NE(page.find("<section id=\"compare\">"), std::string::npos);
  EXPECT_NE(page.find("Compared with the expert"), std::string::npos);
  EXPECT_NE(page.find("id=\"plot-compare\""), std::string::npos);
  // The section sits before the footer.
  EXPECT_LT(page.find("id=\"compare\""), page.find("<footer>"));
  fs::remove_all(dir);
}

// A real-time run with --record stores the device's track; the exported scenario replays at the
// fixed step to the record's metrics and state hash.
TEST(CompareCli, RecordedHapticsRunReplaysToItsRecord) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "runs a drill twice; the Release pass runs it";
#endif
  const fs::path dir = temp_dir("haptics");
  const fs::path db = dir / "records.sqlite";
  const std::string scenario =
      (fs::path(PHACO_SOURCE_DIR) / "data/scenarios/capsulorhexis_expert.json").string();
  Result r = phaco("run " + scenario + " --haptics scripted:left --no-rt --duration 0.3 --record " +
                   db.string() + " --trainee haptic_ann");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("recorded as record 1"), std::string::npos) << r.output;
  r = phaco("export 1 --db " + db.string() + " --scenario " + (dir / "rec.json").string() +
            " --json " + (dir / "record.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const json rec = json::parse(read_text(dir / "rec.json"));
  const json record = json::parse(read_text(dir / "record.json"));
  // The left hand is what the device produced: ~1 sample per ms over 0.3 s, not the script's
  // handful of key frames; the recording lasts as long as the live run.
  EXPECT_GT(rec["hands"]["left"]["track"].size(), 100u);
  EXPECT_NEAR(rec["duration_s"].get<double>(), 0.3, 1e-9);
  EXPECT_EQ(record["report"]["recorded_from"]["device"], "scripted:left");
  EXPECT_TRUE(record["report"].contains("live"));
  r = phaco("run " + (dir / "rec.json").string() + " --json");
  ASSERT_EQ(r.code, 0) << r.output;
  const json replay = json::parse(r.output.substr(r.output.find('{')));
  EXPECT_EQ(replay["state_hash"], record["state_hash"]);
  EXPECT_EQ(replay["metrics"], record["metrics"]);
  fs::remove_all(dir);
}

TEST(CompareCli, HapticsRecordNeedsTrainee) {
  const fs::path dir = temp_dir("trainee");
  const std::string scenario =
      (fs::path(PHACO_SOURCE_DIR) / "data/scenarios/capsulorhexis_expert.json").string();
  const Result r = phaco("run " + scenario + " --haptics scripted:left --no-rt --duration 0.1 " +
                         "--record " + (dir / "db.sqlite").string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--trainee"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

}  // namespace
