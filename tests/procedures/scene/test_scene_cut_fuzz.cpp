// Issue 18 item 4: the cut invariants on the scene's own meshes while scripted drills cut them.
// Random capsulorhexis drills (a cystotome stroke of random start, depth, speed and turns, then
// forceps grasping near its end and tearing along a drifting arc, with regrasps) and random corneal
// incisions (keratome at a random clock hour, limbus distance, entry angle, depth, speed and
// lateral wobble) run in the full scene at levels 0 and 1, deterministic by seed. After every frame
// that changed a membrane's topology (and every kEveryFrames frames) systems/topology_check runs:
//  - capsule, deformed shape (the positions the physics moves): every invariant, bowtie vertices
//    included, with kDeformedShape's area and angle bounds;
//  - capsule, rest shape (where the scene cuts, capsule_cutting.hpp): the default bounds the cut
//    promises (area >= 1e-8 mm², angles >= 1°);
//  - cornea (anchored: its shape is its rest shape): the default bounds;
// and the patched physics structure of the capsule, and at the end the cut's own bookkeeping.
// A failing drill is written as a scenario file (`phaco run FILE` replays it) whose path the
// failure message prints: PHACO_FUZZ_SAVE_DIR, else <temp>/phaco-scene-cut-fuzz.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "components/particles.hpp"
#include "components/triangles.hpp"
#include "engine/core/rng.hpp"
#include "engine/io/scenario.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/incision/cornea_sheet.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/cornea_cutting.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/cut/membrane_edit.hpp"
#include "systems/incision/keratome.hpp"
#include "systems/topology_check/topology_check.hpp"
#include "tests/support/capsule_invariants.hpp"
#include "tests/support/sanitizers.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

using topology_check::InvariantThresholds;

// Drills per test: Release full, a quarter under ASan (tests/support/sanitizers.hpp);
// PHACO_SCENE_FUZZ_DRILLS=N runs N of each instead (a longer local search).
int drills(int release_count) {
  if (const char* env = std::getenv("PHACO_SCENE_FUZZ_DRILLS")) return std::max(1, std::atoi(env));
  return test::asan_scaled(release_count, 4);
}
// PHACO_SCENE_FUZZ_SEED=S starts the drills' seeds at S instead of 1800.
uint64_t first_seed() {
  const char* env = std::getenv("PHACO_SCENE_FUZZ_SEED");
  return env ? std::strtoull(env, nullptr, 10) : 1800;
}
const int kRhexisDrills = drills(24);
const int kIncisionDrills = drills(48);
constexpr uint64_t kEveryFrames = 30;  // also check frames without a topology change

// Bounds and their reasons: tests/support/capsule_invariants.hpp. The cornea is anchored (its shape
// is its rest shape) and is held to the rest bounds.
constexpr InvariantThresholds kRestShape = test::kCapsuleRestBounds;
constexpr InvariantThresholds kDeformedShape = test::kCapsuleDeformedBounds;

constexpr double kPi = std::numbers::pi;

struct FuzzOutcome {
  std::string failure;                           // empty when every check passed
  uint64_t checks = 0;                           // check_membrane calls
  uint64_t cut_segments = 0, tear_advances = 0;  // capsule
  uint64_t incision_segments = 0;                // cornea
  double min_angle_deformed_deg = 180.0;         // capsule, over every checked frame
  double min_area_deformed_mm2 = 1e30;
};

// Smallest angle and area over the alive triangles (deformed-shape figures for the report).
void shape_extremes(const Particles& p, const Triangles& tr, FuzzOutcome& out) {
  for (uint32_t t = 0; t < tr.slots.size(); ++t) {
    if (!tr.slots.alive(t)) continue;
    auto at = [&](uint32_t i) { return Vec3(p.x[i], p.y[i], p.z[i]); };
    const Vec3 q[3] = {at(tr.a[t]), at(tr.b[t]), at(tr.c[t])};
    const double twice_area = (q[1] - q[0]).cross(q[2] - q[0]).norm();
    out.min_area_deformed_mm2 = std::min(out.min_area_deformed_mm2, 0.5 * twice_area);
    for (int k = 0; k < 3; ++k) {
      const Vec3 u = q[(k + 1) % 3] - q[k], v = q[(k + 2) % 3] - q[k];
      const double angle = std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / kPi;
      out.min_angle_deformed_deg = std::min(out.min_angle_deformed_deg, angle);
    }
  }
}

Quat unit(double w, double x, double y, double z) {
  return Quat(w, x, y, z).normalized();
}

