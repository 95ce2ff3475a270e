// The scripted expert and novice drills (data/scenarios/*_expert.json, *_novice_*.json, made by
// scripts/scenarios/make_all.sh): the expert meets every target its report lists; each
// novice misses exactly the targets its script breaks — including the ones that follow from it
// physically (a radial run-out also enlarges and distorts the opening; a shallow or narrow trench
// gives the probe less purchase, so the quarter turn falls short and the trenches cross at ~72°)
// — and shows the expected events. The drills measure the corneal ports by default (their files'
// "ports"), so the targets include globe.max_rotation_deg and ports.max_force_mN: the scripted
// hands pivot in their ports, and no novice's defect is a port's (none misses a port target).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "engine/io/tool_shape.hpp"
#include "engine/io/track.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

struct DrillCase {
  const char* file;
  std::set<std::string> missed;         // targets the run must miss, no more, no fewer
  std::set<std::string> events_needed;  // event kinds that must occur
};

std::ostream& operator<<(std::ostream& os, const DrillCase& c) {
  return os << c.file;
}

bool meets(const nlohmann::json& value, const nlohmann::json& target) {
  const double v = value.is_boolean() ? (value.get<bool>() ? 1.0 : 0.0) : value.get<double>();
  if (target.contains("min") && v < target["min"].get<double>()) return false;
  if (target.contains("max") && v > target["max"].get<double>()) return false;
  return true;
}

class DrillScenario : public ::testing::TestWithParam<DrillCase> {};

TEST_P(DrillScenario, MissesExactlyTheTargetsItsScriptBreaks) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "whole drills take minutes under ASan; the Release pass runs them";
#endif
  const DrillCase& c = GetParam();
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  const RunReport r = run_scenario(test::repo_scenario(c.file), o);
  ASSERT_FALSE(r.targets.empty());
  std::set<std::string> missed;
  for (const auto& [name, target] : r.targets.items()) {
    if (!r.metrics.contains(name))
      continue;  // not measured in this scene (listed in docs/metrics.md)
    if (!meets(r.metrics[name], target)) missed.insert(name);
  }
  EXPECT_EQ(missed, c.missed) << "score " << r.metrics.value("score", -1.0);
  std::set<std::string> kinds;
  for (const auto& e : r.events) kinds.insert(e.value("kind", ""));
  for (const auto& k : c.events_needed)
    EXPECT_TRUE(kinds.count(k)) << "event '" << k << "' missing";
  // A complication (a radial tear-out, a posterior capsule rupture: the drill files'
  // "complications", docs/scoring.md) fails the drill and caps its score at 40; nothing else does.
  const bool complication = c.missed.count("rhexis.radial_tearouts") > 0 ||
                            c.missed.count("capsule_breach") > 0 ||
                            c.missed.count("posterior_capsule.rupture") > 0;
  EXPECT_EQ(r.metrics.value("drill_failed", 0.0) > 0, complication);
  EXPECT_EQ(!r.complications.empty(), complication);
  if (complication) {
    EXPECT_LE(r.metrics["score"].get<double>(), 40.0);
  }
  EXPECT_EQ(r.metrics.value("attempted", 0.0), 1.0) << "every scripted hand attempts its step";
  if (c.missed.empty()) {
    EXPECT_DOUBLE_EQ(r.metrics["score"].get<double>(), 100.0) << "the expert loses no points";
  } else {
    // The off-centre novice scores 91.5: its opening is decentred by its hands' 0.7 mm shift
    // (0.69 mm) since the held flap folds at the tear resistance (issue 17 item 5); when the
    // forceps dragged the disc it was 0.83–0.89 mm and the score under 90.
    EXPECT_LT(r.metrics["score"].get<double>(), 95.0) << "a novice loses points";
  }
}

// The difficulty changes the outcome of the same hands (data/drills/capsulorhexis.json "hard":
// an 88-year-old's capsule, anterior bowing 0.4 kPa, a 2.2 mm chamber). The expert's tracks, which
// meet every target on the standard eye (centring 0.04 mm, circularity 0.95, no warning), give a
// run-out warning and a less round, less centred opening: the bowed membrane pulls the tear
// outward (seed 004 §1).
TEST(DrillDifficulty, TheExpertsHandsOnAHardEyeGetARunoutWarning) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "whole drills take minutes under ASan; the Release pass runs them";
#endif
  Scenario s = test::repo_scenario("capsulorhexis_expert.json");
  s.difficulty = "hard";
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  const RunReport hard = run_scenario(s, o);
  EXPECT_GE(hard.metrics.value("runout_warnings", 0.0), 1.0);
  EXPECT_EQ(hard.metrics.value("rhexis.complete", 0.0), 1.0) << "still a complete opening";
  EXPECT_GT(hard.metrics.value("rhexis.centering_mm", 0.0), 0.2);
  EXPECT_LT(hard.metrics.value("rhexis.circularity", 1.0), 0.93);
}

