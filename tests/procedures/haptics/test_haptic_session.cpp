// The haptic runtime (procedures/haptics/haptic_session): device → ring → simulation, model →
// triple buffer → haptic thread → force → device; a silent device frees the hand and freezes the
// tool; the haptic thread allocates nothing once running. No scene here, so this runs under TSan.
// Timing is never asserted: the loop runs briefly and the tests wait for conditions.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include "engine/core/clock.hpp"
#include "engine/haptics/device.hpp"
#include "engine/haptics/recording_device.hpp"
#include "engine/haptics/replay_device.hpp"
#include "engine/haptics/sample_bounds.hpp"
#include "engine/haptics/scripted_device.hpp"
#include "engine/haptics/udp_bridge.hpp"
#include "procedures/haptics/haptic_session.hpp"
#include "tests/engine/haptics/alloc_counter.hpp"

namespace phaco {
namespace {

// A device the test moves by hand: a pose, a health switch, the last force it was sent.
class HandDevice final : public Device {
 public:
  std::string_view name() const override { return "test hand"; }
  DeviceLimits limits() const override { return {}; }
  void start(int64_t) override {}
  void stop() override {}
  bool read(int64_t now, DeviceSample& out) override {
    if (alloc_probe.load(std::memory_order_relaxed)) {
      test::count_allocations_on_this_thread(true);  // the haptic thread marks itself
      alloc_probe.store(false, std::memory_order_relaxed);
    }
    out.t_ns = now;
    out.seq = ++seq;
    out.pos_mm = Vec3(x.load(), y.load(), z.load());
    out.grip = grip.load();
    return true;
  }
  void write_force(const Vec3& f, int64_t) override {
    fz.store(f.z());
    fnorm.store(f.norm());
    writes.fetch_add(1);
  }
  DeviceHealth health(int64_t) const override {
    return silent.load() ? DeviceHealth::Silent : DeviceHealth::Ok;
  }