// Cystotome stroke then forceps tear on the anterior capsule; heights from the lens's anterior
// surface (the capsule lies on it), so every drill touches the membrane.
Scenario random_rhexis(uint64_t seed, int level) {
  Scenario s = test::repo_scenario("capsulorhexis_demo.json");
  const CounterRng rng(seed, 18);
  uint32_t draw = 0;
  auto u = [&](double lo, double hi) { return lo + (hi - lo) * rng.uniform_double(0, 0, draw++); };
  const eye::EyeGeometry g = eye::eye_geometry(eye::default_eye_params());
  const double rim = g.capsule_radius;
  auto surface = [&](double x, double y) {
    return g.lens_anterior_z(std::min(std::hypot(x, y), std::min(rim, g.lens_a)));
  };
  const Quat cystotome_q = unit(0.768848, 0.023666, 0.638993, 0.0);
  const Quat forceps_q = unit(0.812035, -0.358301, -0.460673, 0.0);

  // A cystotome stroke from (x, y) starting at t: down to a random depth, a few legs, up; leaves
  // x, y and t at its end.
  HandTrack cystotome{Hand::Right, ToolKind::Cystotome, {}};
  auto stroke = [&](double& t, double& x, double& y) {
    const double press = u(0.0, 0.35);  // mm below the surface
    cystotome.track.push_back({t, Vec3(x, y, surface(x, y) + 1.5), cystotome_q});
    t += u(0.2, 0.5);
    cystotome.track.push_back({t, Vec3(x, y, surface(x, y) - press), cystotome_q});
    double heading = u(0.0, 2.0 * kPi);
    const int legs = 1 + static_cast<int>(u(0.0, 5.0));
    for (int k = 0; k < legs; ++k) {
      // Mostly gentle turns; now and then a hairpin that crosses the stroke's own path.
      heading += u(0.0, 1.0) < 0.2 ? u(0.75 * kPi, 1.1 * kPi) : u(-0.35 * kPi, 0.35 * kPi);
      const double length = u(0.2, 1.2), speed = u(1.0, 8.0);  // mm, mm/s
      x += length * std::cos(heading), y += length * std::sin(heading);
      const double r = std::hypot(x, y), r_max = 1.05 * rim;  // a little way off the rim at most
      if (r > r_max) x *= r_max / r, y *= r_max / r;
      t += length / speed;
      cystotome.track.push_back({t, Vec3(x, y, surface(x, y) - press), cystotome_q});
    }
    t += u(0.1, 0.4);
    cystotome.track.push_back({t, Vec3(x, y, surface(x, y) + 1.5), cystotome_q});
  };
  const double r0 = u(0.0, 0.5 * rim), a0 = u(0.0, 2.0 * kPi);
  double x = r0 * std::cos(a0), y = r0 * std::sin(a0), t = 0.0;
  stroke(t, x, y);

  // The forceps come down near the stroke's end, close, and tear round a centre near the axis.
  HandTrack forceps{Hand::Left, ToolKind::Forceps, {}};
  forceps.track.push_back({0.0, Vec3(-1.0, 0.0, 3.5), forceps_q});
  t += 0.05;
  forceps.track.push_back({t, Vec3(-1.0, 0.0, 3.5), forceps_q});
  const double off = u(0.0, 0.3), off_a = u(0.0, 2.0 * kPi);
  x += off * std::cos(off_a), y += off * std::sin(off_a);
  const double grasp_depth = u(-0.05, 0.15);
  t += u(0.2, 0.4);
  forceps.track.push_back({t, Vec3(x, y, surface(x, y) - grasp_depth), forceps_q});
  t += 0.1;
  forceps.track.push_back({t, Vec3(x, y, surface(x, y) - grasp_depth), forceps_q, 1.0});
  const double cx = u(-0.5, 0.5), cy = u(-0.5, 0.5);
  double radius = std::max(0.3, std::hypot(x - cx, y - cy));
  double angle = std::atan2(y - cy, x - cx);
  const double turn = u(0.0, 1.0) < 0.5 ? 1.0 : -1.0;
  const double lift = u(-0.05, 0.3);
  const int steps = 4 + static_cast<int>(u(0.0, 10.0));
  for (int k = 0; k < steps; ++k) {
    if (u(0.0, 1.0) < 0.15) {  // regrasp: open, lift, come down a little back, close
      const Vec3 at = forceps.track.back().pos;
      forceps.track.push_back({t += 0.1, at, forceps_q, 0.0});
      forceps.track.push_back({t += 0.1, at + Vec3(0.0, 0.0, 0.3), forceps_q, 0.0});
      const double back = angle - turn * u(0.0, 0.3);
      const double bx = cx + radius * std::cos(back), by = cy + radius * std::sin(back);
      forceps.track.push_back({t += 0.15, Vec3(bx, by, surface(bx, by) - grasp_depth), forceps_q});
      forceps.track.push_back(
          {t += 0.1, Vec3(bx, by, surface(bx, by) - grasp_depth), forceps_q, 1.0});
    }
    angle += turn * u(0.15, 0.6);
    radius = std::clamp(radius + u(-0.35, 0.35), 0.3, 1.1 * rim);  // drifts in and out: run-outs
    const double fx = cx + radius * std::cos(angle), fy = cy + radius * std::sin(angle);
    t += u(0.08, 0.3);
    forceps.track.push_back({t, Vec3(fx, fy, surface(fx, fy) + lift), forceps_q, 1.0});
  }
  const Vec3 last = forceps.track.back().pos;
  forceps.track.push_back({t += 0.1, last, forceps_q, 0.0});
  forceps.track.push_back({t += 0.2, last + Vec3(0.0, 0.0, 1.5), forceps_q, 0.0});
  // Sometimes a second stroke anywhere on the capsule: across the flap, the tear or the rim.
  if (u(0.0, 1.0) < 0.4) {
    const double r1 = u(0.0, rim), a1 = u(0.0, 2.0 * kPi);
    x = r1 * std::cos(a1), y = r1 * std::sin(a1);
    stroke(t, x, y);
  }

  s.name = "scene cut fuzz: rhexis, seed " + std::to_string(seed);
  s.description =
      "random cystotome stroke and forceps tear (tests/procedures/scene/test_scene_cut_fuzz.cpp)";
  s.eye.level = level;
  s.seed = seed;
  s.hands = {forceps, cystotome};
  s.duration_s = t + 0.05;
  return s;
}

