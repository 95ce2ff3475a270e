// `phaco report RUN.json --html OUT.html` as a user meets it, and the page as a real browser draws
// it: headless Chromium takes a screenshot of the written file, which must decode, not be blank,
// and show the score box apart from the page background.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "tests/apps/cli.hpp"

namespace {

namespace fs = std::filesystem;
using phaco::test::phaco;
using phaco::test::read_text;
using phaco::test::temp_dir;
using phaco::test::write_text;

using Result = phaco::test::ShellResult;
using phaco::test::shell;

const fs::path kFixture = fs::path(PHACO_SOURCE_DIR) / "tests/apps/data/report_fixture.json";

// Debian's package installs /usr/bin/chromium; other systems name it differently.
std::string find_chromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    const Result r = shell(std::string("command -v ") + name);
    if (r.code == 0 && !r.output.empty()) return r.output.substr(0, r.output.find('\n'));
  }
  return {};
}

TEST(ReportCli, WritesTheHtmlPage) {
  const fs::path dir = temp_dir("write");
  const fs::path out = dir / "out.html";
  const Result r = phaco("report " + kFixture.string() + " --html " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(out));
  const std::string html = read_text(out);
  EXPECT_NE(html.find(">90<small>/100</small>"), std::string::npos);
  size_t images = 0;
  for (size_t at = html.find("data:image/png;base64,"); at != std::string::npos;
       at = html.find("data:image/png;base64,", at + 1))
    ++images;
  EXPECT_EQ(images, 7u);
  EXPECT_EQ(html.find("http"), std::string::npos);
  fs::remove_all(dir);
}

TEST(ReportCli, BadInputIsExitTwoNamingFileAndField) {
  const fs::path dir = temp_dir("bad");
  EXPECT_EQ(phaco("report " + kFixture.string()).code, 2) << "--html is required";
  EXPECT_EQ(phaco("report --html x.html").code, 2) << "the run report is required";
  EXPECT_EQ(phaco("report " + kFixture.string() + " --html x.html --pdf").code, 2);

  const Result missing =
      phaco("report " + (dir / "nope.json").string() + " --html " + (dir / "o.html").string());
  EXPECT_EQ(missing.code, 2);
  EXPECT_NE(missing.output.find("nope.json: cannot open"), std::string::npos) << missing.output;

  std::ofstream(dir / "garbage.json") << "{ not json";
  const Result garbage =
      phaco("report " + (dir / "garbage.json").string() + " --html " + (dir / "o.html").string());
  EXPECT_EQ(garbage.code, 2);
  EXPECT_NE(garbage.output.find("garbage.json: not valid JSON"), std::string::npos)
      << garbage.output;

  std::ifstream f(kFixture);
  nlohmann::json run = nlohmann::json::parse(f);
  run["series"]["hands"]["left"]["force_mN"] = "strong";
  std::ofstream(dir / "RUN.json") << run.dump();
  const Result typed =
      phaco("report " + (dir / "RUN.json").string() + " --html " + (dir / "o.html").string());
  EXPECT_EQ(typed.code, 2);
  EXPECT_NE(typed.output.find("RUN.json: series.hands.left.force_mN: expected an array of numbers"),
            std::string::npos)
      << typed.output;
  EXPECT_FALSE(fs::exists(dir / "o.html")) << "nothing written on bad input";
  fs::remove_all(dir);
}

TEST(ReportCli, HeadlessChromiumRendersThePage) {
  const std::string chromium = find_chromium();
  ASSERT_FALSE(chromium.empty())
      << "Chromium is not installed: run scripts/install-deps.sh (it installs Debian's "
         "'chromium' package; CI does)";
  const fs::path dir = temp_dir("chromium");
  const fs::path out = dir / "out.html", shot = dir / "shot.png";
  const Result r = phaco("report " + kFixture.string() + " --html " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;

  // The flags keep Chromium off the network (closed on CI machines) and out of the user's profile.
  const Result browser = shell("timeout 120 " + chromium +
                               " --headless --no-sandbox --disable-gpu "
                               "--disable-background-networking --disable-component-update"
                               " --disable-sync --no-first-run --user-data-dir=" +
                               (dir / "profile").string() + " --screenshot=" + shot.string() +
                               " --window-size=1200,2000 file://" + out.string());
  ASSERT_TRUE(fs::exists(shot)) << "no screenshot; chromium said:\n" << browser.output;
  const cv::Mat img = cv::imread(shot.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << "the screenshot does not decode";
  EXPECT_EQ(img.cols, 1200);
  EXPECT_EQ(img.rows, 2000);

  // Not blank: text, tables and charts put a good share of non-white pixels on the page.
  size_t ink = 0, score_green = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);  // B, G, R
      if (p[0] < 235 || p[1] < 235 || p[2] < 235) ++ink;
      // The score box of a good score is #2e7d32 (R 46, G 125, B 50) behind white digits.
      if (std::abs(p[2] - 46) < 20 && std::abs(p[1] - 125) < 20 && std::abs(p[0] - 50) < 20)
        ++score_green;
    }
  }
  EXPECT_GT(ink, img.total() / 20) << "the page looks blank";
  // The score region differs from the white background: the box is about 250 × 130 px.
  EXPECT_GT(score_green, 10000u) << "the score box is not drawn";
  fs::remove_all(dir);
}

}  // namespace
