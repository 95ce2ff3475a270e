// Scripted device against sample_track; recording → scenario JSON → load → replay, identical.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "engine/core/error.hpp"
#include "engine/haptics/replay_device.hpp"
#include "engine/haptics/scripted_device.hpp"
#include "engine/io/track.hpp"

namespace phaco {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

HandTrack demo_track() {
  HandTrack h;
  h.hand = Hand::Left;
  h.tool = ToolKind::Forceps;
  TrackSample a, b, c;
  a.t = 0.0;
  a.pos = Vec3(-1, 0, 3.5);
  b.t = 0.5;
  b.pos = Vec3(0, 1, 2.0);
  b.quat = Quat(Eigen::AngleAxisd(0.8, Vec3::UnitX()));
  b.grip = 1.0;
  c.t = 1.25;
  c.pos = Vec3(0.5, 1, 1.8);
  c.pedal = 3.0;
  h.track = {a, b, c};
  return h;
}

TEST(ScriptedDevice, FollowsSampleTrackAndEndsAfterTheTrack) {
  const HandTrack h = demo_track();
  ScriptedDeviceOptions o;
  o.hold_s = 0.1;
  o.force_log_size = 8;
  ScriptedDevice dev(h, o);
  DeviceSample s;
  EXPECT_FALSE(dev.read(0, s));
  EXPECT_EQ(dev.health(0), DeviceHealth::Silent);

  const int64_t start = 5 * kSecond;
  dev.start(start);
  uint32_t last_seq = 0;
  for (int ms = 0; ms <= 1400; ms += 7) {
    const int64_t now = start + ms * 1'000'000LL;
    ASSERT_TRUE(dev.read(now, s));
    // The device's time is (now − start) ns × 1e-9, the same arithmetic here.
    const ToolPose ref = sample_track(h.track, static_cast<double>(now - start) * 1e-9);
    EXPECT_EQ(s.pos_mm, ref.pos) << ms;
    EXPECT_EQ(s.quat.coeffs(), ref.quat.coeffs()) << ms;
    EXPECT_EQ(s.grip, ref.grip);
    EXPECT_EQ(s.pedal, ref.pedal);
    EXPECT_EQ(s.t_ns, now);
    EXPECT_GT(s.seq, last_seq);
    last_seq = s.seq;
    EXPECT_EQ(dev.health(now), ms <= 1350 ? DeviceHealth::Ok : DeviceHealth::Ended) << ms;
    dev.write_force(Vec3(ms, 0, 0), now);
  }
  // The ring keeps the last 8 forces, oldest first.
  const std::vector<ForceRecord> f = dev.forces().recent();
  ASSERT_EQ(f.size(), 8u);
  EXPECT_EQ(f.back().force_mn.x(), 1400.0);
  EXPECT_EQ(f.front().force_mn.x(), 1400.0 - 7 * 7);
  EXPECT_EQ(dev.forces().total(), 201u);
  EXPECT_EQ(dev.counters().accepted, 201u);
}

TEST(ScriptedDevice, EmptyTrackIsAnInputError) {
  HandTrack h;
  EXPECT_THROW(ScriptedDevice{h}, InputError);
}

// A device-like stream: irregular receive times, float-ish poses, repeated reads of one sample.
std::vector<DeviceSample> device_stream(int n) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::uniform_int_distribution<int64_t> gap(200'000, 3'000'000);
  std::vector<DeviceSample> out;
  int64_t t = 123 * kSecond + 456;
  for (int i = 0; i < n; ++i) {
    DeviceSample s;
    t += gap(rng);
    s.t_ns = t;
    s.seq = 1000 + static_cast<uint32_t>(i);
    s.pos_mm = Vec3(float(u(rng) * 5), float(u(rng) * 5), float(u(rng) * 5 + 2));
    s.quat = Quat(u(rng), u(rng), u(rng), u(rng)).normalized();
    s.grip = 0.5 + 0.5 * u(rng);
    s.pedal = 1.5 + 1.5 * u(rng);
    out.push_back(s);
    out.push_back(s);  // the haptic loop reads the same sample again
  }
  return out;
}

TEST(DeviceRecorder, RecordWriteLoadReplayGivesIdenticalSamples) {
  const std::vector<DeviceSample> stream = device_stream(300);
  DeviceRecorder rec(300);
  for (const DeviceSample& s : stream) rec.record(s);
  ASSERT_EQ(rec.size(), 300u);
  EXPECT_EQ(rec.dropped(), 0u);

  Scenario base;
  base.drill = Drill::Capsulorhexis;
  base.seed = 3;
  const std::filesystem::path file =
      std::filesystem::temp_directory_path() /
      ("phaco_test_recording_" + std::to_string(::getpid()) + ".json");
  rec.write(file, base, Hand::Right, ToolKind::Cystotome);
  const Scenario loaded = load_scenario(file);
  std::filesystem::remove(file);
  const HandTrack* h = loaded.find_hand(Hand::Right);
  ASSERT_NE(h, nullptr);
  EXPECT_EQ(h->tool, ToolKind::Cystotome);
  ASSERT_EQ(h->track.size(), rec.size());
  for (std::size_t i = 0; i < rec.size(); ++i) EXPECT_EQ(h->track[i], rec.samples()[i]) << i;
  EXPECT_GE(loaded.duration_s, h->track.back().t);

  ReplayDevice replay(*h);
  const int64_t start = 7 * kSecond;
  replay.start(start);
  DeviceSample s;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const DeviceSample& orig = stream[2 * i];
    const int64_t at = start + (orig.t_ns - rec.origin_ns());
    for (const int64_t now : {at, at + 100'000}) {  // at the sample, and held 0.1 ms later
      ASSERT_TRUE(replay.read(now, s)) << i;
      EXPECT_EQ(s.seq, i + 1);
      EXPECT_EQ(s.t_ns, at);
      EXPECT_EQ(s.pos_mm, orig.pos_mm) << i;  // positions exactly as the device gave them
      EXPECT_EQ(s.quat.coeffs(), rec.samples()[i].quat.coeffs()) << i;
      EXPECT_NEAR(s.quat.angularDistance(orig.quat), 0.0, 1e-7);
      EXPECT_EQ(s.grip, orig.grip);
      EXPECT_EQ(s.pedal, orig.pedal);
    }
    if (i + 1 < rec.size()) {
      EXPECT_EQ(replay.health(at), DeviceHealth::Ok);
    }
  }
  const int64_t end = start + (stream.back().t_ns - rec.origin_ns());
  EXPECT_EQ(replay.health(end), DeviceHealth::Ok);
  EXPECT_EQ(replay.health(end + 1), DeviceHealth::Ended);
  ASSERT_TRUE(replay.read(end + kSecond, s));  // held after the end
  EXPECT_EQ(s.seq, rec.size());
  // Time going backwards (a restart) finds the right sample again.
  ASSERT_TRUE(replay.read(start, s));
  EXPECT_EQ(s.seq, 1u);
}

TEST(DeviceRecorder, DropsAndCountsBeyondCapacity) {
  const std::vector<DeviceSample> stream = device_stream(10);
  DeviceRecorder rec(4);
  int kept = 0;
  for (const DeviceSample& s : stream) kept += rec.record(s) ? 1 : 0;
  EXPECT_EQ(kept, 4);
  EXPECT_EQ(rec.size(), 4u);
  EXPECT_EQ(rec.dropped(), 6u);
  DeviceSample bad = stream[0];
  bad.seq = 1;
  bad.t_ns = stream.back().t_ns + 1;
  bad.pos_mm.x() = std::nan("");
  EXPECT_FALSE(rec.record(bad));
  EXPECT_EQ(rec.rejected(), 1u);
  DeviceRecorder empty(4);
  EXPECT_THROW(empty.track(Hand::Left, ToolKind::Forceps), InputError);
}

}  // namespace
}  // namespace phaco
