// The programs away from the source tree (issue 23): `--version` names the version, the revision
// and the data folder in use; a copy of `phaco` outside the build tree reads ../share/openphaco
// beside it and never the compile-time source data, even though that still exists; a run report
// names the build that made it. (scripts/check-package.sh does the same with the real package.)
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "tests/apps/cli.hpp"

namespace {

namespace fs = std::filesystem;
using phaco::test::read_text;
using phaco::test::shell;
using phaco::test::temp_dir;

// The version in the top-level CMakeLists.txt's project() line.
std::string project_version() {
  const std::string text = read_text(fs::path(PHACO_SOURCE_DIR) / "CMakeLists.txt");
  std::smatch m;
  if (!std::regex_search(text, m, std::regex(R"(project\(OpenPhaco VERSION ([0-9.]+))"))) return "";
  return m[1];
}

const std::regex kRevision("[0-9a-f]{12}(-dirty)?|unknown");

TEST(Install, VersionNamesRevisionAndData) {
  const std::string version = project_version();
  ASSERT_FALSE(version.empty());
  const std::string source_data = fs::weakly_canonical(fs::path(PHACO_SOURCE_DIR) / "data");
  for (const std::string program : {PHACO_BIN, PHACO_TRAINER_BIN}) {
    const auto r = shell("env -u PHACO_DATA_DIR " + program + " --version");
    ASSERT_EQ(r.code, 0) << r.output;
    std::smatch m;
    const std::string name = fs::path(program).filename();
    ASSERT_TRUE(
        std::regex_search(r.output, m, std::regex(name + " ([0-9.]+) \\(revision (\\S+)\\)")))
        << r.output;
    EXPECT_EQ(m[1], version);
    EXPECT_TRUE(std::regex_match(m[2].str(), kRevision)) << m[2];
    EXPECT_NE(r.output.find("data: " + source_data + " (build tree)"), std::string::npos)
        << r.output;
  }
  const auto env = shell("PHACO_DATA_DIR=/srv/phaco-data " + std::string(PHACO_BIN) + " --version");
  EXPECT_NE(env.output.find("data: /srv/phaco-data (PHACO_DATA_DIR)"), std::string::npos)
      << env.output;
}

TEST(Install, ACopyOutsideTheBuildTreeReadsShareBesideIt) {
  const fs::path root = fs::canonical(temp_dir("install"));  // as /proc/self/exe names it
  fs::create_directories(root / "bin");
  fs::copy_file(PHACO_BIN, root / "bin" / "phaco");
  const std::string phaco = "cd " + root.string() + " && env -u PHACO_DATA_DIR bin/phaco ";
  const fs::path scenario =
      fs::path(PHACO_SOURCE_DIR) / "data" / "scenarios" / "corneal_incision_expert.json";

  // No share/openphaco: the source data (still there) is not used; the error says where it looked.
  const auto none = shell(phaco + "validate " + scenario.string());
  EXPECT_EQ(none.code, 2) << none.output;
  EXPECT_NE(none.output.find((root / "share" / "openphaco").string()), std::string::npos)
      << none.output;
  EXPECT_NE(none.output.find("PHACO_DATA_DIR"), std::string::npos) << none.output;
  EXPECT_NE(shell(phaco + "--version").output.find("data: not found"), std::string::npos);

  const fs::path share = root / "share" / "openphaco";
  fs::create_directories(share);
  fs::copy(fs::path(PHACO_SOURCE_DIR) / "data", share, fs::copy_options::recursive);
  const auto version = shell(phaco + "--version");
  EXPECT_NE(
      version.output.find("data: " + (root / "share" / "openphaco").string() + " (installed)"),
      std::string::npos)
      << version.output;
  const auto ok = shell(phaco + "validate " + (share / "scenarios" / scenario.filename()).string());
  EXPECT_EQ(ok.code, 0) << ok.output;
  fs::remove_all(root);
}

TEST(Install, ARunReportNamesTheBuildThatMadeIt) {
  const fs::path dir = temp_dir("software");
  std::ofstream(dir / "s.json") << R"({ "drill": "capsulorhexis", "eye": { "level": 0 },
    "dt_s": 0.01, "duration_s": 0.05, "hands": { "right": { "tool": "cystotome", "track": [
    { "t": 0, "pos": [0, 0, 3.5], "quat": [1, 0, 0, 0] },
    { "t": 0.05, "pos": [0, 0, 3.4], "quat": [1, 0, 0, 0] } ] } } })";
  const auto r = phaco::test::phaco("run " + (dir / "s.json").string() + " --report " +
                                    (dir / "r.json").string());
  ASSERT_EQ(r.code, 0) << r.output;
  const auto report = nlohmann::json::parse(read_text(dir / "r.json"));
  ASSERT_TRUE(report.contains("software")) << report.dump().substr(0, 200);
  EXPECT_EQ(report["software"]["name"], "OpenPhaco");
  EXPECT_EQ(report["software"]["version"], project_version());
  EXPECT_TRUE(std::regex_match(report["software"]["revision"].get<std::string>(), kRevision));
  // The page's footer names it too.
  const auto page = phaco::test::phaco("report " + (dir / "r.json").string() + " --html " +
                                       (dir / "r.html").string());
  ASSERT_EQ(page.code, 0) << page.output;
  const std::string run_by = "a run of OpenPhaco " + project_version() + " (revision " +
                             report["software"]["revision"].get<std::string>() + ")";
  EXPECT_NE(read_text(dir / "r.html").find(run_by), std::string::npos) << run_by;
  fs::remove_all(dir);
}

}  // namespace
