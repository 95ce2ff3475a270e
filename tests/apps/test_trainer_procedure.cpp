// phaco-trainer --procedure under Xvfb (issue 20 item 1, docs/procedures.md): the steps follow one
// another in the trainer, each step's score is printed, the scripted run closes when done, and
// --procedure-out's recording replays with `phaco run` to the same scores and state hashes, and
// --stats covers every step.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/apps/cli.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/sanitizers.hpp"

namespace {

namespace fs = std::filesystem;
using phaco::test::read_text;
using phaco::test::shell;
using phaco::test::temp_dir;
using phaco::test::write_text;

TEST(TrainerProcedure, StepsThroughAndItsRecordingReplays) {
  PHACO_REQUIRE_ENVIRONMENT(shell("command -v xvfb-run").code == 0,
                            "xvfb-run not found (scripts/install-deps.sh installs xvfb)");
  const fs::path dir = temp_dir("trainer-procedure");
  const fs::path scenarios = fs::path(PHACO_SOURCE_DIR) / "data/scenarios";
  write_text(dir / "p.json",
             R"({"name": "short", "level": 0, "steps": [{"scenario": ")" +
                 (scenarios / "corneal_incision_expert.json").string() + R"("}, {"scenario": ")" +
                 (scenarios / "capsulorhexis_expert.json").string() + R"(", "duration_s": 1.0}]})");
  // Under ASan, Mesa's llvmpipe keeps allocations to process exit that LeakSanitizer would report
  // as the trainer's (as for the display tests, tests/CMakeLists.txt): its exit code would be 1.
  const std::string leaks = phaco::test::kUnderAsan ? "ASAN_OPTIONS=detect_leaks=0 " : "";
  const auto r =
      shell(leaks + "xvfb-run -a -s '-screen 0 1280x720x24' " + std::string(PHACO_TRAINER_BIN) +
            " --procedure " + (dir / "p.json").string() + " --procedure-out " +
            (dir / "rec").string() + " --left track --right track --size 960x600 --stats " +
            (dir / "stats.json").string() + " --stats-after 3600");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("procedure: step 1 corneal_incision scored"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("procedure: step 2 capsulorhexis scored"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("procedure: total"), std::string::npos) << r.output;

  const nlohmann::json live = nlohmann::json::parse(read_text(dir / "rec/report.json"));
  const auto replay =
      shell(std::string(PHACO_BIN) + " run " + (dir / "rec/procedure.json").string() + " --json");
  ASSERT_EQ(replay.code, 0) << replay.output;
  const nlohmann::json again = nlohmann::json::parse(replay.output);
  ASSERT_EQ(live["steps"].size(), 2u);
  ASSERT_EQ(again["steps"].size(), 2u);
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(live["steps"][i]["state_hash"], again["steps"][i]["state_hash"]) << i;
    EXPECT_EQ(live["steps"][i]["metrics"]["score"], again["steps"][i]["metrics"]["score"]) << i;
  }
  EXPECT_TRUE(again["steps"][1]["carried_in"].contains("main_port"));
  EXPECT_EQ(live["total"], again["total"]);

  // --stats over a procedure (phaco-perf trainer): written at its end, over every step.
  const nlohmann::json stats = nlohmann::json::parse(read_text(dir / "stats.json"));
  ASSERT_EQ(stats["steps"].size(), 2u) << stats.dump();
  uint64_t frames = 0;
  for (size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(stats["steps"][i]["drill"], live["steps"][i]["drill"]) << i;
    EXPECT_EQ(stats["steps"][i]["sim_frames"], live["steps"][i]["frames"]) << i;
    frames += stats["steps"][i]["sim_frames"].get<uint64_t>();
    // Why a haptic period ran long, per step: the loop's own figures, the period's as above.
    // No speed is judged here: each part must be there, its summary's order p50 ≤ p99 ≤ max
    // (a field written under the wrong name breaks it), and the overruns a count.
    const nlohmann::json& loop = stats["steps"][i].at("haptic_loop");
    EXPECT_EQ(loop.at("period").at("p99_us"), stats["steps"][i]["haptic_period_p99_us"]) << i;
    for (const char* part : {"lateness", "compute", "spin"}) {
      const nlohmann::json& d = loop.at(part);
      EXPECT_LE(d.at("p50_us").get<double>(), d.at("p99_us").get<double>()) << part;
      EXPECT_LE(d.at("p99_us").get<double>(), d.at("max_us").get<double>()) << part;
    }
    EXPECT_TRUE(loop.at("overruns").is_number_integer()) << i;
  }
  EXPECT_EQ(stats["sim_frames"], frames);
  EXPECT_GT(stats["frames"].get<uint64_t>(), 0u) << "render frames";
}

}  // namespace
