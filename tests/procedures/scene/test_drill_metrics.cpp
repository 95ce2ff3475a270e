// The drill's metrics in the running scene (procedures/scene/drill_metrics): the three demo
// scenarios give the metrics the scene's own summaries give, path lengths equal to the tracks'
// polylines at the frame times, a score in 0..100 whose terms follow docs/scoring.md, series
// within the contract, and the same figures for 1 and 2 threads. The demos run once each and are
// shared by the tests (a run is the expensive part).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <string>

#include "components/tool.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/metrics/metrics.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

struct DemoRun {
  std::unique_ptr<Scene> scene;
  DrillReport report;
};

// One run per (scenario, threads), kept for the whole executable.
DemoRun& demo(const char* name, int threads = 1) {
  static std::map<std::pair<std::string, int>, DemoRun> runs;
  auto& r = runs[{name, threads}];
  if (!r.scene) {
    r.scene = test::run_to_end(test::repo_scenario(name), threads);
    r.report = drill_report(*r.scene);
  }
  return r;
}

const nlohmann::json& term(const DrillReport& r, const std::string& metric) {
  for (const auto& t : r.score_terms)
    if (t["metric"] == metric) return t;
  static const nlohmann::json none;
  ADD_FAILURE() << "no score term for " << metric;
  return none;
}

// The track's polyline sampled at the frame times 0, dt, ..., N·dt (where the scene puts the tool).
double track_length_at_frames(const Scenario& s, const HandTrack& hand) {
  std::vector<Vec3> pts;
  const uint64_t frames = s.frame_count();
  for (uint64_t f = 0; f <= frames; ++f) {
    pts.push_back(sample_track(hand.track, static_cast<double>(f) * s.dt_s).pos);
  }
  return metrics::polyline_length(pts);
}

void expect_common_contract(const DemoRun& run) {
  const DrillReport& r = run.report;
  const Scenario& s = run.scene->scenario;
  ASSERT_TRUE(r.metrics.contains("score"));
  EXPECT_GE(r.score, 0.0);
  EXPECT_LE(r.score, 100.0);
  EXPECT_DOUBLE_EQ(r.metrics["score"].get<double>(), r.score);
  // The score is the sum of its terms, each within 0..weight; the weights add to 100 (no demo has
  // a complication, which would cap the sum, nor is idle).
  EXPECT_TRUE(r.complications.empty());
  EXPECT_TRUE(r.attempted);
  double sum = 0, weights = 0;
  for (const auto& t : r.score_terms) {
    EXPECT_GE(t["points"].get<double>(), 0.0);
    EXPECT_LE(t["points"].get<double>(), t["weight"].get<double>());
    sum += t["points"].get<double>(), weights += t["weight"].get<double>();
  }
  EXPECT_NEAR(sum, r.score, 1e-9);
  EXPECT_NEAR(weights, 100.0, 1e-9);
  EXPECT_NEAR(r.metrics["time_s"].get<double>(), s.duration_s, 1e-9);
  // Series: ≤ 2000 samples, first at 0 and last at the end, every hand the same length.
  const auto& t = r.series["t_s"];
  ASSERT_GE(t.size(), 2u);
  EXPECT_LE(t.size(), metrics::kMaxSeriesSamples);
  EXPECT_EQ(t.front().get<double>(), 0.0);
  EXPECT_NEAR(t.back().get<double>(), s.duration_s, 1e-9);
  for (const HandTrack& hand : s.hands) {
    const std::string name(to_string(hand.hand));
    const auto& h = r.series["hands"][name];
    EXPECT_EQ(h["tool"], std::string(to_string(hand.tool)));
    EXPECT_EQ(h["pos_mm"].size(), t.size());
    EXPECT_EQ(h["speed_mm_s"].size(), t.size());
    EXPECT_EQ(h["force_mN"].size(), t.size());
    // Path length: the track's polyline at the frame times; mean speed: that over the duration.
    const double length = track_length_at_frames(s, hand);
    EXPECT_NEAR(r.metrics[name + ".path_length_mm"].get<double>(), length, 1e-6) << name;
    EXPECT_NEAR(r.metrics[name + ".tool_speed_mm_s.mean"].get<double>(),
                length / (static_cast<double>(s.frame_count()) * s.dt_s), 1e-6)
        << name;
    EXPECT_GE(r.metrics[name + ".tool_speed_mm_s.max"].get<double>(),
              r.metrics[name + ".tool_speed_mm_s.mean"].get<double>());
    EXPECT_GE(r.metrics[name + ".contact_force_mN.max"].get<double>(),
              r.metrics[name + ".contact_force_mN.mean"].get<double>());
    EXPECT_GE(r.metrics[name + ".contact_force_mN.std"].get<double>(), 0.0);
    // The histograms hold every frame.
    uint64_t n = 0;
    for (const auto& c : h["speed_histogram"]["counts"]) n += c.get<uint64_t>();
    EXPECT_EQ(n, s.frame_count());
  }
  // Events in time order, each with a kind.
  double last = 0;
  for (const auto& e : r.events) {
    EXPECT_GE(e["t_s"].get<double>(), last);
    last = e["t_s"].get<double>();
    EXPECT_FALSE(e["kind"].get<std::string>().empty());
  }
}

