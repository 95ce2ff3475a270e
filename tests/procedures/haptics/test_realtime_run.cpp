// A scene stepped in real time beside the haptic session (procedures/haptics/realtime_run): a
// scripted device drives the forceps, every frame publishes a model, the thread adopts them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "engine/haptics/scripted_device.hpp"
#include "engine/schedule/executor.hpp"
#include "procedures/haptics/realtime_run.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

HapticSessionConfig quiet_config() {
  HapticSessionConfig c;
  c.loop.realtime = false;  // CI machines may refuse SCHED_FIFO; the logic is the same
  c.loop.lock_memory = false;
  c.loop.warmup_ticks = 0;
  return c;
}

TEST(RealtimeRun, AScriptedDeviceDrivesTheSceneInRealTime) {
  // The demo's forceps (left) from a scripted device, the first 1.5 s, in real time.
  const Scenario s = test::repo_scenario("capsulorhexis_demo.json");
  const HandTrack* left = s.find_hand(Hand::Left);
  ASSERT_NE(left, nullptr);
  HapticSession session(quiet_config());
  session.attach(Hand::Left, std::make_unique<ScriptedDevice>(*left));
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  RealtimeRunOptions run;
  run.duration_s = 1.5;
  const RealtimeRunReport r = run_realtime(s, o, session, run);
  EXPECT_EQ(r.frames, static_cast<uint64_t>(std::ceil(1.5 / s.dt_s - 1e-9)));
  EXPECT_GE(r.haptics.models_published, r.frames)
      << "one model per frame (and one before the start)";
  const HapticHandStats& h = r.haptics.hands[static_cast<size_t>(Hand::Left)];
  // Counts, not rates (issue 18): the loop ran, read the device and took the scene's models. How
  // fast it ticks beside the frames is the harness's figure (phaco-perf haptics).
  EXPECT_TRUE(h.attached);
  EXPECT_GT(h.ticks, 0u);
  EXPECT_GT(h.samples, 0u);
  EXPECT_GT(h.models_adopted, 0u);
  EXPECT_LE(h.models_adopted, r.haptics.models_published);
  EXPECT_FALSE(r.haptics.hands[static_cast<size_t>(Hand::Right)].attached);
  const nlohmann::json j = to_json(r);
  EXPECT_TRUE(j["haptics"]["hands"].contains("left"));
  EXPECT_NE(summary_text(r).find("haptic thread"), std::string::npos);
}

// A run as long as its scenario steps that scenario once: the step before the haptic thread
// starts made the run restart the scene for its last frame, and report on that fresh scene.
TEST(RealtimeRun, ARunAsLongAsItsScenarioKeepsItsSceneAndReportsItsSystems) {
  Scenario s = test::repo_scenario("capsulorhexis_demo.json");
  s.duration_s = 0.5;
  HapticSession session(quiet_config());
  session.attach(Hand::Left, std::make_unique<ScriptedDevice>(*s.find_hand(Hand::Left)));
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  RealtimeRunOptions run;  // duration 0: the scenario's
  uint64_t last_frame = 0;
  std::vector<std::string> systems;
  run.at_end = [&](Scene& scene) {
    last_frame = scene.frame;
    for (const SystemTiming& t : scene.executor->timings()) systems.push_back(t.name);
  };
  const RealtimeRunReport r = run_realtime(s, o, session, run);
  EXPECT_EQ(r.restarts, 0u);
  EXPECT_EQ(r.frames, s.frame_count());
  EXPECT_EQ(last_frame, s.frame_count() + 1) << "the step before the start and the run's frames";
  // Every system of the scene, with the fields `phaco run --json` gives (what they measure is
  // the harness's business).
  const nlohmann::json j = to_json(r);
  ASSERT_FALSE(systems.empty());
  EXPECT_EQ(j["systems"].size(), systems.size());
  for (const std::string& name : systems) {
    ASSERT_TRUE(j["systems"].contains(name)) << name;
    for (const char* field : {"p50_ms", "p99_ms", "mean_ms", "max_ms"})
      EXPECT_TRUE(j["systems"][name].contains(field)) << name << " " << field;
  }
}

TEST(RealtimeRun, AStalledSimulationLeavesTheHapticThreadRunning) {
  const Scenario s = test::repo_scenario("capsulorhexis_demo.json");
  HapticSession session(quiet_config());
  session.attach(Hand::Left, std::make_unique<ScriptedDevice>(*s.find_hand(Hand::Left)));
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  RealtimeRunOptions run;
  run.duration_s = 0.6;
  run.stall_at_s = 0.2;
  run.stall_ms = 200;
  // The haptic ticks seen after each frame: the stall lies between two of them.
  std::vector<uint64_t> ticks_after_frame;
  ticks_after_frame.reserve(128);
  run.after_frame = [&](Scene&) {
    ticks_after_frame.push_back(session.stats().hands[static_cast<size_t>(Hand::Left)].ticks);
  };
  const RealtimeRunReport r = run_realtime(s, o, session, run);
  const auto planned = static_cast<uint64_t>(std::ceil(0.6 / s.dt_s - 1e-9));
  EXPECT_EQ(r.frames, planned - 1) << "one frame slot spent stalled";
  EXPECT_GE(r.late_frames, 1u) << "the frames after the stall start late";
  const HapticHandStats& h = r.haptics.hands[static_cast<size_t>(Hand::Left)];
  // 200 ms without a model: the haptic thread went on ticking and reading the device, more ticks
  // across the stalled slot than across any ordinary frame (8 ms), and the force never dropped.
  ASSERT_GE(ticks_after_frame.size(), 3u);
  std::vector<uint64_t> gaps;
  for (size_t i = 1; i < ticks_after_frame.size(); ++i)
    gaps.push_back(ticks_after_frame[i] - ticks_after_frame[i - 1]);
  std::sort(gaps.begin(), gaps.end());
  EXPECT_GT(gaps.back(), gaps[gaps.size() / 2]) << "no frame gap held more ticks than the median";
  EXPECT_GT(h.samples, 0u);
  EXPECT_EQ(h.zero_force_ticks, 0u);
}

}  // namespace
}  // namespace phaco
