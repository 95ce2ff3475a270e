// The trainer session (procedures/trainer/trainer_session): start, pause, resume, reset and
// finish with scripted devices on the capsulorhexis expert; the stored recording replays to the
// stored state hash (headless) and replay_last() reaches it live; a renderer that sleeps 200 ms
// per snapshot slows neither the simulation nor the haptic loop.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "engine/core/error.hpp"
#include "engine/records/records.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/trainer/trainer_session.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

using namespace std::chrono_literals;

TrainerConfig config(double duration_s) {
  TrainerConfig c;
  c.scenario = test::repo_scenario("capsulorhexis_expert.json");
  c.devices = {"scripted", "scripted"};
  c.duration_s = duration_s;
  c.scene.cache_dir = test::scene_cache_dir();
  c.haptics.loop.realtime = false;  // CI may refuse SCHED_FIFO; the logic is the same
  c.haptics.loop.lock_memory = false;
  c.haptics.loop.warmup_ticks = 0;
  return c;
}

void wait_for(TrainerSession& s, TrainerState state, std::chrono::milliseconds limit) {
  const auto until = std::chrono::steady_clock::now() + limit;
  while (s.state() != state && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(10ms);
}

TEST(TrainerSession, StartPauseResumeResetFinish) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "real-time drills run in the Release pass";
#endif
  TrainerSession s(config(1.0));
  EXPECT_EQ(s.state(), TrainerState::Idle);
  EXPECT_EQ(s.newest_snapshot(), nullptr);
  s.start();
  EXPECT_EQ(s.state(), TrainerState::Running);
  const render::RenderSnapshot* snap = s.newest_snapshot();
  ASSERT_NE(snap, nullptr) << "start() returns once the first snapshot is published";
  EXPECT_EQ(snap->bodies.size(), 4u);
  EXPECT_EQ(snap->tools.size(), 2u);

  std::this_thread::sleep_for(200ms);
  s.pause();
  EXPECT_EQ(s.state(), TrainerState::Paused);
  std::this_thread::sleep_for(50ms);  // the frame in progress, if any, ends
  const uint64_t paused_frame = s.status().frame;
  EXPECT_GT(paused_frame, 1u);
  std::this_thread::sleep_for(200ms);
  EXPECT_EQ(s.status().frame, paused_frame) << "no frames while paused";
  EXPECT_GT(s.status().haptic_ticks, 100) << "the haptic loop runs on while paused";
  s.resume();
  wait_for(s, TrainerState::Ended, 5s);
  EXPECT_EQ(s.state(), TrainerState::Ended);
  const TrainerStatus st = s.status();
  EXPECT_EQ(st.frame, 120u) << "1 s at dt 1/120";
  EXPECT_GT(st.sim_rate_hz, 0.0);

  s.reset();
  EXPECT_EQ(s.state(), TrainerState::Running);
  EXPECT_LT(s.status().frame, 60u) << "a fresh scene";
  const nlohmann::json r = s.finish();
  EXPECT_EQ(s.state(), TrainerState::Idle);
  EXPECT_TRUE(r.contains("metrics"));
  EXPECT_TRUE(r["metrics"].contains("score"));
  EXPECT_TRUE(r.contains("state_hash"));
  EXPECT_TRUE(r.contains("live"));
  EXPECT_GT(r["live"]["haptics"]["hands"]["left"]["samples"].get<uint64_t>(), 0u);
  EXPECT_GT(r["recorded_from"]["left"]["samples"].get<uint64_t>(), 0u);
}

TEST(TrainerSession, TheRecordedRunReplaysToTheSameHash) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "real-time drills run in the Release pass";
#endif
  const auto db = std::filesystem::temp_directory_path() /
                  ("trainer-test-" + std::to_string(::getpid()) + ".sqlite");
  std::filesystem::remove(db);
  TrainerConfig c = config(1.0);
  c.trainee = "trainee one";
  c.records_db = db;
  TrainerSession s(c);
  s.start();
  wait_for(s, TrainerState::Ended, 6s);
  const nlohmann::json r = s.finish();
  ASSERT_TRUE(r.contains("record_id"));
  const std::string hash = r["state_hash"];

  // The stored record: its recording, run headless, gives its state hash.
  const RecordStore store(db, OpenMode::ExistingOnly);
  const auto rec = store.record(r["record_id"].get<int64_t>());
  ASSERT_TRUE(rec.has_value());
  EXPECT_EQ(rec->state_hash, hash);
  EXPECT_EQ(rec->trainee, "trainee one");
  const Scenario recording = parse_scenario(rec->recording.dump(), "record", db.parent_path());
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  EXPECT_EQ(run_scenario(recording, o).state_hash, hash);

  // The live replay on the recorded tracks steps exactly as the record's replay.
  s.replay_last();
  wait_for(s, TrainerState::Ended, 6s);
  const nlohmann::json again = s.finish();
  EXPECT_EQ(again["live_state_hash"], hash);
  std::filesystem::remove(db);
}

TEST(TrainerSession, ASlowRendererSlowsNeitherSimulationNorHaptics) {
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
  GTEST_SKIP() << "rates are measured in the Release pass";
#endif
  TrainerSession s(config(3.0));
  s.start();
  std::atomic<bool> done{false};
  std::atomic<int> reads{0};
  std::thread renderer([&] {
    while (!done.load()) {
      if (s.newest_snapshot()) reads.fetch_add(1);
      std::this_thread::sleep_for(200ms);  // a very slow renderer
    }
  });
  const TrainerStatus a = s.status();
  const auto t0 = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(1s);
  const TrainerStatus b = s.status();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  done.store(true);
  renderer.join();
  s.stop();
  const double dt = config(3.0).scenario.dt_s;
  std::printf(
      "slow renderer: %llu frames, %lld haptic ticks over %.3f s wall; %d reads, %llu "
      "snapshots published\n",
      static_cast<unsigned long long>(b.frame - a.frame),
      static_cast<long long>(b.haptic_ticks - a.haptic_ticks), wall, reads.load(),
      static_cast<unsigned long long>(b.snapshots_published - a.snapshots_published));
  EXPECT_GE(static_cast<double>(b.frame - a.frame), 0.8 * wall / dt)
      << "frames simulated over " << wall << " s";
  EXPECT_GE(static_cast<double>(b.haptic_ticks - a.haptic_ticks), 0.7 * wall * 1000);
  EXPECT_GT(b.snapshots_published - a.snapshots_published, 50u * reads.load() / 10);
  EXPECT_GE(reads.load(), 4);
}

TEST(TrainerSession, BadDeviceSpecsAndFinishBeforeStartAreInputErrors) {
  TrainerConfig c = config(1.0);
  c.devices = {"joystick", "desktop"};
  EXPECT_THROW(TrainerSession{c}, InputError);
  TrainerSession s(config(1.0));
  EXPECT_THROW(s.finish(), InputError);
  EXPECT_THROW(s.replay_last(), InputError);
}

}  // namespace
}  // namespace phaco
