// The ports' mode of each input in the trainer (procedures/trainer/live_ports, issue 20 item 2):
// live inputs get "constrain" unless the scenario chooses, tracks keep the drill's "measure", and
// the desktop input's shaft pivots in its hand's port (main: right, side: left; not the keratome).
#include <gtest/gtest.h>

#include "procedures/trainer/desktop_input.hpp"
#include "procedures/trainer/live_ports.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

std::string mode(const Scenario& s) {
  const auto it = s.methods.find("tools.ports");
  return it == s.methods.end() ? "" : it->second;
}

TEST(LivePorts, LiveInputsConstrainTracksKeepTheDrillsMode) {
  const Scenario s = test::repo_scenario("phaco_sculpting_expert.json");
  EXPECT_EQ(mode(with_live_ports(s, {"", "desktop"})), "constrain");
  EXPECT_EQ(mode(with_live_ports(s, {"", "udp:7000@127.0.0.1:7001"})), "constrain");
  EXPECT_EQ(mode(with_live_ports(s, {"", "openhaptics"})), "constrain");
  EXPECT_EQ(mode(with_live_ports(s, {"", "track"})), "") << "the drill file's measure";
  EXPECT_EQ(mode(with_live_ports(s, {"", "scripted"})), "");
  EXPECT_EQ(mode(with_live_ports(s, {"desktop", "track"})), "")
      << "the sculpting scenario has no left hand: nothing live drives a tool";
  Scenario chosen = s;
  chosen.methods["tools.ports"] = "measure";
  EXPECT_EQ(mode(with_live_ports(chosen, {"", "desktop"})), "measure") << "the scenario's choice";
  EXPECT_FALSE(is_live_device("replay:x.json"));
}

TEST(LivePorts, TheDesktopShaftPivotsInItsHandsPort) {
  const Scenario s =
      with_live_ports(test::repo_scenario("capsulorhexis_expert.json"), {"desktop", "desktop"});
  const auto ports = desktop_ports(s);
  ASSERT_TRUE(ports[static_cast<size_t>(Hand::Right)] && ports[static_cast<size_t>(Hand::Left)]);
  EXPECT_EQ(ports[static_cast<size_t>(Hand::Right)]->name, "main");
  EXPECT_EQ(ports[static_cast<size_t>(Hand::Left)]->name, "side");
  const auto incision = desktop_ports(
      with_live_ports(test::repo_scenario("corneal_incision_expert.json"), {"desktop", "desktop"}));
  EXPECT_FALSE(incision[static_cast<size_t>(Hand::Right)]) << "the keratome cuts its port";

  // The mouse moves the tip across the chamber; every published pose's shaft passes the centre.
  const EyePort& port = *ports[static_cast<size_t>(Hand::Right)];
  DesktopInput in;
  in.set_port(Hand::Right, port);
  in.set_start(Hand::Right, ToolKind::Forceps, {Vec3(1.5, -1.0, 1.6), Quat::Identity(), 0, 0});
  in.select(Hand::Right);
  for (int i = 0; i < 10; ++i) {
    in.mouse_move(-30, -15);
    ToolPose p;
    in.read_pose(Hand::Right, p);
    const Vec3 shaft = p.quat * Vec3::UnitZ();
    const Vec3 d = port.centre_mm - p.pos;
    EXPECT_LT((d - d.dot(shaft) * shaft).norm(), 1e-9) << "step " << i;
  }
  in.set_port(Hand::Right, std::nullopt);
  ToolPose p;
  in.read_pose(Hand::Right, p);
  EXPECT_TRUE(p.quat.isApprox(Quat::Identity())) << "no port: the start orientation";
}

}  // namespace
}  // namespace phaco