size_t count_events(const DrillReport& r, const std::string& kind) {
  size_t n = 0;
  for (const auto& e : r.events) n += e["kind"] == kind;
  return n;
}

TEST(DrillMetrics, CapsulorhexisDemoMatchesTheSceneAndTheContract) {
  DemoRun& run = demo("capsulorhexis_demo.json");
  expect_common_contract(run);
  const DrillReport& r = run.report;
  const nlohmann::json cutting = capsule_cutting_summary(*run.scene);
  ASSERT_TRUE(cutting["opening_complete"].get<bool>());
  EXPECT_EQ(r.metrics["rhexis.complete"], 1);
  EXPECT_EQ(r.metrics["rhexis.diameter_mm"].get<double>(),
            cutting["opening_diameter_mm"].get<double>());
  EXPECT_EQ(r.metrics["rhexis.circularity"].get<double>(),
            cutting["opening_circularity"].get<double>());
  EXPECT_EQ(r.metrics["rhexis.centering_mm"].get<double>(),
            cutting["opening_centering_mm"].get<double>());
  EXPECT_EQ(r.metrics["rhexis.radial_tearouts"].get<uint64_t>(),
            cutting["radial_tearouts"].get<uint64_t>());
  EXPECT_EQ(r.metrics["runout_warnings"].get<uint64_t>(),
            cutting["runout_warnings"].get<uint64_t>());
  EXPECT_EQ(count_events(r, "radial_tearout"), cutting["radial_tearouts"].get<size_t>());
  // Grasps: the events and the capsule's own counters agree; regrasps = grasps − 1.
  const nlohmann::json capsule = capsule_physics_summary(*run.scene);
  EXPECT_EQ(count_events(r, "grasp"), capsule["grasps"].get<size_t>());
  EXPECT_EQ(count_events(r, "release"), capsule["releases"].get<size_t>());
  EXPECT_EQ(count_events(r, "missed_grasp"), capsule["missed_grasps"].get<size_t>());
  ASSERT_GE(capsule["grasps"].get<uint64_t>(), 1u);
  EXPECT_EQ(r.metrics["regrasps"].get<uint64_t>(), capsule["grasps"].get<uint64_t>() - 1);
  // The cystotome's puncture stays within its allowance: no lens hit.
  EXPECT_EQ(r.metrics["lens_contacts"], 0) << r.events.dump();
  // The flap pulls on the forceps while they hold it.
  EXPECT_GT(r.metrics["left.contact_force_mN.max"].get<double>(), 0.0);
  // Targets from the eye file; the demo's opening (5.09 mm since the held flap folds at the tear
  // resistance, issue 17 item 5; 4.93 mm before) is inside the band, so the diameter term scores in
  // full (the fall-off outside the band: ScoreTermsFollowTheBandRule).
  EXPECT_EQ(r.targets["rhexis.diameter_mm"]["min"].get<double>(), 5.0);
  EXPECT_EQ(r.targets["rhexis.diameter_mm"]["max"].get<double>(), 5.5);
  EXPECT_EQ(r.targets["rhexis.centering_mm"]["max"].get<double>(), 0.4);
  const double d = r.metrics["rhexis.diameter_mm"].get<double>();
  ASSERT_GE(d, 5.0);
  ASSERT_LE(d, 5.5);
  const auto& dt = term(r, "rhexis.diameter_mm");
  EXPECT_EQ(dt["points"].get<double>(), dt["weight"].get<double>());
  EXPECT_EQ(term(r, "rhexis.complete")["points"].get<double>(), 25.0);
  // The outline: the opening seen from above, about the measured diameter from the axis.
  const auto& outline = r.series["rhexis"]["outline_mm"];
  ASSERT_GE(outline.size(), 8u);
  double mean_radius = 0;
  for (const auto& q : outline) mean_radius += std::hypot(q[0].get<double>(), q[1].get<double>());
  mean_radius /= double(outline.size());
  EXPECT_NEAR(2 * mean_radius, d, 0.3);
  EXPECT_EQ(r.series["rhexis"]["target_diameter_mm"][0].get<double>(), 5.0);
}

