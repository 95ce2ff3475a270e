// HapticLoop: absolute deadlines, increasing indices, statistics consistent with the ticks seen,
// stop/restart, and an honest real-time status. No timing thresholds: the machine may be loaded
// (or sanitized); overruns are allowed and must then be accounted for exactly.
#include <gtest/gtest.h>
#include <sched.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "engine/haptics/haptic_loop.hpp"
#include "engine/haptics/spin_margin.hpp"

namespace phaco {
namespace {

struct Recorder {
  std::vector<TickInfo> ticks = std::vector<TickInfo>(4000);  // sized before start: no growth
  std::atomic<int> count{0};
  std::atomic<int> policy{-1};  // sched_getscheduler(0) as seen from the loop thread

  static void tick(void* self, const TickInfo& info) {
    auto* r = static_cast<Recorder*>(self);
    // Relaxed: the loop thread is the only writer; the test reads after stop() joined it.
    const int n = r->count.load(std::memory_order_relaxed);
    if (n == 0) r->policy.store(sched_getscheduler(0), std::memory_order_relaxed);
    if (n < static_cast<int>(r->ticks.size())) r->ticks[n] = info;
    r->count.store(n + 1, std::memory_order_relaxed);
  }
};

LoopSettings quiet_settings() {
  LoopSettings s;
  s.realtime = false;
  s.lock_memory = false;  // MCL_FUTURE would stay on for the rest of the test binary
  s.warmup_ticks = 5;
  return s;
}

// Waits until a tick function's counter reaches `ticks`.
void run_until(const std::atomic<int>& count, int ticks) {
  // Relaxed: a progress poll; correctness is checked after the join.
  while (count.load(std::memory_order_relaxed) < ticks)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
}
void run_until(const Recorder& r, int ticks) {
  run_until(r.count, ticks);
}

TEST(HapticLoop, AbsoluteDeadlinesIncreasingIndicesAndExactAccounting) {
  Recorder r;
  HapticLoop loop;
  const LoopSettings settings = quiet_settings();
  loop.start(&Recorder::tick, &r, settings);
  EXPECT_TRUE(loop.running());
  run_until(r, 60);
  loop.stop();
  EXPECT_FALSE(loop.running());

  const int n = r.count.load();
  ASSERT_GE(n, 60);
  ASSERT_LE(n, static_cast<int>(r.ticks.size()));
  const int64_t period = settings.period_ns;
  int64_t overruns = 0, missed_total = 0;
  for (int i = 0; i < n; ++i) {
    const TickInfo& t = r.ticks[i];
    EXPECT_EQ(t.deadline_ns, loop.start_ns() + t.index * period) << i;  // exact, no drift
    EXPECT_GE(t.wake_ns, t.deadline_ns) << i;
    const int64_t missed = (t.wake_ns - t.deadline_ns) / period;
    if (i > 0) {
      EXPECT_GT(t.index, r.ticks[i - 1].index) << i;
    }
    if (i + 1 < n) {
      EXPECT_EQ(r.ticks[i + 1].index, t.index + 1 + missed) << i;  // skip, no burst
    }
    if (i >= settings.warmup_ticks && missed > 0) {
      ++overruns;
      missed_total += missed;
    }
  }
  EXPECT_EQ(r.ticks[0].index, 0);

  const LoopStatsSnapshot s = loop.stats();
  EXPECT_EQ(s.ticks, n - settings.warmup_ticks);  // warm-up not counted
  EXPECT_EQ(s.lateness.count, s.ticks);
  EXPECT_EQ(s.compute.count, s.ticks);
  EXPECT_EQ(s.period.count, s.ticks);  // the first counted tick measures from the last warm-up one
  EXPECT_EQ(s.spin.count, s.ticks);
  // Time spun per tick: counted for every tick, never negative.
  EXPECT_GE(s.spin.min_us, 0.0);
  EXPECT_EQ(s.overruns, overruns);
  EXPECT_EQ(s.missed_deadlines, missed_total);
  EXPECT_GE(s.lateness.min_us, 0.0);
  EXPECT_LE(s.period.min_us, s.period.p50_us);
  EXPECT_LE(s.period.p50_us, s.period.p99_us);
  EXPECT_LE(s.period.p99_us, s.period.p999_us);
  EXPECT_LE(s.period.p999_us, s.period.max_us);
}

TEST(HapticLoop, StopIsIdempotentAndTheLoopRestarts) {
  Recorder r;
  HapticLoop loop;
  loop.stop();  // never started: nothing to do
  loop.start(&Recorder::tick, &r, quiet_settings());
  EXPECT_THROW(loop.start(&Recorder::tick, &r, quiet_settings()), std::logic_error);
  run_until(r, 10);
  loop.stop();
  const int after_stop = r.count.load();
  loop.stop();
  EXPECT_FALSE(loop.running());
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_EQ(r.count.load(), after_stop);  // no tick after stop() returned

  Recorder again;
  loop.start(&Recorder::tick, &again, quiet_settings());
  run_until(again, 10);
  loop.stop();
  EXPECT_EQ(again.ticks[0].index, 0);  // a fresh timeline
  EXPECT_EQ(loop.stats().ticks, again.count.load() - quiet_settings().warmup_ticks);
}

TEST(HapticLoop, RejectsBadSettings) {
  HapticLoop loop;
  Recorder r;
  LoopSettings s = quiet_settings();
  s.period_ns = 0;
  EXPECT_THROW(loop.start(&Recorder::tick, &r, s), std::invalid_argument);
  s = quiet_settings();
  s.spin_ns = -1;
  EXPECT_THROW(loop.start(&Recorder::tick, &r, s), std::invalid_argument);
  s = quiet_settings();
  s.max_spin_ns = -1;
  EXPECT_THROW(loop.start(&Recorder::tick, &r, s), std::invalid_argument);
  s = quiet_settings();
  s.realtime = true;
  s.priority = 0;
  EXPECT_THROW(loop.start(&Recorder::tick, &r, s), std::invalid_argument);
  EXPECT_THROW(loop.start(nullptr, &r, quiet_settings()), std::invalid_argument);
  EXPECT_FALSE(loop.running());
}

// The wait's margin (spin_margin.hpp): the floor when sleeps return on time; raised within the
// tick to cover a late sleep; back to the floor once sleeps are on time again; never past the
// cap; and a fixed margin when the cap is the floor.
TEST(SpinMargin, FollowsTheObservedWakeUpLatencyBetweenFloorAndCap) {
  SpinMargin m{.floor_ns = 60'000, .cap_ns = 250'000};
  EXPECT_EQ(m.margin_ns(), 60'000);
  m.observe_sleep(10'000);  // on time: the floor still covers it
  m.decay();
  EXPECT_EQ(m.margin_ns(), 60'000);
  m.observe_sleep(110'000);           // a loaded core: 110 µs late
  EXPECT_EQ(m.margin_ns(), 130'000);  // the overshoot plus the 20 µs guard, at once
  m.observe_sleep(-5'000);            // a negative reading (clock granularity) is no overshoot
  EXPECT_EQ(m.margin_ns(), 130'000);
  int ticks = 0;
  while (m.margin_ns() > 60'000 && ticks < 100'000) m.decay(), ++ticks;
  EXPECT_GT(ticks, 200);       // remembered for a while: the load comes back
  EXPECT_LT(ticks, 2'000);     // but gone within two seconds at 1 kHz
  m.observe_sleep(5'000'000);  // the vCPU descheduled for 5 ms: no spin can cover that
  EXPECT_EQ(m.margin_ns(), 250'000);
  ticks = 0;
  while (m.margin_ns() > 60'000 && ticks < 100'000) m.decay(), ++ticks;
  EXPECT_LT(ticks, 1'000);  // counted as the cap, not as 5 ms: back at the floor within a second
  SpinMargin carried{.floor_ns = 60'000, .cap_ns = 250'000};
  carried.start_at(170'000);  // a previous loop's margin
  EXPECT_EQ(carried.margin_ns(), 170'000);
  carried.decay();
  EXPECT_LT(carried.margin_ns(), 170'000);  // and forgotten as an overshoot would be
  EXPECT_GT(carried.margin_ns(), 160'000);
  SpinMargin fixed{.floor_ns = 60'000, .cap_ns = 60'000};
  fixed.observe_sleep(200'000);
  EXPECT_EQ(fixed.margin_ns(), 60'000);
  SpinMargin sleep_only{.floor_ns = 0, .cap_ns = 0};
  sleep_only.observe_sleep(200'000);
  EXPECT_EQ(sleep_only.margin_ns(), 0);
}

// The margin tick 0's sleep used, as the loop reports it from inside that tick.
struct FirstMarginProbe {
  const HapticLoop* loop = nullptr;
  std::atomic<int64_t> first_margin_ns{-1};
  std::atomic<int> count{0};
  static void tick(void* self, const TickInfo&) {
    auto* p = static_cast<FirstMarginProbe*>(self);
    // Relaxed: the loop thread is the only writer; the test reads after stop() joined it.
    if (p->count.load(std::memory_order_relaxed) == 0)
      p->first_margin_ns.store(p->loop->spin_margin_ns(), std::memory_order_relaxed);
    p->count.store(p->count.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
};

int64_t first_margin_of(const LoopSettings& settings, int64_t* after_stop = nullptr) {
  HapticLoop loop;
  FirstMarginProbe p;
  p.loop = &loop;
  loop.start(&FirstMarginProbe::tick, &p, settings);
  run_until(p.count, 3);
  loop.stop();
  if (after_stop) *after_stop = loop.spin_margin_ns();
  return p.first_margin_ns.load();
}

// A loop started with a learned margin (the trainer's next procedure step, LoopSettings::
// start_margin_ns) sleeps its first tick with it, not with the floor; the margin stays within
// [spin_ns, max_spin_ns] and is still readable after stop() for the loop that follows.
TEST(HapticLoop, StartedWithAMarginBeginsWithIt) {
  LoopSettings s = quiet_settings();  // floor 60 µs, cap 250 µs
  EXPECT_EQ(first_margin_of(s), 60'000);
  s.start_margin_ns = 180'000;
  int64_t kept = 0;
  EXPECT_EQ(first_margin_of(s, &kept), 180'000);
  EXPECT_GE(kept, 60'000);
  EXPECT_LE(kept, 250'000);
  s.start_margin_ns = 900'000;  // beyond the cap: the cap
  EXPECT_EQ(first_margin_of(s), 250'000);
  s.start_margin_ns = 10'000;  // below the floor: the floor
  EXPECT_EQ(first_margin_of(s), 60'000);
  s.start_margin_ns = -1;
  HapticLoop loop;
  EXPECT_THROW(loop.start(&FirstMarginProbe::tick, nullptr, s), std::invalid_argument);
}

TEST(HapticLoop, WithoutRealtimeReportsNotRequested) {
  Recorder r;
  HapticLoop loop;
  loop.start(&Recorder::tick, &r, quiet_settings());
  run_until(r, 3);
  loop.stop();
  const RealtimeStatus status = loop.realtime_status();
  EXPECT_FALSE(status.requested);
  EXPECT_FALSE(status.memory_locked);
  EXPECT_EQ(status.fifo, r.policy.load() == SCHED_FIFO);  // read back, whatever it inherited
}

TEST(HapticLoop, RealtimeStatusMatchesWhatTheThreadRunsUnder) {
  Recorder r;
  HapticLoop loop;
  LoopSettings s = quiet_settings();
  s.realtime = true;
  s.priority = 10;
  loop.start(&Recorder::tick, &r, s);
  run_until(r, 3);
  loop.stop();
  const RealtimeStatus status = loop.realtime_status();
  EXPECT_TRUE(status.requested);
  const int policy = r.policy.load();
  ASSERT_NE(policy, -1);
  EXPECT_EQ(status.fifo, policy == SCHED_FIFO);
  if (status.fifo) {
    EXPECT_EQ(status.priority, s.priority);
    EXPECT_EQ(status.detail.find("refused"), std::string::npos) << status.detail;
  } else {
    EXPECT_NE(status.detail.find("SCHED_FIFO refused"), std::string::npos) << status.detail;
  }
  std::printf("real-time status: fifo=%d priority=%d detail='%s'\n", status.fifo, status.priority,
              status.detail.c_str());
}

}  // namespace
}  // namespace phaco