  std::atomic<double> x{0}, y{0}, z{1}, grip{0}, fz{0}, fnorm{0};
  std::atomic<bool> silent{false}, alloc_probe{false};
  std::atomic<uint64_t> writes{0};
  uint32_t seq = 0;  // haptic thread only
};

// Two anchored triangles: the square |x|, |y| ≤ 2 in the plane z = 0, seen from +z.
void wall_model(HapticModel& m, uint64_t sequence) {
  m.sequence = sequence;
  HapticTool& t = m.tools[static_cast<size_t>(Hand::Right)];
  t = HapticTool{};
  t.present = true;
  t.tip_radius_mm = 0.1f;
  t.node_count = 4;
  const float xs[] = {-2, 2, 2, -2}, ys[] = {-2, -2, 2, 2};
  for (uint32_t i = 0; i < 4; ++i) {
    t.x[i] = xs[i], t.y[i] = ys[i], t.z[i] = 0;
    t.kind[i] = HapticNodeKind::Anchored;
  }
  t.triangle_count = 2;
  t.triangles[0] = {0, 1, 2};
  t.triangles[1] = {0, 2, 3};
  t.patch_stiffness_mn_per_mm = 0;  // rigid
  t.tip_mm = {0, 0, 1};
}

HapticSessionConfig quiet_config() {
  HapticSessionConfig c;
  c.loop.realtime = false;  // CI machines may refuse SCHED_FIFO; the logic is the same
  c.loop.lock_memory = false;
  c.loop.warmup_ticks = 0;
  return c;
}

template <class F>
bool wait_for(F&& condition, double seconds = 3.0) {
  const int64_t until = now_ns() + static_cast<int64_t>(seconds * 1e9);
  while (now_ns() < until) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return condition();
}

TEST(HapticSession, TheWallPushesBackOnlyWhenTouched) {
  HapticSession session(quiet_config());
  auto dev = std::make_unique<HandDevice>();
  HandDevice* hand = dev.get();
  session.attach(Hand::Right, std::move(dev));
  wall_model(session.model_slot(), 1);
  session.publish_model();
  session.start();

  ASSERT_TRUE(wait_for([&] { return hand->writes.load() > 20; }));
  EXPECT_EQ(hand->fnorm.load(), 0.0) << "1 mm above the wall: no force";

  hand->z.store(-0.2);  // 0.3 mm into the wall (tip radius 0.1)
  ASSERT_TRUE(wait_for([&] { return hand->fz.load() > 1.0; }))
      << "the wall pushes the hand out (+z)";
  const double pushed = hand->fz.load();
  hand->z.store(-0.4);
  ASSERT_TRUE(wait_for([&] { return hand->fz.load() > pushed + 1.0; })) << "deeper pushes harder";
  hand->z.store(2.0);
  ASSERT_TRUE(wait_for([&] { return hand->fnorm.load() == 0.0; })) << "lifted off: no force";
  session.stop();

  const HapticSessionStats s = session.stats();
  const HapticHandStats& h = s.hands[static_cast<size_t>(Hand::Right)];
  EXPECT_TRUE(h.attached);
  EXPECT_GT(h.ticks, 20u);
  EXPECT_EQ(h.samples, h.ticks) << "this device gives a new sample every tick";
  EXPECT_GE(h.models_adopted, 1u);
  EXPECT_EQ(h.zero_force_ticks, 0u);
  EXPECT_EQ(h.latency.count, static_cast<int64_t>(h.samples));
  EXPECT_GE(h.latency.min_us, 0.0) << "a force is never written before its sample";
  EXPECT_FALSE(s.realtime.requested);
  EXPECT_FALSE(s.realtime.fifo);
}

TEST(HapticSession, TheSimulationGetsTheNewestPoseAndASilentDeviceFreezesIt) {
  HapticSession session(quiet_config());
  auto dev = std::make_unique<HandDevice>();
  HandDevice* hand = dev.get();
  session.attach(Hand::Right, std::move(dev));
  ToolPose pose;
  EXPECT_FALSE(session.newest_pose(Hand::Left, pose))
      << "no device in the left hand: its track drives it";
  EXPECT_FALSE(session.newest_pose(Hand::Right, pose)) << "no sample yet";
  EXPECT_FALSE(session.drives(Hand::Left));
  EXPECT_TRUE(session.drives(Hand::Right)) << "before its first sample too: the scene holds it";
  wall_model(session.model_slot(), 1);
  session.publish_model();
  session.start();

  hand->x.store(0.5), hand->z.store(-0.3);  // pressing into the wall
  ASSERT_TRUE(
      wait_for([&] { return session.newest_pose(Hand::Right, pose) && pose.pos.x() == 0.5; }));
  ASSERT_TRUE(wait_for([&] { return hand->fnorm.load() > 1.0; }));

  hand->silent.store(true);  // the device stops reporting
  ASSERT_TRUE(wait_for([&] { return hand->fnorm.load() == 0.0; })) << "silent: the hand is let go";
  const auto zeroed = session.stats().hands[static_cast<size_t>(Hand::Right)].zero_force_ticks;
  EXPECT_GT(zeroed, 0u);
  session.stop();
  EXPECT_TRUE(session.newest_pose(Hand::Right, pose));
  EXPECT_DOUBLE_EQ(pose.pos.x(), 0.5) << "the tool stays where the device left it";
  EXPECT_EQ(session.last_force(Hand::Right), Vec3::Zero());
}

TEST(HapticSession, TheHapticThreadAllocatesNothingOnceRunning) {
  if (!test::haptic_allocation_counting_available())
    GTEST_SKIP() << "operator new is the sanitizer's here";
  HapticSession session(quiet_config());
  auto dev = std::make_unique<HandDevice>();
  HandDevice* hand = dev.get();
  session.attach(Hand::Right, std::move(dev));
  wall_model(session.model_slot(), 1);
  session.publish_model();
  session.start();
  ASSERT_TRUE(wait_for([&] { return hand->writes.load() > 50; }));  // started up

  test::open_allocation_window();
  hand->alloc_probe.store(true);
  ASSERT_TRUE(wait_for([&] { return !hand->alloc_probe.load(); }));
  const uint64_t before = hand->writes.load();
  // New models, contact and no contact, for a few hundred ticks.
  for (int k = 0; k < 30; ++k) {
    wall_model(session.model_slot(), 2 + k);
    session.publish_model();
    hand->z.store(k % 2 ? -0.3 : 0.5);
    std::this_thread::sleep_for(std::chrono::milliseconds(8));
  }
  ASSERT_TRUE(wait_for([&] { return hand->writes.load() > before + 200; }));
  hand->silent.store(true);  // the silent path too
  ASSERT_TRUE(wait_for([&] { return hand->writes.load() > before + 250; }));
  const long allocations = test::allocations_on_marked_threads();
  session.stop();
  test::close_allocation_window();
  EXPECT_EQ(allocations, 0) << "the haptic thread allocated";
}

// ---------------------------------------------------------------------------------------------
// Deterministic ticks (HapticSession::step): each tick runs at a given instant, no thread.

constexpr int64_t kMs = 1'000'000;

TickInfo tick_at(int64_t k, int64_t t) {
  return TickInfo{k, t, t};
}

// A track for the right hand: pressing into the wall, then samples the bounds must catch, each
// held 2 ms, then pressing again with the pedal out of range (clamped, kept).
HandTrack faulty_track() {
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  HandTrack h;
  h.hand = Hand::Right;
  auto at = [&](double t_ms, Vec3 pos, double pedal = 0) {
    TrackSample x;
    x.t = t_ms * 1e-3, x.pos = pos, x.pedal = pedal;
    h.track.push_back(x);
  };
  at(0, Vec3(0, 0, -0.2));                   // seq 1: good, in contact
  at(2, Vec3(1.2e19, 0, 0));                 // seq 2: outside the workspace
  at(4, Vec3(0, kNaN, 0));                   // seq 3: non-finite
  at(6, Vec3(0, 0, -kWorkspaceHalfMm - 1));  // seq 4: outside, just
  at(8, Vec3(0.5, 0, -0.3), 7.0);            // seq 5: good, pedal clamped to 3
  return h;
}

// Steps `session` at start + k ms, k = 0..9, checking after every tick that nothing out of
// bounds reached the simulation's side or the force.
void step_and_check(HapticSession& session, int64_t start) {
  for (int64_t k = 0; k < 10; ++k) {
    session.step(tick_at(k, start + k * kMs));
    ToolPose pose;
    ASSERT_TRUE(session.newest_pose(Hand::Right, pose)) << "tick " << k;
    EXPECT_TRUE(pose.pos.allFinite()) << "tick " << k;
    EXPECT_LE(pose.pos.cwiseAbs().maxCoeff(), kWorkspaceHalfMm) << "tick " << k;
    EXPECT_LE(pose.pedal, kMaxPedal) << "tick " << k;
    // Dropped samples leave the tool where the good one had it: still pressing, still pushed.
    EXPECT_LT(pose.pos.z(), 0.0) << "tick " << k;
    const Vec3 f = session.last_force(Hand::Right);
    EXPECT_TRUE(f.allFinite()) << "tick " << k;
    EXPECT_GT(f.z(), 1.0) << "tick " << k << ": the wall still pushes on the last good pose";
  }
}

// `dev` started at `start` in the right hand, the wall published.
void attach_at_the_wall(HapticSession& session, std::unique_ptr<Device> dev, int64_t start) {
  dev->start(start);
  session.attach(Hand::Right, std::move(dev));
  wall_model(session.model_slot(), 1);
  session.publish_model();
}

TEST(HapticSessionBounds, ReplayAndRecordingDropAndCountOutOfBoundsSamples) {
  DeviceRecorder recorder(64);
  for (const bool recording : {false, true}) {
    SCOPED_TRACE(recording ? "recording passthrough of a replay" : "replay");
    HapticSession session(quiet_config());
    std::unique_ptr<Device> dev = std::make_unique<ReplayDevice>(faulty_track());
    if (recording) dev = recording_device(std::move(dev), recorder);
    const int64_t start = 1'000 * kMs;
    attach_at_the_wall(session, std::move(dev), start);
    step_and_check(session, start);
    const HapticHandStats h = session.stats().hands[static_cast<size_t>(Hand::Right)];
    // Sample-and-hold at 2 ms per sample: each is read twice and counted once.
    EXPECT_EQ(h.samples, 2u) << "seq 1 and seq 5 reach the physics";
    EXPECT_EQ(h.samples_outside_workspace, 2u);
    EXPECT_EQ(h.samples_non_finite, 1u);
    EXPECT_EQ(h.samples_clamped, 1u);
    ToolPose pose;
    ASSERT_TRUE(session.newest_pose(Hand::Right, pose));
    EXPECT_EQ(pose.pos, Vec3(0.5, 0, -0.3));
    EXPECT_EQ(pose.pedal, kMaxPedal);
  }
  // The recording holds only what passed, clamped as the physics got it.
  ASSERT_EQ(recorder.size(), 2u);
  EXPECT_EQ(recorder.rejected(), 3u);
  EXPECT_EQ(recorder.samples()[1].pedal, kMaxPedal);
}

TEST(HapticSessionBounds, ScriptedTrackOutOfBoundsIsDroppedEveryTick) {
  // Interpolated between a good pose and 1.2e19 mm: every tick after the first is outside.
  HandTrack h = faulty_track();
  h.track.resize(2);
  HapticSession session(quiet_config());
  const int64_t start = 1'000 * kMs;
  attach_at_the_wall(session, std::make_unique<ScriptedDevice>(h), start);
  step_and_check(session, start);
  const HapticHandStats s = session.stats().hands[static_cast<size_t>(Hand::Right)];
  EXPECT_EQ(s.samples, 1u);
  EXPECT_EQ(s.samples_outside_workspace, 9u) << "a new sample each tick, each counted";
  EXPECT_EQ(s.samples_non_finite, 0u);
}

// A UDP bridge on loopback, packets into the wall. The device's receive time of the last packet
// comes back with the sample; ticks then run at chosen instants after it.
struct UdpHand {
  UdpBridgePeer peer;
  UdpBridgeDevice* device = nullptr;
  uint32_t seq = 0;
  explicit UdpHand(HapticSession& session,
                   double silence_ms = UdpBridgeConfig{}.silence_timeout_ms) {
    UdpBridgeConfig c;
    c.bind_host = "127.0.0.1";
    c.peer_host = "127.0.0.1";
    c.peer_port = peer.local_port();
    c.silence_timeout_ms = silence_ms;
    c.max_age_ms = 1000;
    auto dev = std::make_unique<UdpBridgeDevice>(c);
    device = dev.get();
    peer.set_device("127.0.0.1", device->local_port());
    device->start(now_ns());
    session.attach(Hand::Right, std::move(dev));
  }
  udp_protocol::PoseMessage pose(float x, float y, float z) {
    udp_protocol::PoseMessage m;
    m.seq = ++seq;
    m.sender_time_us = steady_time_us();
    m.pos_mm = {x, y, z};
    return m;
  }
  // Sends a pose until the device shows it while live (a read later than the silence timeout
  // reads as silence: a slow machine just takes another try) and returns its receive time.
  int64_t deliver(float z) {
    for (int attempt = 0; attempt < 1000; ++attempt) {
      peer.send(pose(0, 0, z));
      DeviceSample s;
      const int64_t give_up = now_ns() + 20 * kMs;
      while (now_ns() < give_up) {
        if (device->read(now_ns(), s) && s.seq == seq) return s.t_ns;
      }
    }
    return -1;
  }
};

// Issue 18: when packets stop, the tool freezes and the force goes to zero within 5 ms. Ticks run
// at the loop's period from the last packet's receive time, at several phases of the tick
// against the packet; every tick up to the silence timeout still pushes (so the zero is the
// silence's doing), and the first zero comes no later than 5 ms after the last packet.
TEST(HapticSessionSilence, ForceIsZeroAndToolFrozenWithin5msOfTheLastPacket) {
  HapticSession session(quiet_config());
  UdpHand udp(session);
  wall_model(session.model_slot(), 1);
  session.publish_model();
  const int64_t period = quiet_config().loop.period_ns;
  const int64_t timeout_ns = std::llround(UdpBridgeConfig{}.silence_timeout_ms * 1e6);
  int64_t k = 0;
  for (const int64_t phase : {int64_t{0}, period / 4, period / 2, period - 1}) {
    SCOPED_TRACE("tick phase " + std::to_string(phase) + " ns");
    const float z = -0.2f - 0.01f * static_cast<float>(k % 7);
    const int64_t last = udp.deliver(z);
    ASSERT_GT(last, 0) << "no packet read back within the silence timeout in 1000 tries";
    int64_t first_zero = -1;
    for (int64_t t = last + phase; t <= last + 20 * kMs; t += period) {
      session.step(tick_at(k++, t));
      const Vec3 f = session.last_force(Hand::Right);
      ToolPose pose;
      ASSERT_TRUE(session.newest_pose(Hand::Right, pose));
      EXPECT_FLOAT_EQ(static_cast<float>(pose.pos.z()), z) << "frozen at the last pose";
      if (t - last <= timeout_ns) {
        EXPECT_GT(f.z(), 1.0) << "live at " << (t - last) << " ns: the wall pushes";
      } else if (first_zero < 0) {
        first_zero = t - last;
      }
      if (first_zero >= 0) {
        EXPECT_EQ(f, Vec3::Zero()) << "at " << (t - last) << " ns";
      }
    }
    ASSERT_GE(first_zero, 0);
    EXPECT_LE(first_zero, 5 * kMs) << "silence to zero force";
  }
  const HapticHandStats h = session.stats().hands[static_cast<size_t>(Hand::Right)];
  EXPECT_GT(h.zero_force_ticks, 0u);
  EXPECT_EQ(h.samples, 4u);
  udp.device->stop();
}

TEST(HapticSessionBounds, UdpPacketsOutOfBoundsStopAtTheBridge) {
  HapticSession session(quiet_config());
  UdpHand udp(session, /*silence_ms=*/60'000);
  wall_model(session.model_slot(), 1);
  session.publish_model();
  ASSERT_GT(udp.deliver(-0.2f), 0);
  udp.peer.send(udp.pose(1e19f, 0, 0));
  udp.peer.send(udp.pose(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  ASSERT_TRUE(wait_for([&] {
    const DeviceCounters c = udp.device->counters();
    return c.out_of_workspace == 1 && c.non_finite == 1;
  }));
  step_and_check(session, now_ns());
  const HapticHandStats h = session.stats().hands[static_cast<size_t>(Hand::Right)];
  EXPECT_EQ(h.samples, 1u);
  EXPECT_EQ(h.samples_outside_workspace + h.samples_non_finite, 0u) << "the bridge dropped them";
  EXPECT_EQ(h.counters.dropped(), 2u);
  udp.device->stop();
}

TEST(HapticSession, StepIsRefusedWhileTheThreadRuns) {
  HapticSession session(quiet_config());
  session.attach(Hand::Right, std::make_unique<HandDevice>());
  session.start();
  EXPECT_THROW(session.step(tick_at(0, now_ns())), std::logic_error);
  session.stop();
}

}  // namespace
}  // namespace phaco
