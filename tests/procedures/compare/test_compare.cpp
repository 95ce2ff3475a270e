// compare_reports on synthetic run reports whose answer is known: identical runs differ by
// nothing; the same path played slower aligns to ≈ 0 mm while equal-time differences do not; a
// path moved 0.5 mm out of its plane is 0.5 mm away after alignment; malformed reports name the
// file and the field.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <numbers>

#include "engine/core/error.hpp"
#include "procedures/compare/compare.hpp"
#include "procedures/report/compare_section.hpp"

namespace {

using nlohmann::json;
using phaco::compare::compare_reports;
using phaco::compare::Comparison;

// A tool tip going once round a 2.5 mm circle in the x-y plane (the rhexis plane), at depth z,
// u ∈ [0, 1] the fraction of the path done.
json circle(double u, double z) {
  const double a = 2 * std::numbers::pi * u;
  return json::array({2.5 * std::cos(a), 2.5 * std::sin(a), z});
}

// A report of `n` samples over `duration` s, both hands on the circle (left offset in x), speed
// and force functions of the path fraction u.
json report(size_t n, double duration, double z = 3.5, const std::string& drill = "capsulorhexis") {
  json t = json::array(), hands = json::object();
  for (const char* hand : {"left", "right"}) {
    json pos = json::array(), speed = json::array(), force = json::array();
    const double dx = std::string(hand) == "left" ? -1.0 : 0.0;
    for (size_t k = 0; k < n; ++k) {
      const double u = static_cast<double>(k) / static_cast<double>(n - 1);
      json p = circle(u, z);
      p[0] = p[0].get<double>() + dx;
      pos.push_back(p);
      speed.push_back(2 * std::numbers::pi * 2.5 / duration);
      force.push_back(10 + 5 * std::sin(std::numbers::pi * u));  // mN, a bump mid-path
    }
    hands[hand] = {
        {"tool", "forceps"}, {"pos_mm", pos}, {"speed_mm_s", speed}, {"force_mN", force}};
  }
  for (size_t k = 0; k < n; ++k) t.push_back(duration * static_cast<double>(k) / (n - 1.0));
  return {
      {"drill", drill},
      {"series", {{"t_s", t}, {"hands", hands}}},
      {"metrics", {{"time_s", duration}, {"rhexis.diameter_mm", 5.0}, {"rhexis.complete", true}}}};
}

TEST(Compare, IdenticalReportsDifferByNothing) {
  const json r = report(300, 10);
  const Comparison c = compare_reports(r, r, "run.json", "expert.json");
  EXPECT_EQ(c.drill, "capsulorhexis");
  EXPECT_DOUBLE_EQ(c.time_ratio, 1.0);
  ASSERT_EQ(c.hands.size(), 2u);
  EXPECT_EQ(c.hands[0].hand, "left");
  for (const auto& h : c.hands) {
    EXPECT_EQ(h.path_distance_mm.max, 0.0);
    EXPECT_EQ(h.speed_diff_mm_s.rms, 0.0);
    EXPECT_EQ(h.force_diff_mN.rms, 0.0);
    EXPECT_EQ(h.plain_path_distance_mm.max, 0.0);
    ASSERT_EQ(h.distance_mm.size(), 300u);
    for (size_t i = 0; i < h.t_s.size(); ++i) EXPECT_DOUBLE_EQ(h.expert_t_s[i], h.t_s[i]);
  }
  ASSERT_EQ(c.metrics.size(), 3u);
  for (const auto& m : c.metrics) EXPECT_EQ(m.difference, 0.0) << m.name;
}

TEST(Compare, SlowerCopyOfTheSamePathAlignsToZeroDistance) {
  // The expert goes round in 10 s with 400 samples; the run, the same circle in 15 s, 600 samples.
  const json expert = report(400, 10), run = report(600, 15);
  const Comparison c = compare_reports(run, expert, "run.json", "expert.json");
  EXPECT_NEAR(c.time_ratio, 1.5, 1e-12);
  for (const auto& h : c.hands) {
    // Expert samples are 2π·2.5/399 ≈ 0.039 mm apart: alignment is off by at most half of that.
    EXPECT_LT(h.path_distance_mm.mean, 0.02) << h.hand;
    EXPECT_LT(h.path_distance_mm.max, 0.03) << h.hand;
    // At equal times the run is a third of a turn behind at the expert's end: millimetres apart.
    EXPECT_GT(h.plain_path_distance_mm.mean, 1.0) << h.hand;
    // Aligned force bumps coincide; at equal times they do not.
    EXPECT_LT(h.force_diff_mN.rms, 0.1) << h.hand;
    EXPECT_GT(h.plain_force_diff_mN.rms, 1.0) << h.hand;
    // The run is slower: its speed is 2/3 of the expert's.
    EXPECT_NEAR(h.speed_diff_mm_s.mean, 2 * std::numbers::pi * 2.5 * (1 / 15.0 - 1 / 10.0), 1e-9);
    // The matched expert time runs at 10/15 of the run's.
    EXPECT_NEAR(h.expert_t_s.back(), 10.0, 1e-9);
    EXPECT_NEAR(h.expert_t_s[300], 5.0, 0.05);  // half way round at 7.5 s and 5 s
  }
  EXPECT_NEAR(c.metrics[0].difference, 0.0, 1e-12);  // rhexis.complete
  bool saw_time = false;
  for (const auto& m : c.metrics) {
    if (m.name != "time_s") continue;
    saw_time = true;
    EXPECT_DOUBLE_EQ(m.difference, 5.0);
  }
  EXPECT_TRUE(saw_time);
}

TEST(Compare, PathMovedHalfAMillimetreIsHalfAMillimetreAway) {
  // Moved along z, normal to the circle's plane, so no warping can bring it closer than 0.5 mm.
  const json expert = report(500, 10, 3.5), run = report(500, 10, 4.0);
  const Comparison c = compare_reports(run, expert, "run.json", "expert.json");
  for (const auto& h : c.hands) {
    EXPECT_NEAR(h.path_distance_mm.mean, 0.5, 1e-6) << h.hand;
    EXPECT_NEAR(h.path_distance_mm.max, 0.5, 1e-6) << h.hand;
  }
}

TEST(Compare, WarpingPathIsMonotoneFromStartToEnd) {
  std::vector<double> a, b;
  for (int k = 0; k < 50; ++k) a.insert(a.end(), {k * 0.1, 0.0, 0.0});
  for (int k = 0; k < 120; ++k) b.insert(b.end(), {k * 0.05, 0.0, 0.0});
  const auto path = phaco::compare::dtw_path(a, b, 5);
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(path.front(), std::make_pair(size_t{0}, size_t{0}));
  EXPECT_EQ(path.back(), std::make_pair(size_t{49}, size_t{119}));
  for (size_t k = 1; k < path.size(); ++k) {
    const auto di = path[k].first - path[k - 1].first, dj = path[k].second - path[k - 1].second;
    EXPECT_TRUE(di <= 1 && dj <= 1 && di + dj >= 1) << k;
  }
  EXPECT_THROW(phaco::compare::dtw_path({}, b, 5), std::invalid_argument);
}

// The InputError's message, or "" when none was thrown.
std::string error_of(const json& run, const json& expert) {
  try {
    compare_reports(run, expert, "run.json", "expert.json");
  } catch (const phaco::InputError& e) {
    return e.what();
  }
  return {};
}

TEST(Compare, MalformedReportsNameTheFileAndTheField) {
  const json good = report(50, 2);
  auto expect = [&](const json& run, const json& expert, const std::string& file,
                    const std::string& field) {
    const std::string m = error_of(run, expert);
    EXPECT_NE(m.find(file + ": "), std::string::npos) << m;
    EXPECT_NE(m.find(field), std::string::npos) << m;
  };
  json r = good;
  r.erase("series");
  expect(r, good, "run.json", "series: missing");
  r = good;
  r["series"]["hands"]["right"]["force_mN"][2] = "strong";
  expect(good, r, "expert.json", "series.hands.right.force_mN[2]: expected a number");
  r = good;
  r["series"]["hands"]["left"]["pos_mm"][3] = json::array({1.0, 2.0});
  expect(r, good, "run.json", "series.hands.left.pos_mm[3]");
  r = good;
  r["series"]["hands"]["left"]["speed_mm_s"].erase(0);
  expect(r, good, "run.json", "series.hands.left.speed_mm_s");
  r = good;
  r["series"]["hands"].erase("left");
  expect(r, good, "run.json", "series.hands.left: missing");
  r = good;
  r["series"]["t_s"] = "soon";
  expect(r, good, "run.json", "series.t_s: expected an array of numbers");
  r = good;
  r["metrics"]["time_s"] = "two";
  expect(r, good, "run.json", "metrics.time_s: expected a number");
  r = good;
  r.erase("metrics");
  expect(good, r, "expert.json", "metrics: missing");
  expect(good, report(50, 2, 3.5, "phaco_sculpting"), "run.json", "drill");
  expect(json::array(), good, "run.json", "expected a run report object");
}

TEST(Compare, JsonCarriesFiguresAndAlignedSeries) {
  const json expert = report(100, 10), run = report(150, 15);
  const Comparison c = compare_reports(run, expert, "run.json", "expert.json");
  const json j = phaco::compare::to_json(c);
  EXPECT_EQ(j["drill"], "capsulorhexis");
  EXPECT_NEAR(j["time"]["ratio"].get<double>(), 1.5, 1e-12);
  EXPECT_EQ(j["hands"]["right"]["series"]["path_distance_mm"].size(), 150u);
  EXPECT_EQ(j["hands"]["right"]["series"]["force_diff_mN"].size(), 150u);
  EXPECT_TRUE(j["hands"]["left"]["aligned"]["path_distance_mm"].contains("mean"));
  EXPECT_DOUBLE_EQ(j["metrics"]["time_s"]["difference"].get<double>(), 5.0);
  const std::string text = phaco::compare::summary_text(c);
  EXPECT_NE(text.find("ratio 1.500"), std::string::npos) << text;
  EXPECT_NE(text.find("time_s"), std::string::npos) << text;
}

TEST(CompareSection, HasHeadingTablesAndOneInlinedPlot) {
  const Comparison c =
      compare_reports(report(120, 12), report(100, 10), "run.json", "ex<pert>.json");
  const std::string html = phaco::report::compare_section(c);
  EXPECT_NE(html.find("<section id=\"compare\">"), std::string::npos);
  EXPECT_NE(html.find("Compared with the expert"), std::string::npos);
  EXPECT_NE(html.find("ex&lt;pert&gt;.json"), std::string::npos);  // escaped
  size_t plots = 0;
  for (size_t p = html.find("data:image/png;base64,"); p != std::string::npos;
       p = html.find("data:image/png;base64,", p + 1))
    ++plots;
  EXPECT_EQ(plots, 1u);
  EXPECT_NE(html.find("rhexis.diameter_mm"), std::string::npos);
}

}  // namespace