// The scripted hands pivot in their corneal ports (scripts/scenarios/ports.py computes the port
// centres in Python): at every frame with the tip inside the eye, the shaft's axis passes the C++
// default_ports centre — main for the right hand, side for the left — within 0.02 mm. This keeps
// the generator's copy of default_ports honest. The keratome cuts its port and is not checked.
// The axis is the drawn shaft's (engine/io/tool_shape): for the cystotome and the chopper beside
// the tip by their bent points, and checked where the aim is whole (port_pivot's rule: the tip
// one bend and 1 mm past the centre; nearer, the axis could pass the centre only across the
// tunnel).
TEST(DrillPivot, TheScriptedShaftsPassThroughTheirPortCentres) {
  const eye::EyeParams params = eye::default_eye_params();
  const eye::EyeGeometry g = eye::eye_geometry(params);
  for (const char* file :
       {"capsulorhexis_expert.json", "capsulorhexis_novice_off_centre.json",
        "capsulorhexis_novice_runout.json", "capsulorhexis_novice_small.json",
        "phaco_sculpting_expert.json", "phaco_sculpting_novice_shallow.json",
        "phaco_sculpting_novice_narrow.json", "nucleus_removal_expert.json",
        "nucleus_removal_novice_rupture.json", "nucleus_removal_novice_wasteful.json"}) {
    const Scenario s = test::repo_scenario(file);
    const DrillFile drill = load_drill_for(s);
    ASSERT_TRUE(drill.guidance.incision_site && drill.guidance.side_port) << file;
    const auto ports = default_ports(params, drill.guidance.incision_site->clock_hour,
                                     drill.guidance.side_port->clock_hour);
    for (const HandTrack& h : s.hands) {
      const EyePort& port = ports[h.hand == Hand::Right ? 0 : 1];
      const Vec3 centre = port.centre_mm;
      const double bend = shaft_offset_local(h.tool).norm();
      double worst = 0;
      int inside = 0;
      for (uint64_t f = 0; f <= s.frame_count(); ++f) {
        const ToolPose p = sample_track(h.track, static_cast<double>(f) * s.dt_s);
        const double rho = std::hypot(p.pos.x(), p.pos.y());
        const double front =
            rho < g.limbus_radius
                ? g.cornea_anterior_centre_z +
                      std::sqrt(g.cornea_anterior_radius * g.cornea_anterior_radius - rho * rho)
                : -1e9;
        if (p.pos.z() >= front) continue;  // outside the eye: the hand is free
        if (bend > 0 && (p.pos - centre).dot(port.axis) < bend + 1.0) continue;
        ++inside;
        const ShaftAxis axis = shaft_axis(p, h.tool);
        const Vec3 d = centre - axis.point;
        worst = std::max(worst, (d - d.dot(axis.direction) * axis.direction).norm());
      }
      EXPECT_GT(inside, 0) << file;
      EXPECT_LT(worst, 0.02) << file << ": shaft passes the port centre " << worst << " mm off";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Drills, DrillScenario,
    ::testing::Values(
        DrillCase{"capsulorhexis_expert.json", {}, {"grasp", "release"}},
        DrillCase{"capsulorhexis_novice_off_centre.json",
                  {"rhexis.centering_mm", "rhexis.puncture_offset_mm"},
                  {}},
        DrillCase{"capsulorhexis_novice_small.json", {"rhexis.diameter_mm"}, {}},
        DrillCase{"capsulorhexis_novice_runout.json",
                  {"rhexis.radial_tearouts", "rhexis.diameter_mm", "rhexis.circularity"},
                  {"runout_warning", "radial_tearout"}},
        DrillCase{"phaco_sculpting_expert.json", {}, {}},
        DrillCase{"phaco_sculpting_novice_shallow.json",
                  {"trench.depth_fraction", "trench.0.depth_fraction", "trench.1.depth_fraction",
                   "trench.crossing_angle_deg"},
                  {}},
        DrillCase{"phaco_sculpting_novice_narrow.json",
                  {"trench.width_mm", "trench.0.width_mm", "trench.1.width_mm",
                   "trench.crossing_angle_deg"},
                  {}},
        // The incision: a straight keratome pass; the steep one keeps the site and the width but
        // its tunnel is under 1 mm (scripts/scenarios/incision.py).
        DrillCase{"corneal_incision_expert.json", {}, {}},
        DrillCase{"corneal_incision_novice_steep.json",
                  {"incision.entry_angle_deg", "incision.tunnel_length_mm"},
                  {}},
        DrillCase{"corneal_incision_novice_site.json", {"incision.limbus_distance_mm"}, {}},
        // Nucleus removal (issue 19, scripts/scenarios/nucleus_removal.py): three cracks, then
        // each quadrant held and emulsified. The dip goes through the posterior pole (a rupture,
        // which fails the drill); the wasteful hands use ultrasound where aspiration does.
        DrillCase{"nucleus_removal_expert.json", {}, {}},
        DrillCase{"nucleus_removal_novice_rupture.json",
                  {"posterior_capsule.min_distance_mm", "posterior_capsule.rupture"},
                  {"posterior_capsule_rupture"}},
        DrillCase{"nucleus_removal_novice_wasteful.json", {"cde_pct_s"}, {}}),
    [](const auto& info) {
      std::string n = info.param.file;
      n = n.substr(0, n.find('.'));
      return n;
    });

}  // namespace
}  // namespace phaco
