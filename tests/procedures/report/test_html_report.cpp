// The HTML run report (procedures/report/html_report.hpp): the page carries the score, every
// metric and one inlined PNG per plot the report's data allows; missing sections are skipped with
// a note; malformed fields are InputErrors that name the field.
#include <gtest/gtest.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "engine/core/error.hpp"
#include "procedures/report/html_report.hpp"

namespace {

using nlohmann::json;
using phaco::report::base64_encode;
using phaco::report::html_report;

json fixture() {
  std::ifstream f(std::string(PHACO_SOURCE_DIR) + "/tests/apps/data/report_fixture.json");
  return json::parse(f);
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size()))
    ++n;
  return n;
}

constexpr const char* kImage = "<img";
constexpr const char* kPng = "src=\"data:image/png;base64,";

std::vector<std::uint8_t> base64_decode(const std::string& s) {
  std::vector<std::uint8_t> out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    int v = -1;
    if (c >= 'A' && c <= 'Z')
      v = c - 'A';
    else if (c >= 'a' && c <= 'z')
      v = c - 'a' + 26;
    else if (c >= '0' && c <= '9')
      v = c - '0' + 52;
    else if (c == '+')
      v = 62;
    else if (c == '/')
      v = 63;
    else
      continue;  // padding
    acc = (acc << 6) | static_cast<uint32_t>(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(static_cast<std::uint8_t>((acc >> bits) & 0xFF));
    }
  }
  return out;
}

// The decoded images of the page, in order.
std::vector<cv::Mat> images(const std::string& html) {
  std::vector<cv::Mat> out;
  const std::string key = kPng;
  for (size_t at = html.find(key); at != std::string::npos; at = html.find(key, at + 1)) {
    const size_t begin = at + key.size(), end = html.find('"', begin);
    const std::vector<std::uint8_t> png = base64_decode(html.substr(begin, end - begin));
    out.push_back(cv::imdecode(png, cv::IMREAD_COLOR));
  }
  return out;
}