// A keratome pass from a random approach, with lateral and normal wobble on the way in, then out.
Scenario random_incision(uint64_t seed, int level) {
  Scenario s = test::repo_scenario("corneal_incision_demo.json");
  const CounterRng rng(seed, 19);
  uint32_t draw = 0;
  auto u = [&](double lo, double hi) { return lo + (hi - lo) * rng.uniform_double(0, 0, draw++); };
  const eye::EyeParams params = eye::default_eye_params();
  const incision::CorneaSpheres sp = corneal_incision::cornea_spheres(params);
  const incision::IncisionApproach approach{u(0.0, 12.0), u(0.1, 1.0), u(8.0, 60.0)};
  const incision::KeratomeBlade b = incision::incision_start_blade(
      sp.anterior_centre_z, sp.anterior_radius_mm, sp.limbus_radius_mm, approach,
      corneal_incision::eye_keratome(params));
  const incision::BladeFrame f = incision::blade_frame(b);
  const Quat q = incision::tool_quat_for_blade(f.d, f.l);
  const Vec3 normal = f.d.cross(f.l).normalized();
  HandTrack keratome{Hand::Right, ToolKind::Keratome, {}};
  double t = 0.0;
  keratome.track.push_back({t, f.tip - 0.4 * f.d, q});
  const double depth = u(0.5, 4.0), speed = u(2.0, 12.0);  // mm along the axis, mm/s
  const int legs = 1 + static_cast<int>(u(0.0, 5.0));
  for (int k = 1; k <= legs; ++k) {
    const double along = depth * k / legs;
    const Vec3 wobble = u(-0.3, 0.3) * f.l + u(-0.08, 0.08) * normal;
    // The blade also pitches about its lateral axis by up to 8° either way.
    const Quat pitch(Eigen::AngleAxisd(u(-8.0, 8.0) * kPi / 180.0, f.l));
    t += (depth / legs) / speed + 0.01;
    keratome.track.push_back({t, f.tip + along * f.d + wobble, (pitch * q).normalized()});
  }
  t += u(0.1, 0.4);
  keratome.track.push_back({t, f.tip - 0.6 * f.d, q});

  s.name = "scene cut fuzz: incision, seed " + std::to_string(seed);
  s.description = "random keratome pass (tests/procedures/scene/test_scene_cut_fuzz.cpp)";
  s.eye.level = level;
  s.seed = seed;
  s.hands = {keratome};
  s.duration_s = t + 0.05;
  return s;
}

