// The cohort page (issue 21 item 4): one curve per trainee and drill, pass rates from the pass
// line, the weakest metrics from the score terms, markup escaped; and the page as headless
// Chromium renders it: its DOM has the curves and its pixels show them in their colours.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "procedures/report/cohort_dashboard.hpp"
#include "tests/support/environment.hpp"
#include "tests/support/shell.hpp"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using phaco::report::CohortAttempt;

size_t count_in(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

json terms(double rhexis_lost, double centring_lost) {
  return json::array(
      {{{"metric", "rhexis.diameter_mm"}, {"weight", 20}, {"points", 20 - rhexis_lost}},
       {{"metric", "rhexis.centering_mm"}, {"weight", 15}, {"points", 15 - centring_lost}}});
}

std::vector<CohortAttempt> cohort() {
  std::vector<CohortAttempt> a;
  // Ana improves past the line; Ben stays below it and keeps missing the centring; Zoe <Eve> has
  // one unscored attempt and one incision.
  for (int i = 0; i < 4; ++i)
    a.push_back({"Ana", "capsulorhexis", "2026-11-0" + std::to_string(i + 1) + "T10:00:00.000Z",
                 60.0 + 10 * i, terms(4 - i, 0)});
  for (int i = 0; i < 3; ++i)
    a.push_back({"Ben", "capsulorhexis", "2026-11-0" + std::to_string(i + 1) + "T11:00:00.000Z",
                 50.0 + i, terms(0, 12)});
  a.push_back({"Zoe <Eve>", "capsulorhexis", "2026-11-02T09:00:00.000Z", std::nullopt, json()});
  a.push_back({"Zoe <Eve>", "corneal_incision", "2026-11-03T09:00:00.000Z", 88.0, json()});
  return a;
}

TEST(CohortDashboard, OneCurvePerTraineeAndDrillWithPassRatesAndWeakestMetrics) {
  phaco::report::CohortOptions o;
  o.title = "Residents 2026";
  const std::string page = phaco::report::cohort_dashboard(cohort(), o);
  EXPECT_EQ(page.rfind("<!DOCTYPE html>", 0), 0u);
  // Ana and Ben in capsulorhexis, <Eve> in incision (her unscored rhexis draws no line).
  EXPECT_EQ(count_in(page, "class=\"curve\""), 3u) << page;
  EXPECT_NE(page.find("data-trainee=\"Ana\" data-drill=\"capsulorhexis\""), std::string::npos);
  EXPECT_NE(page.find("data-trainee=\"Zoe &lt;Eve&gt;\" data-drill=\"corneal_incision\""),
            std::string::npos);
  EXPECT_EQ(page.find("Zoe <Eve>"), std::string::npos) << "markup in a name must be escaped";
  // Ana's latest (90) passes, Ben's (52) does not: 1 of 2; attempts 2 of 7 (80 and 90).
  EXPECT_NE(page.find("<td>capsulorhexis</td><td>3</td><td>1 of 2 (50 %)</td><td>7</td><td>29 %"),
            std::string::npos)
      << page;
  // Ben's weakest: centring, 12 points lost on average; Ana's: the diameter, 2.5 on average.
  EXPECT_NE(page.find("capsulorhexis: rhexis.centering_mm (12.0)"), std::string::npos);
  EXPECT_NE(page.find("capsulorhexis: rhexis.diameter_mm (2.5)"), std::string::npos);
  EXPECT_NE(page.find("class=\"pass\""), std::string::npos);
  EXPECT_EQ(page.find("<script"), std::string::npos);
  // No records: a page that says so.
  EXPECT_NE(phaco::report::cohort_dashboard({}, o).find("No records yet"), std::string::npos);
}

std::string find_chromium() {
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    const auto r = phaco::test::shell(std::string("command -v ") + name);
    if (r.code == 0 && !r.output.empty()) return name;
  }
  return {};
}

TEST(CohortDashboard, HeadlessChromiumShowsACurvePerTrainee) {
  const std::string chromium = find_chromium();
  PHACO_REQUIRE_ENVIRONMENT(!chromium.empty(), "no Chromium (Debian package chromium)");
  const fs::path dir = fs::temp_directory_path() / ("phaco-cohort-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path page = dir / "cohort.html", shot = dir / "shot.png";
  std::ofstream(page) << phaco::report::cohort_dashboard(cohort(), {});
  const std::string flags =
      " --headless --no-sandbox --disable-gpu --disable-background-networking"
      " --disable-component-update --disable-sync --no-first-run"
      " --user-data-dir=" +
      (dir / "profile").string();
  const auto dom = phaco::test::shell("timeout 120 " + chromium + flags + " --dump-dom file://" +
                                      page.string() + " 2>/dev/null");
  // The browser's own parse of the page: three curves, each with its points.
  EXPECT_EQ(count_in(dom.output, "<polyline class=\"curve\""), 3u) << dom.output.substr(0, 2000);
  phaco::test::shell("timeout 120 " + chromium + flags + " --screenshot=" + shot.string() +
                     " --window-size=1000,1600 file://" + page.string());
  const cv::Mat img = cv::imread(shot.string(), cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty()) << "no screenshot";
  // Ana's curve is the palette's first colour (#4e79a7), Ben's the second (#f28e2b). Counted
  // below the legend (whose swatches have the same colours), where the charts are.
  size_t ana = 0, ben = 0;
  for (int y = 200; y < img.rows; ++y)
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b p = img.at<cv::Vec3b>(y, x);  // B, G, R
      if (std::abs(p[2] - 0x4e) < 24 && std::abs(p[1] - 0x79) < 24 && std::abs(p[0] - 0xa7) < 24)
        ++ana;
      if (std::abs(p[2] - 0xf2) < 24 && std::abs(p[1] - 0x8e) < 24 && std::abs(p[0] - 0x2b) < 24)
        ++ben;
    }
  std::printf("[ figures ] curve pixels: Ana %zu, Ben %zu\n", ana, ben);
  // A line across the chart, not its dots alone (four dots of radius 3.5 px are about 150 px).
  EXPECT_GT(ana, 600u);
  EXPECT_GT(ben, 600u);
  fs::remove_all(dir);
}

}  // namespace
