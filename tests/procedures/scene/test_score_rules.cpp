// Scores that mean what they say (issue 20 item 3, docs/scoring.md): tools that never enter the
// eye score 0 in every drill, although their "no contact" terms would have given points; a phaco
// tip plunged through the posterior capsule fails the sculpting drill, names the complication and
// caps the score at the drill file's value.
#include <gtest/gtest.h>

#include <string>

#include "procedures/eye/eye_params.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

RunReport run(const Scenario& s) {
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  return run_scenario(s, o);
}

// The expert's scenario with every hand resting 4 mm above the cornea's apex for 0.25 s.
Scenario idle(const char* expert) {
  Scenario s = test::repo_scenario(expert);
  double x = -1.0;
  for (HandTrack& h : s.hands) {
    TrackSample rest;
    rest.pos = Vec3(x, 0.0, 8.0);
    h.track = {rest};
    x += 2.0;
  }
  s.duration_s = 0.25;
  return s;
}

TEST(ScoreRules, IdleToolsScoreZeroInEveryDrill) {
  for (const char* file : {"corneal_incision_expert.json", "capsulorhexis_expert.json",
                           "phaco_sculpting_expert.json", "nucleus_removal_expert.json"}) {
    const RunReport r = run(idle(file));
    EXPECT_EQ(r.metrics.value("attempted", -1.0), 0.0) << file;
    EXPECT_EQ(r.metrics.value("score", -1.0), 0.0) << file;
    EXPECT_TRUE(r.complications.empty()) << file;
    // Not vacuous: the safety terms' band alone would have given points to doing nothing.
    double would = 0;
    for (const auto& t : r.score_terms) {
      EXPECT_EQ(t["points"].get<double>(), 0.0) << file << ": " << t["metric"];
      const DrillFile drill = load_drill_for(test::repo_scenario(file));
      for (const ScoreTerm& st : drill.scoring)
        if (st.metric == t["metric"])
          would += band_points(t["value"], t["target"], st.falloff, st.weight);
    }
    EXPECT_GT(would, 0.0) << file << ": no safety term to gate";
  }
}

// The probe enters through its port, then plunges with ultrasound on through the whole lens to
// 0.3 mm beyond its posterior pole.
TEST(ScoreRules, APlungeThroughThePosteriorCapsuleFailsSculpting) {
  Scenario s = test::repo_scenario("phaco_sculpting_expert.json");
  test::plunge_through_posterior_capsule(
      s, eye::default_eye_params().get("lens.posterior_half_thickness_mm"));
  const RunReport r = run(s);
  EXPECT_EQ(r.metrics.value("capsule_breach", 0.0), 1.0);
  ASSERT_EQ(r.complications.size(), 1u);
  EXPECT_NE(r.complications[0]["name"].get<std::string>().find("posterior capsule rupture"),
            std::string::npos);
  EXPECT_EQ(r.metrics.value("drill_failed", 0.0), 1.0);
  EXPECT_LE(r.metrics.value("score", 100.0), r.complications[0]["score_cap"].get<double>());
  EXPECT_TRUE(to_json(r)["failed"].get<bool>());
  bool breach = false;
  for (const auto& e : r.events) breach |= e.value("kind", "") == "capsule_breach";
  EXPECT_TRUE(breach);
}

}  // namespace
}  // namespace phaco