// Writes the scenario where a person can replay it; returns the path.
std::filesystem::path save_scenario(const Scenario& s, const std::string& stem) {
  const char* env = std::getenv("PHACO_FUZZ_SAVE_DIR");
  const std::filesystem::path dir =
      env ? std::filesystem::path(env)
          : std::filesystem::temp_directory_path() / "phaco-scene-cut-fuzz";
  std::filesystem::create_directories(dir);
  const std::filesystem::path file = dir / (stem + ".json");
  std::ofstream(file) << to_json(s).dump(2) << '\n';
  return file;
}

std::string report_failure(const char* what, uint64_t frame,
                           const topology_check::InvariantReport& r) {
  std::ostringstream out;
  out << what << " after frame " << frame << ": " << r.summary(5);
  return out.str();
}

// Runs the drill, checking after every topology change and every kEveryFrames frames; stops at
// the first failure.
FuzzOutcome run_checked(const Scenario& s, const InvariantThresholds& deformed,
                        const InvariantThresholds& rest) {
  FuzzOutcome out;
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  auto scene = build_scene(s, o);
  const std::optional<Entity> capsule = scene->body(BodyPart::Capsule);
  const std::optional<Entity> cornea = scene->body(BodyPart::Cornea);
  CapsuleCutting* cc = capsule ? scene->world.get<CapsuleCutting>(*capsule) : nullptr;
  CorneaCutting* kc = cornea ? scene->world.get<CorneaCutting>(*cornea) : nullptr;
  topology_check::InvariantScratch scratch;
  Particles rest_shape;
  uint64_t capsule_changes = 0, cornea_segments = 0;
  const uint64_t frames = s.frame_count();
  for (uint64_t f = 0; f < frames && out.failure.empty(); ++f) {
    step(*scene);
    const bool every = f % kEveryFrames == 0;
    if (cc && (cc->topology_changes != capsule_changes || every)) {
      capsule_changes = cc->topology_changes;
      const Particles& p = scene->world.at<Particles>(*capsule);
      const Triangles& tr = scene->world.at<Triangles>(*capsule);
      const CapsuleSprings& sp = scene->world.at<CapsuleSprings>(*capsule);
      shape_extremes(p, tr, out);
      auto r = topology_check::check_membrane(p, tr, sp.springs, deformed, scratch);
      ++out.checks;
      if (!r.ok()) {
        out.failure = report_failure("capsule (deformed shape)", f, r);
        break;
      }
      rest_shape = test::capsule_rest_shape(p, *cc);
      r = topology_check::check_membrane(rest_shape, tr, sp.springs, rest, scratch);
      ++out.checks;
      if (!r.ok()) {
        out.failure = report_failure("capsule (rest shape)", f, r);
        break;
      }
      const std::string structure =
          topology_check::check_spring_structure(sp.springs, sp.blocks, sp.graph, p.slots.size());
      if (!structure.empty())
        out.failure = "capsule physics after frame " + std::to_string(f) + ": " + structure;
    }
    if (kc && (kc->segments != cornea_segments || every)) {
      cornea_segments = kc->segments;
      const auto r = topology_check::check_membrane(scene->world.at<Particles>(*cornea),
                                                    scene->world.at<Triangles>(*cornea),
                                                    kc->springs, rest, scratch);
      ++out.checks;
      if (!r.ok()) out.failure = report_failure("cornea", f, r);
    }
  }
  if (cc) {
    out.cut_segments = cc->cut_segments, out.tear_advances = cc->tear_state.advances;
    CapsuleSprings& sp = scene->world.at<CapsuleSprings>(*capsule);
    const cut::CutMesh m{scene->world.at<Particles>(*capsule), scene->world.at<Triangles>(*capsule),
                         sp.springs, cc->topology, cc->material};
    if (const std::string topo = cut::check_topology(m); out.failure.empty() && !topo.empty())
      out.failure = "capsule cut bookkeeping at the end: " + topo;
  }
  if (kc) {
    out.incision_segments = kc->segments;
    const cut::CutMesh m{scene->world.at<Particles>(*cornea), scene->world.at<Triangles>(*cornea),
                         kc->springs, kc->topology, kc->material};
    if (const std::string topo = cut::check_topology(m); out.failure.empty() && !topo.empty())
      out.failure = "cornea cut bookkeeping at the end: " + topo;
  }
  return out;
}