TEST(DrillMetrics, ScoreTermsFollowTheBandRule) {
  const nlohmann::json target = {{"min", 5.0}, {"max", 5.5}};
  EXPECT_EQ(band_points(5.2, target, 1.0, 20), 20);
  EXPECT_EQ(band_points(5.0, target, 1.0, 20), 20);
  EXPECT_NEAR(band_points(4.5, target, 1.0, 20), 10, 1e-12);
  EXPECT_NEAR(band_points(6.0, target, 1.0, 20), 10, 1e-12);
  EXPECT_EQ(band_points(3.0, target, 1.0, 20), 0);
  EXPECT_EQ(band_points(nlohmann::json(), target, 1.0, 20), 0) << "a missing value scores nothing";
  const nlohmann::json none_allowed = {{"max", 0.0}};
  EXPECT_EQ(band_points(0, none_allowed, 1, 15), 15);
  EXPECT_EQ(band_points(1, none_allowed, 1, 15), 0) << "one radial tear-out loses the term";
  EXPECT_NEAR(band_points(1, none_allowed, 3, 10), 10.0 * 2.0 / 3.0, 1e-12);
}

TEST(DrillMetrics, PhacoSculptingDemoMatchesTheTrenchMeasure) {
  DemoRun& run = demo("phaco_sculpting_demo.json");
  expect_common_contract(run);
  const DrillReport& r = run.report;
  const nlohmann::json lens = lens_sculpting_summary(*run.scene);
  EXPECT_EQ(r.metrics["tets_removed"].get<uint64_t>(), lens["tets_removed"].get<uint64_t>());
  EXPECT_EQ(r.metrics["volume_removed_mm3"].get<double>(),
            lens["volume_removed_mm3"].get<double>());
  EXPECT_EQ(r.metrics["ultrasound_time_s"].get<double>(), lens["ultrasound_time_s"].get<double>());
  const auto& trenches = lens["trenches"];
  ASSERT_EQ(r.metrics["trench.count"].get<size_t>(), trenches.size());
  ASSERT_GE(trenches.size(), 2u) << "the demo cuts a cross";
  double width = 0;
  for (size_t i = 0; i < trenches.size(); ++i) {
    EXPECT_EQ(r.metrics["trench." + std::to_string(i) + ".width_mm"].get<double>(),
              trenches[i]["width_mm"].get<double>());
    width += trenches[i]["width_mm"].get<double>();
  }
  EXPECT_NEAR(r.metrics["trench.width_mm"].get<double>(), width / double(trenches.size()), 1e-12);
  EXPECT_EQ(r.metrics["trench.crossing_angle_deg"].get<double>(),
            lens["trench_crossing_angle_deg"].get<double>());
  // The demo stays clear of the posterior capsule and the iris.
  EXPECT_EQ(r.metrics["capsule_breach"], 0) << r.events.dump();
  EXPECT_EQ(r.metrics["iris_contacts"], 0);
  // The trench seen from above: removed centres inside the lens; depth fractions below 1 (negative:
  // cortex above the nucleus), the deepest about the trenches' depth.
  const auto& removed = r.series["trench"]["removed_xy_depth"];
  ASSERT_GT(removed.size(), 0u);
  EXPECT_LE(removed.size(), metrics::kMaxSeriesSamples);
  double deepest = -1;
  for (const auto& e : removed) {
    EXPECT_LE(std::hypot(e[0].get<double>(), e[1].get<double>()), 4.7);
    EXPECT_GE(e[2].get<double>(), -1.0);
    EXPECT_LE(e[2].get<double>(), 1.0);
    deepest = std::max(deepest, e[2].get<double>());
  }
  EXPECT_GT(deepest, 0.5 * r.metrics["trench.depth_fraction"].get<double>());
  // The probe in the lens pushes back by seed 003's k_f·d.
  EXPECT_GT(r.metrics["right.contact_force_mN.max"].get<double>(), 0.0);
}