std::string expect_input_error(const json& run) {
  try {
    html_report(run);
  } catch (const phaco::InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return {};
}

TEST(HtmlReport, Base64MatchesRfc4648Vectors) {
  const auto enc = [](const std::string& s) {
    return base64_encode({reinterpret_cast<const std::uint8_t*>(s.data()), s.size()});
  };
  EXPECT_EQ(enc(""), "");
  EXPECT_EQ(enc("f"), "Zg==");
  EXPECT_EQ(enc("fo"), "Zm8=");
  EXPECT_EQ(enc("foo"), "Zm9v");
  EXPECT_EQ(enc("foob"), "Zm9vYg==");
  EXPECT_EQ(enc("fooba"), "Zm9vYmE=");
  EXPECT_EQ(enc("foobar"), "Zm9vYmFy");
  const std::vector<std::uint8_t> all = {0x00, 0xFF, 0xFE, 0x80, 0x7F};
  EXPECT_EQ(base64_decode(base64_encode(all)), all);
}

TEST(HtmlReport, FixturePageShowsScoreMetricsEventsAndEveryPlot) {
  const json run = fixture();
  const std::string html = html_report(run);
  EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(html.find(">90<small>/100</small>"), std::string::npos) << "the score, large";
  EXPECT_NE(html.find("Capsulorhexis"), std::string::npos);
  EXPECT_NE(html.find("2026-11-02 09:30 UTC"), std::string::npos) << "the date";
  for (const auto& [name, value] : run["metrics"].items()) {
    EXPECT_NE(html.find("<td>" + name + "</td>"), std::string::npos) << name;
  }
  // The fixture meets 8 targets and misses one (a lens contact).
  EXPECT_NE(html.find("8 target(s) met, 1 missed."), std::string::npos);
  EXPECT_EQ(count(html, "<span class=\"missed\">missed</span>"), 1u);
  EXPECT_EQ(count(html, "<span class=\"met\">met</span>"), 8u);
  // Every score term and every event is listed.
  EXPECT_EQ(count(html, "<div class=\"bar\">"), run["score_terms"].size());
  EXPECT_NE(html.find("runout_warning"), std::string::npos);
  EXPECT_NE(html.find("tear_angle_deg 41"), std::string::npos);
  // One image per plot: force and speed over time and their distributions, two path views, rhexis.
  EXPECT_EQ(count(html, kImage), 7u);
  EXPECT_EQ(count(html, kPng), 7u);
  for (const char* id : {"force-time", "force-histogram", "speed-time", "speed-histogram",
                         "paths-top", "paths-side", "rhexis"}) {
    EXPECT_NE(html.find(std::string("id=\"plot-") + id + "\""), std::string::npos) << id;
  }
  // Self-contained: no external resource, no script.
  EXPECT_EQ(html.find("http"), std::string::npos);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  for (const cv::Mat& img : images(html)) {
    ASSERT_FALSE(img.empty()) << "an inlined PNG does not decode";
    EXPECT_GE(img.cols, 800);
    // A drawn chart, not a blank: a good share of non-white pixels.
    cv::Mat gray;
    cv::extractChannel(img, gray, 0);
    EXPECT_GT(img.total() - static_cast<size_t>(cv::countNonZero(gray == 255)), img.total() / 50);
  }
}

TEST(HtmlReport, PathPlotsAreSquareSoCirclesStayCircles) {
  const std::vector<cv::Mat> imgs = images(html_report(fixture()));
  ASSERT_EQ(imgs.size(), 7u);
  // paths-top, paths-side, rhexis: the chart library leaves a plot area 390 px narrower and 126 px
  // shorter than the image; equal axes need that area square.
  for (size_t i = 4; i < 7; ++i) EXPECT_EQ(imgs[i].cols - 390, imgs[i].rows - 126) << i;
}

TEST(HtmlReport, SculptingTrenchAddsTheTopViewPlot) {
  json run = fixture();
  run["drill"] = "phaco_sculpting";
  run["series"].erase("rhexis");
  json removed = json::array();
  for (int i = 0; i < 200; ++i) {
    const double s = -3.0 + 6.0 * i / 199.0;
    removed.push_back({s, 0.05 * (i % 7), 0.8 * (1 - std::abs(s) / 4)});  // the first trench
    removed.push_back({0.05 * (i % 5), s, 0.6 * (1 - std::abs(s) / 4)});  // the second, across
  }
  run["series"]["trench"] = {{"removed_xy_depth", removed}, {"nucleus_radius_mm", 3.3}};
  const std::string html = html_report(run);
  EXPECT_NE(html.find("id=\"plot-trench\""), std::string::npos);
  EXPECT_EQ(html.find("id=\"plot-rhexis\""), std::string::npos);
  EXPECT_EQ(count(html, kPng), 7u);
  EXPECT_NE(html.find("No rhexis outline"), std::string::npos) << "the skipped section says why";
}

TEST(HtmlReport, MissingSectionsAreLeftOutWithANote) {
  // Today's report (before issue 7's fields): no score, no targets, no series.
  const json old = {{"drill", "corneal_incision"},
                    {"scenario", "x.json"},
                    {"metrics", json::object()},
                    {"events", json::array()},
                    {"state_hash", "abc"}};
  const std::string html = html_report(old);
  EXPECT_NE(html.find("no score"), std::string::npos);
  EXPECT_NE(html.find("No series in this report"), std::string::npos);
  EXPECT_NE(html.find("No events."), std::string::npos);
  EXPECT_EQ(count(html, kPng), 0u);
  // An empty object still makes a page.
  EXPECT_NE(html_report(json::object()).find("date not recorded"), std::string::npos);

  json run = fixture();
  run["series"]["hands"].erase("right");
  EXPECT_EQ(count(html_report(run), kPng), 7u) << "one hand is enough for every hand plot";
  run["series"].erase("t_s");
  std::string page = html_report(run);
  EXPECT_EQ(count(page, kPng), 3u) << "without times: the two path views and the rhexis";
  EXPECT_NE(page.find("No sample times"), std::string::npos);
  run["series"]["hands"]["left"].erase("pos_mm");
  page = html_report(run);
  EXPECT_EQ(count(page, kPng), 1u);
  EXPECT_NE(page.find("no tool positions"), std::string::npos);
  run.erase("targets");
  run.erase("score_terms");
  page = html_report(run);
  EXPECT_NE(page.find("No targets in this report"), std::string::npos);
  EXPECT_NE(page.find("No per-term breakdown"), std::string::npos);
  EXPECT_EQ(page.find("class=\"met\""), std::string::npos);
}

// Issue 20 item 3: a complication and a step not attempted are said under the score.
TEST(HtmlReport, AFailedOrUnattemptedDrillSaysSo) {
  json run = fixture();
  EXPECT_EQ(html_report(run).find("FAILED"), std::string::npos);
  run["complications"] = {{{"name", "posterior capsule rupture"}, {"score_cap", 40}}};
  EXPECT_NE(html_report(run).find("FAILED: posterior capsule rupture"), std::string::npos);
  run["metrics"]["attempted"] = 0;
  EXPECT_NE(html_report(run).find("Not attempted"), std::string::npos);
  run["complications"] = 3;
  EXPECT_NE(expect_input_error(run).find("complications"), std::string::npos);
}

TEST(HtmlReport, SeriesOfUnequalLengthAreCutToTheShorterWithANote) {
  json run = fixture();
  auto& force = run["series"]["hands"]["left"]["force_mN"];
  force.erase(force.begin() + 100, force.end());
  const std::string html = html_report(run);
  EXPECT_NE(html.find("100 samples for 300 times; the first 100 drawn"), std::string::npos);
  EXPECT_EQ(count(html, kPng), 7u);
}

TEST(HtmlReport, VerdictsAtTheBoundsAndUnmeasuredTargets) {
  json run = {
      {"metrics",
       {{"rhexis.diameter_mm", 5.0}, {"rhexis.centering_mm", 0.41}, {"rhexis.complete", true}}},
      {"targets",
       {{"rhexis.diameter_mm", {{"min", 5.0}, {"max", 5.5}}},
        {"rhexis.centering_mm", {{"max", 0.4}}},
        {"rhexis.complete", {{"min", 1}}},
        {"trench.depth_fraction", {{"min", 0.7}, {"max", 0.9}}}}}};
  const std::string html = html_report(run);
  EXPECT_NE(html.find("2 target(s) met, 2 missed."), std::string::npos) << html;
  EXPECT_NE(html.find("not measured"), std::string::npos);
}

TEST(HtmlReport, TextFromTheFileIsEscaped) {
  json run = fixture();
  run["scenario"] = "<script>alert(1)</script>";
  run["events"].push_back({{"t_s", 1.0}, {"kind", "<b>odd</b>"}});
  const std::string html = html_report(run);
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("<b>odd"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
}

TEST(HtmlReport, MalformedFieldsAreInputErrorsNamingTheField) {
  EXPECT_NE(expect_input_error(json::array({1, 2})).find("expected a JSON object"),
            std::string::npos);
  EXPECT_NE(expect_input_error(json("text")).find("expected a JSON object"), std::string::npos);

  struct Case {
    json::json_pointer where;
    json value;
    std::string message;
  };
  const std::vector<Case> cases = {
      {json::json_pointer("/series/hands/left/force_mN"), "abc",
       "series.hands.left.force_mN: expected an array of numbers"},
      {json::json_pointer("/series/hands/left/force_mN"), json::array({1, "x"}),
       "series.hands.left.force_mN: expected an array of numbers"},
      {json::json_pointer("/series/hands/right/speed_mm_s"), nullptr,
       "series.hands.right.speed_mm_s: expected an array of numbers"},
      {json::json_pointer("/series/hands/left/pos_mm"), json::array({json::array({1, 2})}),
       "series.hands.left.pos_mm[0]: expected an array of [x, y, z] points"},
      {json::json_pointer("/series/hands/left/tool"), 3,
       "series.hands.left.tool: expected a string"},
      {json::json_pointer("/series/hands/left"), json::array(),
       "series.hands.left: expected an object"},
      {json::json_pointer("/series/t_s"), "now", "series.t_s: expected an array of numbers"},
      {json::json_pointer("/series/rhexis/outline_mm"), json::array({json::array({1, 2, 3})}),
       "series.rhexis.outline_mm[0]: expected an array of [x, y] points"},
      {json::json_pointer("/series/rhexis/target_diameter_mm"), json::array({5.0}),
       "series.rhexis.target_diameter_mm: expected two numbers"},
      {json::json_pointer("/series/trench"),
       json{{"removed_xy_depth", json::array({json::array({1, 2})})}},
       "series.trench.removed_xy_depth[0]: expected an array of [x, y, depth_fraction] points"},
      {json::json_pointer("/series/trench"), json{{"nucleus_radius_mm", "3"}},
       "series.trench.nucleus_radius_mm: expected a number"},
      {json::json_pointer("/series"), 7, "series: expected an object"},
      {json::json_pointer("/metrics"), 3, "metrics: expected an object"},
      {json::json_pointer("/metrics/score"), "high", "metrics.score: expected a number"},
      {json::json_pointer("/targets/rhexis.diameter_mm/min"), "5",
       "targets.rhexis.diameter_mm.min: expected a number"},
      {json::json_pointer("/targets/rhexis.diameter_mm"), 5,
       "targets.rhexis.diameter_mm: expected an object"},
      {json::json_pointer("/score_terms"), json::object(), "score_terms: expected an array"},
      {json::json_pointer("/score_terms/1/points"), "all",
       "score_terms[1].points: expected a number"},
      {json::json_pointer("/events"), "none", "events: expected an array"},
      {json::json_pointer("/events/2/t_s"), "soon", "events[2].t_s: expected a number"},
      {json::json_pointer("/events/2"), 4, "events[2]: expected an object"},
      {json::json_pointer("/drill"), 1, "drill: expected a string"},
  };
  for (const Case& c : cases) {
    json run = fixture();
    run[c.where] = c.value;
    const std::string message = expect_input_error(run);
    EXPECT_NE(message.find(c.message), std::string::npos)
        << c.where.to_string() << " gave: " << message;
  }
}

}  // namespace
