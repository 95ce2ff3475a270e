// The tear limits the force on the flap (issue 17 item 5; systems/tear, procedures/scene/
// capsule_cutting): with the scripted expert (data/scenarios/capsulorhexis_expert.json) the force
// the forceps exert on the flap while tearing has an RMS inside the expert band, 6–14 mN
// (surgeons with force-sensing forceps ≈ 9 mN), and no frame's force rises above the capsule's
// tear resistance F_c by more than the plateau margin (the held flap folds at F_c after the
// frame's edits, and the dynamics relax it from there: measured 1.02·F_c at worst with block-Jacobi
// and deflation; 1.30–1.48·F_c while the fold came before the edits). The scripted novices are the
// expert's hands moved, scaled or turned outward; the tear caps their force at the same plateau
// (their RMS is not the surgeons' ≈ 17 mN, which is voluntary force beyond what the tear needs).
// Whole runs: skipped under ASan like the other drill tests.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "procedures/scene/run.hpp"
#include "systems/tear/tear.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

constexpr double kPlateauMargin = 0.1;

struct TearForce {
  double resistance_mn = 0, rms = 0, max = 0, tearing_s = 0;
  std::vector<double> force;  // per tearing frame, mN
  nlohmann::json metrics;
};

TearForce measure(const char* file) {
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  const RunReport r = run_scenario(test::repo_scenario(file), o);
  TearForce out;
  out.metrics = r.metrics;
  out.resistance_mn = r.physics["capsule_cutting"].value("tear_resistance_mN", 0.0);
  out.rms = r.metrics.value("left.tear_force_mN.rms", -1.0);
  out.max = r.metrics.value("left.tear_force_mN.max", -1.0);
  out.tearing_s = r.metrics.value("left.tearing_s", 0.0);
  const auto& left = r.series["hands"]["left"];
  EXPECT_EQ(left.value("tool", ""), "forceps");
  const auto force = left["force_mN"].get<std::vector<double>>();
  const auto tearing = left["tearing"].get<std::vector<int>>();
  EXPECT_EQ(force.size(), r.frames + 1) << "one sample a frame (not decimated)";
  for (size_t i = 0; i < force.size(); ++i)
    if (tearing[i]) out.force.push_back(force[i]);
  return out;
}

TEST(TearForce, TheExpertTearsAtThePlateauWithAnRmsInTheExpertBand) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "whole drills take minutes under ASan; the Release pass runs them";
#endif
  const TearForce e = measure("capsulorhexis_expert.json");
  EXPECT_NEAR(e.resistance_mn, tear::tear_resistance_mn(1500.0, 0.013), 1e-9)
      << "the standard eye's F_c";
  EXPECT_GT(e.tearing_s, 3.0) << "the expert tears for most of the run";
  ASSERT_FALSE(e.force.empty());
  EXPECT_GE(e.rms, 6.0);
  EXPECT_LE(e.rms, 14.0);
  const double peak = *std::max_element(e.force.begin(), e.force.end());
  EXPECT_DOUBLE_EQ(peak, e.max);
  EXPECT_LE(peak, (1 + kPlateauMargin) * e.resistance_mn) << "no ramp above the tear resistance";
  // Nor once the tear has closed and the forceps still hold the freed disc (the whole run).
  EXPECT_LE(e.metrics.value("left.contact_force_mN.max", 1e9),
            (1 + kPlateauMargin) * e.resistance_mn);
}

TEST(TearForce, TheNovicesTearAtTheSamePlateau) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "whole drills take minutes under ASan; the Release pass runs them";
#endif
  for (const char* file : {"capsulorhexis_novice_off_centre.json",
                           "capsulorhexis_novice_runout.json", "capsulorhexis_novice_small.json"}) {
    const TearForce n = measure(file);
    ASSERT_FALSE(n.force.empty()) << file;
    EXPECT_GT(n.tearing_s, 3.0) << file;
    EXPECT_LE(n.max, (1 + kPlateauMargin) * n.resistance_mn) << file << ": no ramp above F_c";
    // The force sits at the plateau while tearing (ramping up from 0 after each regrasp).
    EXPECT_GT(n.rms, 0.6 * n.resistance_mn) << file;
    EXPECT_LT(n.rms, 1.1 * n.resistance_mn) << file;
  }
}

}  // namespace
}  // namespace phaco
