// Mouse, keyboard and gamepad mapped to the hands (procedures/trainer/desktop_input): the pure
// mapping in the eye's frame, the seqlock handoff under a concurrent writer, and the device.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "procedures/trainer/desktop_input.hpp"

namespace phaco {
namespace {

TEST(DesktopInput, MouseMovesTheTipInTheMicroscopePlane) {
  DesktopMapping m;
  m.mm_per_pixel = 0.02;
  ToolPose p;
  p.pos = {1, 2, 3};
  const ToolPose q = map_mouse_move(p, 50, 100, m);
  EXPECT_NEAR(q.pos.x(), 2.0, 1e-12) << "screen right is +x (3 o'clock)";
  EXPECT_NEAR(q.pos.y(), 0.0, 1e-12) << "screen down is -y (6 o'clock)";
  EXPECT_EQ(q.pos.z(), 3.0);
  const ToolPose w = map_wheel(p, 2, m);
  EXPECT_NEAR(w.pos.z(), 3.0 - 2 * m.depth_mm_per_click, 1e-12) << "wheel forward goes deeper";
  const ToolPose far = map_mouse_move(p, 1e6, 0, m);
  EXPECT_EQ(far.pos.x(), m.workspace_max_mm.x()) << "clamped to the workspace";
  const ToolPose nan = map_mouse_move(p, std::nan(""), 0, m);
  EXPECT_EQ(nan.pos, p.pos);
}

TEST(DesktopInput, ButtonsGripTheForcepsAndPressThePedalOfTheProbe) {
  ToolPose p;
  EXPECT_EQ(map_buttons(p, ToolKind::Forceps, true, false).grip, 1.0);
  EXPECT_EQ(map_buttons(p, ToolKind::Forceps, true, false).pedal, 0.0);
  EXPECT_EQ(map_buttons(p, ToolKind::PhacoProbe, true, false).pedal, 3.0);
  EXPECT_EQ(map_buttons(p, ToolKind::PhacoProbe, false, true).pedal, 2.0);
  EXPECT_EQ(map_buttons(p, ToolKind::PhacoProbe, true, false).grip, 0.0);
}

TEST(DesktopInput, GamepadSticksDriveTheirOwnHands) {
  DesktopMapping m;
  GamepadState pad;
  pad.axes[GamepadState::kLeftX] = 1.0f;    // left hand right
  pad.axes[GamepadState::kRightY] = -1.0f;  // right hand up (superior)
  pad.axes[GamepadState::kRightTrigger] = 1.0f;
  pad.buttons[GamepadState::kLeftBumper] = true;
  ToolPose p;
  const ToolPose l = map_gamepad(p, ToolKind::Forceps, Hand::Left, pad, 0.05, m);
  const ToolPose r = map_gamepad(p, ToolKind::PhacoProbe, Hand::Right, pad, 0.05, m);
  EXPECT_NEAR(l.pos.x(), 0.05 * m.stick_speed_mm_s, 1e-9);
  EXPECT_NEAR(l.pos.y(), 0.0, 1e-9);
  EXPECT_NEAR(l.pos.z(), -0.05 * m.depth_speed_mm_s, 1e-9) << "left bumper: left hand deeper";
  EXPECT_EQ(l.grip, 0.0) << "left trigger released";
  EXPECT_NEAR(r.pos.y(), 0.05 * m.stick_speed_mm_s, 1e-9);
  EXPECT_NEAR(r.pos.x(), 0.0, 1e-9);
  EXPECT_EQ(r.pos.z(), 0.0);
  EXPECT_EQ(r.pedal, 3.0) << "right trigger full on the probe";
  pad.axes[GamepadState::kLeftX] = 0.1f;  // inside the dead zone
  EXPECT_EQ(map_gamepad(p, ToolKind::Forceps, Hand::Left, pad, 0.05, m).pos.x(), 0.0);
}

TEST(DesktopInput, TheSelectedHandFollowsTheMouseAndSwitching) {
  DesktopInput in;
  ToolPose start;
  start.pos = {0, 0, 2};
  in.set_start(Hand::Left, ToolKind::Forceps, start);
  in.set_start(Hand::Right, ToolKind::Cystotome, start);
  EXPECT_EQ(in.selected(), Hand::Right);
  in.mouse_move(100, 0);
  in.switch_hand();
  EXPECT_EQ(in.selected(), Hand::Left);
  in.mouse_buttons(true, false);
  ToolPose l, r;
  in.read_pose(Hand::Left, l);
  in.read_pose(Hand::Right, r);
  EXPECT_EQ(l.pos.x(), 0.0);
  EXPECT_GT(r.pos.x(), 0.5);
  EXPECT_EQ(l.grip, 1.0);
  in.switch_hand();  // the left hand lets go when the mouse leaves it
  in.read_pose(Hand::Left, l);
  EXPECT_EQ(l.grip, 0.0);
}

TEST(DesktopInput, ReadersNeverSeeATornPose) {
  DesktopInput in;
  std::atomic<bool> done{false};
  std::atomic<int> torn{0}, reads{0};
  std::thread reader([&] {
    while (!done.load()) {
      ToolPose p;
      in.read_pose(Hand::Left, p);
      // The writer keeps x == y == -z / 2: any mix of two writes breaks it.
      if (p.pos.y() != p.pos.x() || p.pos.z() != -2 * p.pos.x()) torn.fetch_add(1);
      reads.fetch_add(1);
    }
  });
  DesktopMapping m;
  for (int i = 0; i < 20000 || reads.load() < 1000; ++i) {
    ToolPose p;
    const double v = (i % 100) * 0.01;
    p.pos = {v, v, -2 * v};
    in.set_hand_pose(Hand::Left, p);
  }
  done.store(true);
  reader.join();
  EXPECT_EQ(torn.load(), 0);
  EXPECT_GT(reads.load(), 0);
}

TEST(DesktopInput, TheDeviceReadsANewSampleEveryTick) {
  auto in = std::make_shared<DesktopInput>();
  DesktopDevice dev(in, Hand::Right);
  DeviceSample s;
  EXPECT_FALSE(dev.read(1, s)) << "before start";
  EXPECT_EQ(dev.health(1), DeviceHealth::Silent);
  dev.start(0);
  EXPECT_EQ(dev.health(1), DeviceHealth::Ok);
  EXPECT_FALSE(dev.limits().has_force);
  ToolPose p;
  p.pos = {1, 2, 3};
  in->set_hand_pose(Hand::Right, p);
  ASSERT_TRUE(dev.read(10, s));
  EXPECT_EQ(s.pos_mm, Vec3(1, 2, 3));
  const uint32_t seq = s.seq;
  ASSERT_TRUE(dev.read(20, s));
  EXPECT_EQ(s.seq, seq + 1);
  EXPECT_EQ(s.t_ns, 20);
  dev.write_force(Vec3(1e9, 0, 0), 20);  // ignored
  EXPECT_EQ(dev.counters().accepted, 2u);
}

}  // namespace
}  // namespace phaco