// Runs drills 0..count-1 of one kind; each failure is saved and reported with its file.
template <class MakeScenario>
void fuzz(const char* kind, int count, MakeScenario make, uint64_t& cut_drills,
          FuzzOutcome& total) {
  for (int k = 0; k < count; ++k) {
    const uint64_t seed = first_seed() + static_cast<uint64_t>(k);
    const int level = static_cast<int>(seed % 2);
    const Scenario s = make(seed, level);
    const FuzzOutcome r = run_checked(s, kDeformedShape, kRestShape);
    total.checks += r.checks;
    total.min_angle_deformed_deg = std::min(total.min_angle_deformed_deg, r.min_angle_deformed_deg);
    total.min_area_deformed_mm2 = std::min(total.min_area_deformed_mm2, r.min_area_deformed_mm2);
    total.cut_segments += r.cut_segments, total.tear_advances += r.tear_advances;
    total.incision_segments += r.incision_segments;
    if (r.cut_segments > 0 || r.incision_segments > 0) ++cut_drills;
    if (std::getenv("PHACO_SCENE_FUZZ_VERBOSE"))
      std::printf(
          "%s seed %llu level %d: %llu cut, %llu tear, %llu incision; min angle %.3g area %.3g\n",
          kind, (unsigned long long)seed, level, (unsigned long long)r.cut_segments,
          (unsigned long long)r.tear_advances, (unsigned long long)r.incision_segments,
          r.min_angle_deformed_deg, r.min_area_deformed_mm2);
    if (!r.failure.empty()) {
      const auto file = save_scenario(
          s, std::string(kind) + "-level" + std::to_string(level) + "-seed" + std::to_string(seed));
      ADD_FAILURE() << kind << " seed " << seed << " level " << level << ": " << r.failure
                    << "\n  scenario saved: " << file.string();
    }
  }
}

TEST(SceneCutFuzz, RandomRhexisDrillsKeepTheCapsuleSound) {
  uint64_t cut_drills = 0;
  FuzzOutcome total;
  fuzz("rhexis", kRhexisDrills, random_rhexis, cut_drills, total);
  RecordProperty("checks", std::to_string(total.checks));
  RecordProperty("min_angle_deformed_deg", std::to_string(total.min_angle_deformed_deg));
  RecordProperty("min_area_deformed_mm2", std::to_string(total.min_area_deformed_mm2));
  std::printf(
      "rhexis: %d drills, %llu cut, %llu cut segments, %llu tear advances, %llu checks; "
      "deformed capsule: smallest angle %.3g deg, smallest area %.3g mm^2\n",
      kRhexisDrills, static_cast<unsigned long long>(cut_drills),
      static_cast<unsigned long long>(total.cut_segments),
      static_cast<unsigned long long>(total.tear_advances),
      static_cast<unsigned long long>(total.checks), total.min_angle_deformed_deg,
      total.min_area_deformed_mm2);
  // The fuzz must exercise the cut and the tear, not only look at an uncut capsule.
  EXPECT_GE(cut_drills, static_cast<uint64_t>(kRhexisDrills) * 3 / 4);
  EXPECT_GT(total.tear_advances, 0u);
}

TEST(SceneCutFuzz, RandomIncisionsKeepTheCorneaSound) {
  uint64_t cut_drills = 0;
  FuzzOutcome total;
  fuzz("incision", kIncisionDrills, random_incision, cut_drills, total);
  std::printf("incision: %d drills, %llu cut, %llu segments, %llu checks\n", kIncisionDrills,
              static_cast<unsigned long long>(cut_drills),
              static_cast<unsigned long long>(total.incision_segments),
              static_cast<unsigned long long>(total.checks));
  EXPECT_GE(cut_drills, static_cast<uint64_t>(kIncisionDrills) * 3 / 4);
}

// The failure path itself: with a bound no mesh meets, the first check fails, and the saved file
// is a scenario that loads back equal to the one that ran.
TEST(SceneCutFuzz, AFailureSavesAScenarioThatReplays) {
  Scenario s = random_rhexis(1800, 0);
  s.duration_s = 0.05;
  const FuzzOutcome r = run_checked(s, {.min_area_mm2 = 1e6, .min_angle_deg = 1.0}, kRestShape);
  ASSERT_FALSE(r.failure.empty());
  EXPECT_NE(r.failure.find("SmallArea"), std::string::npos) << r.failure;
  const auto file = save_scenario(s, "self-test-rhexis-level0-seed1800");
  const Scenario back = load_scenario(file);
  EXPECT_EQ(back, s);
  std::filesystem::remove(file);
}

}  // namespace
}  // namespace phaco
