// Device specs: each good form makes its device; each bad one names what is wrong.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "engine/core/error.hpp"
#include "engine/haptics/device_factory.hpp"
#include "engine/haptics/openhaptics_device.hpp"
#include "engine/haptics/replay_device.hpp"
#include "engine/haptics/udp_bridge.hpp"

namespace phaco {
namespace {

std::string error_of(std::string_view spec, const DeviceContext& ctx = {}) {
  try {
    make_device(spec, ctx);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an InputError for '" << spec << "'";
  return {};
}

Scenario one_hand_scenario() {
  Scenario s;
  s.source = "demo.json";
  s.duration_s = 1;
  HandTrack h;
  h.hand = Hand::Right;
  h.track.resize(1);
  s.hands.push_back(h);
  return s;
}

TEST(DeviceFactory, ParsesEachForm) {
  DeviceSpec s = parse_device_spec("udp:0@127.0.0.1:5006");
  EXPECT_EQ(s.kind, DeviceKind::Udp);
  EXPECT_EQ(s.local_port, 0);
  EXPECT_EQ(s.peer_host, "127.0.0.1");
  EXPECT_EQ(s.peer_port, 5006);
  s = parse_device_spec("replay:/tmp/a:b.json:left");
  EXPECT_EQ(s.kind, DeviceKind::Replay);
  EXPECT_EQ(s.file, "/tmp/a:b.json");
  EXPECT_EQ(s.hand, Hand::Left);
  s = parse_device_spec("replay:rec.json");
  EXPECT_FALSE(s.hand.has_value());
  s = parse_device_spec("scripted:right");
  EXPECT_EQ(s.hand, Hand::Right);
  s = parse_device_spec("openhaptics:Left Touch");
  EXPECT_EQ(s.kind, DeviceKind::OpenHaptics);
  EXPECT_EQ(s.device_name, "Left Touch");
}

TEST(DeviceFactory, MakesScriptedUdpAndReplayDevices) {
  const Scenario sc = one_hand_scenario();
  DeviceContext ctx;
  ctx.scenario = &sc;
  auto d = make_device("scripted", ctx);
  EXPECT_EQ(d->name(), "scripted:right");

  auto u = make_device("udp:0@127.0.0.1:9");
  ASSERT_NE(dynamic_cast<UdpBridgeDevice*>(u.get()), nullptr);
  EXPECT_NE(dynamic_cast<UdpBridgeDevice*>(u.get())->local_port(), 0);

  DeviceRecorder rec(2);
  DeviceSample s;
  s.t_ns = 10;
  s.seq = 1;
  rec.record(s);
  const auto file = std::filesystem::temp_directory_path() /
                    ("phaco_test_factory_" + std::to_string(::getpid()) + ".json");
  rec.write(file, sc, Hand::Left, ToolKind::Forceps);  // now two hands
  auto r = make_device("replay:" + file.string() + ":left");
  EXPECT_NE(dynamic_cast<ReplayDevice*>(r.get()), nullptr);
  EXPECT_EQ(dynamic_cast<ReplayDevice*>(r.get())->track().hand, Hand::Left);
  std::filesystem::remove(file);
}

TEST(DeviceFactory, BadSpecsNameTheProblem) {
  using testing::HasSubstr;
  EXPECT_THAT(error_of(""), HasSubstr("empty device spec"));
  EXPECT_THAT(error_of("mouse"), HasSubstr("unknown device 'mouse'"));
  EXPECT_THAT(error_of("udp:5005"), HasSubstr("expected udp:LOCALPORT@PEERHOST:PEERPORT"));
  EXPECT_THAT(error_of("udp:abc@127.0.0.1:9"), HasSubstr("local port 'abc' is not a port"));
  EXPECT_THAT(error_of("udp:70000@127.0.0.1:9"), HasSubstr("local port '70000'"));
  EXPECT_THAT(error_of("udp:0@127.0.0.1"), HasSubstr("has no port"));
  EXPECT_THAT(error_of("udp:0@:9"), HasSubstr("peer host is empty"));
  EXPECT_THAT(error_of("udp:0@127.0.0.1:0"),
              HasSubstr("peer port '0' is not a port number in 1..65535"));
  EXPECT_THAT(error_of("scripted:middle"), HasSubstr("unknown hand 'middle'"));
  EXPECT_THAT(error_of("scripted"), HasSubstr("needs a scenario"));
  const Scenario sc = one_hand_scenario();
  DeviceContext ctx;
  ctx.scenario = &sc;
  EXPECT_THAT(error_of("scripted:left", ctx), HasSubstr("has no left hand"));
  EXPECT_THAT(error_of("replay:"), HasSubstr("missing the recording file"));
  EXPECT_THAT(error_of("replay:/nonexistent/rec.json"), HasSubstr("/nonexistent/rec.json"));
  EXPECT_THAT(error_of("openhaptics:"), HasSubstr("empty device name"));
  if (!openhaptics_available()) {
    EXPECT_THAT(error_of("openhaptics"), HasSubstr("no OpenHaptics support"));
  }
}

}  // namespace
}  // namespace phaco
