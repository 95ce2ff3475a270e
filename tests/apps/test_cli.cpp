// The `phaco` executable as a user meets it: exit codes 0 / 2 / 1 and messages that name the
// problem.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/apps/cli.hpp"

namespace {

namespace fs = std::filesystem;
using phaco::test::phaco;
using phaco::test::read_text;
using phaco::test::temp_dir;
using phaco::test::write_text;

using Result = phaco::test::ShellResult;

fs::path write_text(const fs::path& dir, const std::string& name, const std::string& text) {
  std::ofstream(dir / name) << text;
  return dir / name;
}

const std::string kSmall =
    R"({ "drill": "capsulorhexis", "eye": { "level": 0 }, "dt_s": 0.01, "duration_s": 0.2,
  "hands": { "right": { "tool": "cystotome", "track": [ { "t": 0, "pos": [0, 0, 3.5], "quat": [1, 0, 0, 0] },
                                                      { "t": 0.2, "pos": [0, 0, 2], "quat": [1, 0, 0, 0] } ] } } })";

TEST(Cli, HelpAndVersionSucceed) {
  const Result help = phaco("--help");
  EXPECT_EQ(help.code, 0);
  EXPECT_NE(help.output.find("phaco run FILE"), std::string::npos);
  EXPECT_EQ(phaco("run --help").code, 0);
  EXPECT_EQ(phaco("--version").code, 0);
}

TEST(Cli, UsageErrorsAreBadInput) {
  EXPECT_EQ(phaco("").code, 2);
  const Result unknown = phaco("frobnicate");
  EXPECT_EQ(unknown.code, 2);
  EXPECT_NE(unknown.output.find("unknown command 'frobnicate'"), std::string::npos);
  EXPECT_EQ(phaco("run").code, 2);
  const Result opt = phaco("run x.json --fast");
  EXPECT_EQ(opt.code, 2);
  EXPECT_NE(opt.output.find("unknown option '--fast'"), std::string::npos);
  EXPECT_EQ(phaco("mesh --level 9 --out /tmp/x").code, 2);
  EXPECT_EQ(phaco("mesh --level 1").code, 2) << "--out is required";
}

TEST(Cli, ValidateNamesFileAndField) {
  const fs::path dir = temp_dir("validate");
  const fs::path good = write_text(dir, "good.json", kSmall);
  std::string bad_text = kSmall;
  bad_text.replace(bad_text.find("capsulorhexis"), 13, "capsulotomy");
  const fs::path bad = write_text(dir, "bad.json", bad_text);
  EXPECT_EQ(phaco("validate " + good.string()).code, 0);
  const Result r = phaco("validate " + good.string() + " " + bad.string());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.json: drill: unknown drill 'capsulotomy'"), std::string::npos)
      << r.output;
  const Result missing = phaco("validate " + (dir / "nope.json").string());
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.output.find("nope.json"), std::string::npos);
  fs::remove_all(dir);
}

// Issue 18 item 1: validate checks what run reads before its meshes (the drill file, the tools it
// allows, the eye overrides in their ranges, the eye's geometry) and the workspace, so a file it
// accepts is one run does not refuse; each refusal names the file and the field (exit 2).
TEST(Cli, ValidateChecksWhatRunReadsAndTheBounds) {
  const fs::path dir = temp_dir("validate_bounds");
  auto with = [&](const std::string& name, const std::string& from, const std::string& to) {
    std::string text = kSmall;
    text.replace(text.find(from), from.size(), to);
    return write_text(dir, name, text);
  };
  const struct {
    fs::path file;
    const char* message;
  } cases[] = {
      {with("far.json", "[0, 0, 2]", "[0, 0, 1e300]"),
       "far.json: hands.right.track[1].pos[2]: expected a coordinate in -50..50 mm"},
      {with("stiff.json", "\"level\": 0 }",
            "\"level\": 0, \"overrides\": { \"capsule.youngs_modulus_kpa\": 1e9 } }"),
       "stiff.json: eye.overrides[\"capsule.youngs_modulus_kpa\"]: expected a number in "
       "100..20000"},
      {with("wide.json", "\"level\": 0 }",
            "\"level\": 0, \"overrides\": { \"capsule.radius_mm\": 5.5 } }"),
       "wide.json: eye: inconsistent eye parameters: capsule.radius_mm"},
      {with("tool.json", "\"cystotome\"", "\"phaco_probe\""),
       "tool.json: hands.right.tool: the capsulorhexis drill"},
  };
  for (const auto& c : cases) {
    const Result r = phaco("validate " + c.file.string());
    EXPECT_EQ(r.code, 2) << c.file << ": " << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << r.output;
  }
  const Result edge = phaco("validate " + with("edge.json", "[0, 0, 2]", "[0, 0, 50]").string());
  EXPECT_EQ(edge.code, 0) << edge.output;
  fs::remove_all(dir);
}