TEST(DrillMetrics, CornealIncisionDemoHasKinematicsAndNoStress) {
  DemoRun& run = demo("corneal_incision_demo.json");
  expect_common_contract(run);
  const DrillReport& r = run.report;
  // The keratome enters at the limbus and withdraws through its own wound.
  EXPECT_EQ(r.metrics["corneal_stress_events"], 0);
  EXPECT_EQ(r.metrics["iris_contacts"], 0);
  // The demo's pass is steep (60° to the cornea): it loses exactly the wound-architecture terms.
  std::set<std::string> lost;
  for (const auto& t : r.score_terms)
    if (t["points"].get<double>() < t["weight"].get<double>()) lost.insert(t["metric"]);
  EXPECT_EQ(lost, (std::set<std::string>{"incision.entry_angle_deg", "incision.tunnel_length_mm"}));
  EXPECT_LT(r.score, 100.0);
}

TEST(DrillMetrics, RunReportCarriesTheDrillReport) {
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  const RunReport r = run_scenario(test::repo_scenario("corneal_incision_demo.json"), o);
  const nlohmann::json j = to_json(r);
  for (const char* key : {"metrics", "targets", "events", "series", "score_terms"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["metrics"]["score"], r.metrics["score"]);
  EXPECT_EQ(j["targets"]["corneal_stress_events"]["max"].get<double>(), 0.0);
  const DrillFile drill = load_drill_for(test::repo_scenario("corneal_incision_demo.json"));
  EXPECT_EQ(j["score_terms"].size(), drill.scoring.size()) << "one term per drill-file term";
  EXPECT_TRUE(j["series"]["hands"].contains("right"));
  const std::string text = summary_text(r);
  char score[32];
  std::snprintf(score, sizeof score, "score %.1f / 100", r.metrics["score"].get<double>());
  EXPECT_NE(text.find(score), std::string::npos) << text;
  EXPECT_NE(text.find("right.path_length_mm"), std::string::npos) << text;
}

TEST(DrillMetrics, SameForOneAndTwoThreadsAndTheReportChangesNothing) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "thread-count determinism is the Release pass's check; under ASan the same code "
                  "runs in CapsulorhexisDemoMatchesTheSceneAndTheContract";
#endif
  DemoRun& one = demo("capsulorhexis_demo.json", 1);
  DemoRun& two = demo("capsulorhexis_demo.json", 2);
  EXPECT_EQ(one.report.metrics, two.report.metrics);
  EXPECT_EQ(one.report.events, two.report.events);
  EXPECT_EQ(one.report.series, two.report.series);
  EXPECT_EQ(one.report.score_terms, two.report.score_terms);
  // Measuring only reads: the state hash is the same before and after a report.
  const std::string before = state_hash(*one.scene);
  (void)drill_report(*one.scene);
  EXPECT_EQ(state_hash(*one.scene), before);
  EXPECT_EQ(state_hash(*two.scene), before);
}

}  // namespace
}  // namespace phaco
