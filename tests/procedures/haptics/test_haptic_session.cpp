// The haptic runtime (procedures/haptics/haptic_session): device → ring → simulation, model →
// triple buffer → haptic thread → force → device; a silent device frees the hand and freezes the
// tool; the haptic thread allocates nothing once running. No scene here, so this runs under TSan.
// Timing is never asserted: the loop runs briefly and the tests wait for conditions.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "engine/core/clock.hpp"
#include "engine/haptics/device.hpp"
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

}  // namespace
}  // namespace phaco