TEST(Cli, RunWritesReportAndIsThreadIndependent) {
  const fs::path dir = temp_dir("run");
  const fs::path scen = write_text(dir, "small.json", kSmall);
  const std::string cache = " --cache-dir " + (dir / "cache").string();
  const Result one =
      phaco("run " + scen.string() + " --threads 1 --report " + (dir / "r1.json").string() + cache);
  ASSERT_EQ(one.code, 0) << one.output;
  const Result two =
      phaco("run " + scen.string() + " --threads 2 --report " + (dir / "r2.json").string() + cache);
  ASSERT_EQ(two.code, 0) << two.output;
  const auto r1 = nlohmann::json::parse(std::ifstream(dir / "r1.json"));
  const auto r2 = nlohmann::json::parse(std::ifstream(dir / "r2.json"));
  EXPECT_EQ(r1["frames"], 20);
  EXPECT_EQ(r1["threads"], 1);
  EXPECT_EQ(r2["threads"], 2);
  EXPECT_EQ(r1["state_hash"], r2["state_hash"]);
  const Result json = phaco("run " + scen.string() + " --json" + cache);
  ASSERT_EQ(json.code, 0);
  EXPECT_EQ(nlohmann::json::parse(json.output)["state_hash"], r1["state_hash"]);
  EXPECT_EQ(phaco("run " + scen.string() + " --threads 0" + cache).code, 2);
  EXPECT_EQ(phaco("run " + scen.string() + " --threads many" + cache).code, 2);
  const Result unwritable =
      phaco("run " + scen.string() + " --report /nonexistent-dir/r.json" + cache);
  EXPECT_EQ(unwritable.code, 2);
  EXPECT_NE(unwritable.output.find("/nonexistent-dir/r.json"), std::string::npos);
  fs::remove_all(dir);
}

TEST(Cli, RunRejectsBadScenarioWithExitTwo) {
  const fs::path dir = temp_dir("runbad");
  std::string text = kSmall;
  text.replace(text.find("\"t\": 0.2"), 8, "\"t\": -1.0");
  const fs::path scen = write_text(dir, "unsorted.json", text);
  const Result r = phaco("run " + scen.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("unsorted.json: hands.right.track[1].t"), std::string::npos) << r.output;
  fs::remove_all(dir);
}

TEST(Cli, MeshWritesEveryBody) {
  const fs::path dir = temp_dir("mesh");
  const Result r = phaco("mesh --level 0 --out " + dir.string());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"cornea.obj", "capsule.obj", "iris.obj", "globe.obj", "lens_surface.obj",
                        "lens.node", "lens.ele"}) {
    EXPECT_TRUE(fs::exists(dir / f)) << f;
    EXPECT_GT(fs::file_size(dir / f), 100u) << f;
  }
  fs::remove_all(dir);
}

TEST(Cli, GraphPrintsDot) {
  const fs::path dir = temp_dir("graph");
  const fs::path scen = write_text(dir, "small.json", kSmall);
  const Result r = phaco("graph " + scen.string() + " --cache-dir " + (dir / "cache").string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("digraph"), std::string::npos);
  EXPECT_NE(r.output.find("move_tools"), std::string::npos);
  EXPECT_NE(r.output.find("apply_commands"), std::string::npos);
  fs::remove_all(dir);
}

}  // namespace
